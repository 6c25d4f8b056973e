#pragma once
// Latent states: states of a model that no channel of a record shows, neither as a column nor
// through a kinematic equation or a derivative column (docs/latent-states.md). Where they enter
// the equations linearly (an unmeasured mass on linear springs and dampers, an input filter, an
// extra pole), the algebra eliminates them: the equations that hold them are combined, with
// polynomials in the time derivative d/dt, into equations in the channels the record shows, whose
// coefficients are functions of the model's parameters.
//
// Example: an oscillator driven through a first-order filter, with only y and x measured,
//   y' = v;  v' = -c*v - k*y - eps*y^3 + g*z;  z' = -a*z + b*x
// gives, with the latent z eliminated,
//   y''' = -(a + c)*y'' - (k + a*c)*y' - a*k*y - eps*(y^3)' - a*eps*y^3 + b*g*x
// whose six coefficients determine a, c, k, eps and the product b*g, but not b and g apart.

#include <ginac/ginac.h>

#include <map>
#include <string>
#include <vector>

#include "momentid/model.hpp"

namespace momentid {

// coefficient * d^order/dt^order of the monomial (over Model::variables(): measured states,
// inputs, functions; all zeros is the constant 1).
struct EliminatedTerm {
  GiNaC::ex coefficient;  // exact, in the model's parameters that are not fixed
  int order = 0;
  Monomial monomial;
};

// The terms of one equation free of the latent states, whose sum is zero. The first term is the
// leading one (the highest derivative of a measured state), with coefficient 1.
struct EliminatedEquation {
  int equation = 0;          // the equation of a measured state it stands for (an index)
  std::vector<int> sources;  // the model's equations it combines, that one among them
  std::vector<EliminatedTerm> terms;
};

// What the elimination gives and what the eliminated equations can determine.
struct Elimination {
  std::vector<int> latent;  // the latent states (indices into Model::states()); empty: none
  std::vector<EliminatedEquation> equations;
  // The distinct coefficients that hold a parameter, as functions of the parameters, with the
  // sign they have on the right side of the equation (up to sign when two terms share one):
  // what the data can estimate.
  std::vector<GiNaC::ex> coefficients;
  std::vector<int> parameters;  // the parameters not fixed (indices into Model::parameters())
  std::map<int, GiNaC::numeric> fixed;  // the others, by index: declared fixed, or given
  // The rank of the coefficients' Jacobian in those parameters, at a generic point: as many
  // combinations of the parameters as the eliminated equations determine.
  int rank = 0;
  // Groups of parameters that the coefficients leave undetermined: each moves in a direction the
  // coefficients do not see (a scale that only a product shows, a parameter no coefficient
  // holds), with how many of the group must be fixed (`param g = 1 fixed`).
  struct Undetermined {
    std::vector<int> parameters;
    int to_fix = 0;
  };
  std::vector<Undetermined> undetermined;
};

// The latent states of `model` for a record with the channels that `measured` flags (per channel
// or per variable, as measured_variables takes them), eliminated. An empty `latent` when every
// state is shown. Throws ModelError, at the equation, when a latent state enters nonlinearly
// (times another state, in a power or in abs/sign), when it does not reach the equations of the
// measured states, or when the equations that hold the latent states' derivatives do not
// determine them.
// `fixed` gives parameters known values by name (IdentifyOptions::fixed), as `fixed` in the
// model does.
Elimination eliminate_latent(const Model& model, const std::vector<bool>& measured,
                             const std::map<std::string, double>& fixed = {});

// The model whose parameters are the elimination's coefficients (`coefficients`, in order, each
// named as format_text writes it) and whose equations are the eliminated ones (labelled
// "without z"), beside the model's equations that hold no latent state. Its terms take time
// derivatives of whole monomials (Term::order), which only the lagged equations read: it is for
// derive_lagged and the lagged pass, not for simulation or the zero-lag equations. A
// coefficient's nominal value is its value at the parameters' nominal values, where they have
// them. Throws ModelError when an equation without latent states holds a parameter.
Model coefficient_model(const Model& model, const Elimination& elimination);

// A coefficient of `elimination` as format_text writes it: "c*a + k".
std::string coefficient_text(const Model& model, const GiNaC::ex& coefficient);

// The elimination as text: the latent states, the eliminated equations with the measured
// highest derivative on the left, the coefficients and what they leave undetermined.
std::string format_text(const Model& model, const Elimination& elimination);
std::string format_json(const Model& model, const Elimination& elimination);

// "(y^3)'", "y''", "x": a monomial over the model's variables, differentiated `order` times.
std::string derivative_text(const Model& model, const Monomial& monomial, int order);

}  // namespace momentid
