#pragma once
// The identified model as a vector field, for its linearisation (engineering.cpp) and its free
// response (runaway.cpp): the right-hand side at the estimates, its Jacobian by central
// differences and its equilibrium.

#include <Eigen/Dense>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "momentid/identify.hpp"
#include "momentid/simulate.hpp"

namespace momentid {

// The right-hand side f(y) at the estimates `theta`, the inputs at `u`.
class RightHandSide {
 public:
  RightHandSide(const Model& model, const std::vector<double>& theta, std::vector<double> u)
      : f_(model, numbers(theta)), u_(std::move(u)), n_(f_.states()) {}
  Eigen::VectorXd operator()(const Eigen::VectorXd& y) const { return at(y, u_); }
  // f at y with the inputs at `u` instead.
  Eigen::VectorXd at(const Eigen::VectorXd& y, const std::vector<double>& u) const {
    Eigen::VectorXd out(n_);
    if (!f_.derivative(y.data(), u.data(), out.data())) out.setConstant(NAN);
    return out;
  }
  int states() const { return n_; }

 private:
  static std::vector<GiNaC::numeric> numbers(const std::vector<double>& theta) {
    std::vector<GiNaC::numeric> out;
    for (double v : theta) out.emplace_back(v);
    return out;
  }
  CompiledModel f_;
  std::vector<double> u_;
  int n_;
};

// The Jacobian of f at y by central differences; `kink` names the first state in which f is not
// differentiable at y (an abs or sign switching there), or is -1: its one-sided derivatives
// differ (a kink), or its difference quotient halves as the step doubles (a jump).
Eigen::MatrixXd jacobian(const RightHandSide& f, const Eigen::VectorXd& y, int& kink);

// The equilibrium f(y) = 0 near the origin (Newton from it), or nullopt when none is found.
std::optional<Eigen::VectorXd> equilibrium(const RightHandSide& f);

// The record's standard deviation of the channel `name`, 0 when it has none.
double spread_of(const IdentifyResult& r, const std::string& name);

// The estimates of every parameter (fixed ones at their values), and the inputs' means.
std::vector<double> estimates_of(const IdentifyResult& r);
std::vector<double> input_means(const IdentifyResult& r);

}  // namespace momentid
