#pragma once
// Shared by the files of the lagged equations: how a record shows each variable of a model and
// reads each term as a lag function (LagDeriver, lag_deriver.cpp), the default instruments
// (lag_options.cpp), and the pieces of text their messages use (lagged_format.cpp).

#include <ginac/ginac.h>

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "momentid/lagged.hpp"
#include "momentid/model.hpp"

namespace momentid {

// How the data show a model variable: `scale` times the `order`-th time derivative of the
// measured variable `base`.
struct Observation {
  int base = -1;  // -1: the data cannot show it
  int order = 0;
  GiNaC::numeric scale = 1;
  std::string reason;  // why not, when base is -1
};

// `flags` per channel (states, then inputs) or per variable, as per variable: a function is
// measured when its argument's channels are, for the pass computes it from them.
std::vector<bool> measured_variables(const Model& model, std::vector<bool> flags);

// How data with the variables flagged in `measured` (as for measured_variables) show each
// variable of `model`: measured; a derivative of a measured variable through kinematic equations
// (v = y' when y' = v) or a derivative column's state; or, where no derivative reads a state, the
// integral of a derivative column (negative orders). Then each term of an equation as a lag
// function with an instrument.
class LagDeriver {
 public:
  LagDeriver(const Model& model, const std::vector<bool>& measured);

  const Observation& observation(int v) const { return observed_[v]; }

  // Whether a term of `eq` reads a derivative from its column, and the same derivative is also
  // the derivative in s of its state's reading.
  bool read_both_ways(const Equation& eq) const;

  // The lag functions of one term, weighted, for instrument ψ: throws ModelError when the term
  // is not a time derivative of measured channels.
  // `columns`: read a derivative from the column that measures it, where there is one.
  std::pair<LagFunction, GiNaC::numeric> lag_function(const Equation& eq, const Term& t,
                                                      const Monomial& instrument,
                                                      bool columns) const;

  // "v = y'" for a state the data show as a derivative, "y'' = a" for one they show through
  // its derivative.
  std::string definition(int v) const;

  // The states the data show only as integrals of a derivative column, but for those that are
  // another's derivative (v when y' = v): `--integrate` with these forms every state, and no
  // equation then needs an integral.
  std::vector<std::string> integral_state_names() const;
  // Their names joined by commas, `except` left out.
  std::string integral_states(const std::string& except = "") const;

 private:
  // Throws the ModelError for term `t` of `eq`, which is not a time derivative of measured
  // channels: it names the column the term needs, for a state the data show only through a
  // derivative column (a FormStatesError) or for an unmeasured variable.
  [[noreturn]] void reject_term(const Equation& eq, const Term& t) const;

  // "state " or "input ", for a message about a missing column.
  std::string channel_kind(std::size_t v) const;

  // Fills observed_[v]; `depth` guards against kinematic cycles.
  const Observation& observe(int v, int depth);

  // Reads the states that observe() left unread through a column of their derivative (v' = a)
  // or a kinematic equation from a state so read (y' = v): as integrals of a measured channel,
  // negative orders. Only where no derivative reads them, so that the readings above stand.
  void integrate();

  // How the data show the derivative of `state`, which they show.
  Observation derivative_of(int state) const;

  // A kinematic equation v' = ratio*w with w read: v as the integral of w's reading.
  std::optional<Observation> integral_of(int v) const;

  const Model& model_;
  std::vector<bool> measured_;
  int variables_, states_;
  std::vector<Observation> observed_;
};

// Whether an equation has a term with a parameter: only those give lagged equations.
bool has_parameter(const Equation& eq);

// The instruments when LagOptions leaves them open (LagOptions::instruments): for each measured
// state, itself and its highest power in the functions the equations' terms are read as, with
// its square and cube where the model's terms call for them; each measured input whose term has
// a parameter; a derivative column that stands for its state.
std::vector<Monomial> default_instruments(const Model& model, const std::vector<bool>& measured,
                                          const LagDeriver& deriver);

// A number as GiNaC prints it: 3, -1/2.
std::string number_text(const GiNaC::numeric& q);
// The marks of the order-th derivative: ' '' ''' for orders up to 3, ^(k) above.
std::string primes(int order);
// A term as written in a model: 2*c*y^3, x, v', ...
std::string term_text(const Model& model, const Term& t);

}  // namespace momentid
