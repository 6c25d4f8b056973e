// Latent states eliminated (momentid/latent.hpp).
//
// With the latent states z and D = d/dt, each equation reads M_e(D) z + R_e = 0, M_e's entries
// of degree at most 1 in D, R_e free of z. The equations that hold the latent derivatives, L,
// give M_L(D) z = -R_L, so z = -adj(M_L) R_L / det(M_L); any other equation o that holds z
// becomes det(M_L) R_o - M_o adj(M_L) R_L = 0, a polynomial in D applied to terms in the shown
// channels: d^k/dt^k of a monomial is read as the k-th lag derivative of its cross-moments.

#include "momentid/latent.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "derive/lag_deriver.hpp"
#include "momentid/algebra_lock.hpp"

namespace momentid {
namespace {

using GiNaC::ex;
using Signal = std::pair<int, Monomial>;  // (order, monomial): d^order/dt^order monomial
using Signals = std::map<Signal, ex>;     // the coefficient of each signal
using SymbolIndex = std::map<ex, int, GiNaC::ex_is_less>;

// A polynomial in the parameters: its terms by their exponents over the parameters in declaration
// order (highest first), each factor in that order, so that the text does not depend on how
// GiNaC happens to order a sum.
std::string polynomial_text(const Model& model, const ex& polynomial) {
  const std::size_t count = model.parameters().size();
  std::vector<std::pair<std::vector<int>, GiNaC::numeric>> terms;
  const auto add_term = [&](const ex& term) {
    std::vector<int> exponents(count, 0);
    GiNaC::numeric number = 1;
    const auto add_factor = [&](const ex& f) {
      if (GiNaC::is_a<GiNaC::numeric>(f)) {
        number *= GiNaC::ex_to<GiNaC::numeric>(f);
        return;
      }
      const bool power = GiNaC::is_a<GiNaC::power>(f);
      const ex base = power ? f.op(0) : f;
      for (std::size_t p = 0; p < count; ++p) {
        if (base.is_equal(model.parameter_symbol(static_cast<int>(p)))) {
          exponents[p] += power ? GiNaC::ex_to<GiNaC::numeric>(f.op(1)).to_int() : 1;
        }
      }
    };
    if (GiNaC::is_a<GiNaC::mul>(term)) {
      for (std::size_t i = 0; i < term.nops(); ++i) add_factor(term.op(i));
    } else {
      add_factor(term);
    }
    terms.emplace_back(std::move(exponents), number);
  };
  const ex expanded = polynomial.expand();
  if (GiNaC::is_a<GiNaC::add>(expanded)) {
    for (std::size_t i = 0; i < expanded.nops(); ++i) add_term(expanded.op(i));
  } else {
    add_term(expanded);
  }
  std::sort(terms.begin(), terms.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  std::string out;
  for (const auto& [exponents, number] : terms) {
    std::vector<std::string> factors;
    for (std::size_t p = 0; p < count; ++p) {
      if (exponents[p] == 0) continue;
      factors.push_back(model.parameters()[p].name +
                        (exponents[p] == 1 ? "" : "^" + std::to_string(exponents[p])));
    }
    const GiNaC::numeric size = GiNaC::abs(number);
    if (size != 1 || factors.empty()) factors.insert(factors.begin(), number_text(size));
    std::string term;
    for (std::size_t i = 0; i < factors.size(); ++i) term += (i ? "*" : "") + factors[i];
    out += number.is_negative() ? (out.empty() ? "-" : " - ") : (out.empty() ? "" : " + ");
    out += term;
  }
  return out;
}

}  // namespace

std::string coefficient_text(const Model& model, const ex& coefficient) {
  const ex fraction = coefficient.normal().numer_denom();
  const ex numerator = fraction.op(0), denominator = fraction.op(1);
  if (denominator.is_equal(1)) return polynomial_text(model, numerator);
  const auto grouped = [&](const ex& p, bool product) {
    const std::string t = polynomial_text(model, p);
    const bool sum = t.find(' ') != std::string::npos;
    return sum || (product && t.find('*') != std::string::npos) ? "(" + t + ")" : t;
  };
  return grouped(numerator, false) + "/" + grouped(denominator, true);
}

namespace {

// The model's equations, taken apart around its latent states.
class Eliminator {
 public:
  Eliminator(const Model& model, const std::vector<int>& latent,
             const std::map<std::string, double>& given)
      : model_(model), latent_(latent), variables_(model.variables().size()) {
    for (std::size_t v = 0; v < variables_; ++v) variable_[model.variable_symbol(v)] = int(v);
    for (std::size_t s = 0; s < model.states().size(); ++s) {
      derivative_[model.derivative_symbol(int(s))] = int(s);
    }
    for (std::size_t p = 0; p < model.parameters().size(); ++p) {
      const Declaration& d = model.parameters()[p];
      if (const auto it = given.find(d.name); it != given.end()) {
        known_[int(p)] = GiNaC::numeric(it->second);
        fixed_[model.parameter_symbol(int(p))] = known_[int(p)];
      } else if (d.fixed && d.value) {
        known_[int(p)] = *d.value;
        fixed_[model.parameter_symbol(int(p))] = *d.value;
      } else {
        parameter_[model.parameter_symbol(int(p))] = int(p);
      }
    }
  }

  Elimination run(const std::vector<bool>& shown_functions);

 private:
  // ModelError at equation e.
  [[noreturn]] void fail(std::size_t e, const std::string& why) const {
    const Equation& eq = model_.equations()[e];
    throw ModelError(eq.where, "equation " + eq.name() + " " + why);
  }
  bool latent(int state) const {
    return std::find(latent_.begin(), latent_.end(), state) != latent_.end();
  }
  // Whether `e` holds a state, input, derivative or function.
  bool holds_variable(const ex& e) const {
    for (const auto& [symbol, v] : variable_) {
      if (e.has(symbol)) return true;
    }
    for (const auto& [symbol, s] : derivative_) {
      if (e.has(symbol)) return true;
    }
    return false;
  }
  // Adds `factor` * d^order/dt^order of each term of `r` to `out`.
  void apply(const ex& factor, int order, const ex& r, std::size_t e, Signals& out) const;
  // A linear state's signal in the lowest shown state of its kinematic chain (v'' as y''').
  Signal lowest(Signal signal, ex& coefficient) const;

  const Model& model_;
  std::vector<int> latent_;
  std::size_t variables_;
  SymbolIndex variable_, derivative_, parameter_;
  GiNaC::exmap fixed_;
  std::map<int, GiNaC::numeric> known_;
};

void Eliminator::apply(const ex& factor, int order, const ex& r, std::size_t e,
                       Signals& out) const {
  const ex expanded = r.expand();
  const auto add_term = [&](const ex& term) {
    ex coefficient = factor;
    Monomial monomial(variables_, 0);
    int derivative = -1;
    const auto add_factor = [&](const ex& f) {
      ex base = f;
      int power = 1;
      if (GiNaC::is_a<GiNaC::power>(f) && GiNaC::is_a<GiNaC::numeric>(f.op(1)) &&
          GiNaC::ex_to<GiNaC::numeric>(f.op(1)).is_pos_integer()) {
        base = f.op(0);
        power = GiNaC::ex_to<GiNaC::numeric>(f.op(1)).to_int();
      }
      if (const auto v = variable_.find(base); v != variable_.end()) {
        monomial[static_cast<std::size_t>(v->second)] += power;
      } else if (const auto s = derivative_.find(base); s != derivative_.end()) {
        if (power != 1 || derivative >= 0) {
          fail(e,
               "holds a power or a product of derivatives, which the elimination cannot "
               "differentiate");
        }
        derivative = s->second;
      } else {
        coefficient *= f;  // a number or a parameter
      }
    };
    if (GiNaC::is_a<GiNaC::mul>(term)) {
      for (std::size_t i = 0; i < term.nops(); ++i) add_factor(term.op(i));
    } else {
      add_factor(term);
    }
    if (derivative >= 0) {
      if (monomial.degree() != 0) {
        fail(e, "holds a derivative times a state, which the elimination cannot differentiate");
      }
      monomial[static_cast<std::size_t>(derivative)] = 1;
    }
    Signal signal = lowest({order + (derivative >= 0 ? 1 : 0), monomial}, coefficient);
    auto [at, added] = out.try_emplace(std::move(signal), coefficient);
    if (!added) at->second += coefficient;
  };
  if (GiNaC::is_a<GiNaC::add>(expanded)) {
    for (std::size_t i = 0; i < expanded.nops(); ++i) add_term(expanded.op(i));
  } else if (!expanded.is_zero()) {
    add_term(expanded);
  }
}

Signal Eliminator::lowest(Signal signal, ex& coefficient) const {
  auto& [order, monomial] = signal;
  if (monomial.degree() != 1) return signal;
  const auto w =
      static_cast<int>(std::find(monomial.begin(), monomial.end(), 1) - monomial.begin());
  if (w >= static_cast<int>(model_.states().size())) return signal;
  // s' = ratio*w: w^(k) = s^(k+1) / ratio.
  int state = w;
  for (std::size_t step = 0; step < model_.states().size(); ++step) {
    const int s = model_.integral_of(state);
    if (s < 0 || s == state || latent(s)) break;
    coefficient /= model_.kinematic(s)->ratio;
    monomial[static_cast<std::size_t>(state)] = 0;
    monomial[static_cast<std::size_t>(s)] = 1;
    ++order;
    state = s;
  }
  return signal;
}

// The rank of the coefficients' Jacobian in the free parameters, at a generic point, and the
// groups of parameters in its null space.
void identifiability(const Model& model, Elimination& out) {
  const auto n = static_cast<Eigen::Index>(out.parameters.size());
  const auto m = static_cast<Eigen::Index>(out.coefficients.size());
  GiNaC::exmap point;
  for (Eigen::Index k = 0; k < n; ++k) {
    // Irrational values: no coincidence of the parameters makes a coefficient vanish there.
    const double value = std::sqrt(2.0 + 1.7 * static_cast<double>(k));
    point[model.parameter_symbol(out.parameters[static_cast<std::size_t>(k)])] = value;
  }
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(std::max<Eigen::Index>(m, 1), n);
  for (Eigen::Index i = 0; i < m; ++i) {
    for (Eigen::Index k = 0; k < n; ++k) {
      const GiNaC::symbol& p = model.parameter_symbol(out.parameters[static_cast<std::size_t>(k)]);
      const ex d = out.coefficients[static_cast<std::size_t>(i)].diff(p).subs(point).evalf();
      if (GiNaC::is_a<GiNaC::numeric>(d))
        jacobian(i, k) = GiNaC::ex_to<GiNaC::numeric>(d).to_double();
    }
  }
  if (n == 0) return;
  // Each column scaled to unit length, so that the rank does not depend on the parameters' units.
  for (Eigen::Index k = 0; k < n; ++k) {
    const double norm = jacobian.col(k).norm();
    if (norm > 0) jacobian.col(k) /= norm;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(jacobian, Eigen::ComputeFullV);
  const Eigen::VectorXd& s = svd.singularValues();
  constexpr double kTolerance = 1e-9;
  out.rank = 0;
  for (Eigen::Index i = 0; i < s.size(); ++i) out.rank += s(i) > kTolerance * std::max(1.0, s(0));
  const Eigen::Index nullity = n - out.rank;
  if (nullity == 0) return;
  // The projector on the null space is the same for any basis of it: parameters it joins
  // belong to one group, and the group holds as many null directions as its block's trace.
  const Eigen::MatrixXd basis = svd.matrixV().rightCols(nullity);
  const Eigen::MatrixXd projector = basis * basis.transpose();
  std::vector<int> group(static_cast<std::size_t>(n), -1);
  for (Eigen::Index k = 0; k < n; ++k) {
    if (projector(k, k) < 1e-8 || group[static_cast<std::size_t>(k)] >= 0) continue;
    Elimination::Undetermined u;
    std::vector<Eigen::Index> stack{k};
    group[static_cast<std::size_t>(k)] = static_cast<int>(out.undetermined.size());
    double trace = 0;
    while (!stack.empty()) {
      const Eigen::Index a = stack.back();
      stack.pop_back();
      u.parameters.push_back(out.parameters[static_cast<std::size_t>(a)]);
      trace += projector(a, a);
      for (Eigen::Index b = 0; b < n; ++b) {
        if (group[static_cast<std::size_t>(b)] < 0 && std::abs(projector(a, b)) > 1e-8) {
          group[static_cast<std::size_t>(b)] = group[static_cast<std::size_t>(k)];
          stack.push_back(b);
        }
      }
    }
    std::sort(u.parameters.begin(), u.parameters.end());
    u.to_fix = static_cast<int>(std::lround(trace));
    out.undetermined.push_back(std::move(u));
  }
}

Elimination Eliminator::run(const std::vector<bool>& shown_functions) {
  Elimination out;
  out.latent = latent_;
  out.fixed = known_;
  const std::size_t count = latent_.size();
  const std::vector<Equation>& equations = model_.equations();
  std::vector<std::vector<ex>> dz(equations.size()), z(equations.size());
  std::vector<ex> rest(equations.size());
  GiNaC::exmap zero;
  for (int j : latent_) {
    zero[model_.state_symbol(j)] = 0;
    zero[model_.derivative_symbol(j)] = 0;
  }
  for (std::size_t e = 0; e < equations.size(); ++e) {
    const ex full = (equations[e].lhs - equations[e].rhs).subs(fixed_).expand();
    for (std::size_t f = 0; f < shown_functions.size(); ++f) {
      if (!shown_functions[f] && full.has(model_.function_symbol(int(f)))) {
        fail(e, "holds " + model_.functions()[f].name +
                    " of a latent state: a latent state can be eliminated only where it enters "
                    "linearly");
      }
    }
    for (int j : latent_) {
      const ex& zs = model_.state_symbol(j);
      const ex& zd = model_.derivative_symbol(j);
      const ex a = full.coeff(zd, 1), b = full.coeff(zs, 1);
      if (full.degree(zs) > 1 || full.degree(zd) > 1 || holds_variable(a) || holds_variable(b)) {
        fail(e, "holds the latent state " + model_.states()[static_cast<std::size_t>(j)].name +
                    " in a product or a power: a latent state can be eliminated only where it "
                    "enters linearly");
      }
      dz[e].push_back(a);
      z[e].push_back(b);
    }
    rest[e] = full.subs(zero);
  }
  const auto holds = [&](const std::vector<ex>& row) {
    return std::any_of(row.begin(), row.end(), [](const ex& c) { return !c.is_zero(); });
  };
  std::vector<std::size_t> defining, joined;
  for (std::size_t e = 0; e < equations.size(); ++e) {
    if (holds(dz[e])) {
      defining.push_back(e);
    } else if (holds(z[e])) {
      joined.push_back(e);
    }
  }
  std::string names;
  for (int j : latent_) {
    names += (names.empty() ? "" : ", ") + model_.states()[static_cast<std::size_t>(j)].name;
  }
  if (defining.size() != count) {
    throw ModelError(model_.equations().front().where,
                     std::to_string(defining.size()) + " equations hold the derivatives of the " +
                         std::to_string(count) + " latent states " + names +
                         ": expected one equation for each");
  }
  if (joined.empty()) {
    throw ModelError(model_.equations().front().where,
                     "the latent states " + names +
                         " enter no equation of the measured states: the record holds nothing "
                         "of them (remove them from the model)");
  }
  const GiNaC::symbol d("D");
  GiNaC::matrix m(static_cast<unsigned>(count), static_cast<unsigned>(count));
  for (std::size_t l = 0; l < count; ++l) {
    for (std::size_t j = 0; j < count; ++j) {
      m(static_cast<unsigned>(l), static_cast<unsigned>(j)) =
          dz[defining[l]][j] * d + z[defining[l]][j];
    }
  }
  const ex determinant = m.determinant().expand();
  if (determinant.is_zero()) {
    fail(defining.front(), "and the others that hold the latent states' derivatives (" + names +
                               ") do not determine them");
  }
  // adj(M)_jl = (-1)^(j+l) times the minor of M without row l and column j.
  const auto adjugate = [&](std::size_t j, std::size_t l) -> ex {
    if (count == 1) return 1;
    GiNaC::matrix minor(static_cast<unsigned>(count - 1), static_cast<unsigned>(count - 1));
    for (std::size_t r = 0, rr = 0; r < count; ++r) {
      if (r == l) continue;
      for (std::size_t c = 0, cc = 0; c < count; ++c) {
        if (c == j) continue;
        minor(static_cast<unsigned>(rr), static_cast<unsigned>(cc++)) =
            m(static_cast<unsigned>(r), static_cast<unsigned>(c));
      }
      ++rr;
    }
    return ((j + l) % 2 ? -1 : 1) * minor.determinant();
  };
  const auto apply_operator = [&](const ex& op, const ex& r, std::size_t e, Signals& signals) {
    const ex p = op.expand();
    for (int k = 0; k <= p.degree(d); ++k) {
      const ex factor = p.coeff(d, k);
      if (!factor.is_zero()) apply(factor, k, r, e, signals);
    }
  };
  for (std::size_t o : joined) {
    Signals signals;
    apply_operator(determinant, rest[o], o, signals);
    for (std::size_t l = 0; l < count; ++l) {
      ex weight = 0;
      for (std::size_t j = 0; j < count; ++j) weight += z[o][j] * adjugate(j, l);
      apply_operator(-weight, rest[defining[l]], defining[l], signals);
    }
    EliminatedEquation eq;
    eq.equation = static_cast<int>(o);
    eq.sources.push_back(static_cast<int>(o));
    for (std::size_t e : defining) eq.sources.push_back(static_cast<int>(e));
    std::sort(eq.sources.begin(), eq.sources.end());
    for (auto& [signal, coefficient] : signals) {
      coefficient = coefficient.expand().normal();
      if (!coefficient.is_zero()) eq.terms.push_back({coefficient, signal.first, signal.second});
    }
    // The highest derivative of a state leads; its coefficient is divided out.
    // Linear terms in a state first, then the other terms in states, then the inputs'.
    const auto rank = [&](const EliminatedTerm& t) {
      const auto states = static_cast<long>(model_.states().size());
      const bool in_states = std::any_of(t.monomial.begin(), t.monomial.begin() + states,
                                         [](int e) { return e != 0; });
      return std::pair{in_states ? (t.monomial.degree() == 1 ? 2 : 1) : 0, t.order};
    };
    std::stable_sort(
        eq.terms.begin(), eq.terms.end(),
        [&](const EliminatedTerm& a, const EliminatedTerm& b) { return rank(a) > rank(b); });
    if (eq.terms.empty()) fail(o, "is lost with the latent states: it holds nothing else");
    const ex lead = eq.terms.front().coefficient;
    for (EliminatedTerm& t : eq.terms) t.coefficient = (t.coefficient / lead).normal();
    out.equations.push_back(std::move(eq));
  }
  for (const auto& [symbol, p] : parameter_) out.parameters.push_back(p);
  std::sort(out.parameters.begin(), out.parameters.end());
  for (const EliminatedEquation& eq : out.equations) {
    for (std::size_t i = 1; i < eq.terms.size(); ++i) {
      const ex& c = eq.terms[i].coefficient;
      bool free = false;
      for (const auto& [symbol, p] : parameter_) free |= c.has(symbol);
      const bool known = std::any_of(
          out.coefficients.begin(), out.coefficients.end(),
          [&](const ex& k) { return (k - c).normal().is_zero() || (k + c).normal().is_zero(); });
      if (free && !known) out.coefficients.push_back((-c).normal());
    }
  }
  // An equation that holds no latent state keeps its parameters as they are.
  for (std::size_t e = 0; e < equations.size(); ++e) {
    if (std::find(defining.begin(), defining.end(), e) != defining.end() ||
        std::find(joined.begin(), joined.end(), e) != joined.end()) {
      continue;
    }
    for (const Term& t : equations[e].terms) {
      if (t.parameter < 0 || fixed_.count(model_.parameter_symbol(t.parameter))) continue;
      const ex p = model_.parameter_symbol(t.parameter);
      if (std::none_of(out.coefficients.begin(), out.coefficients.end(),
                       [&](const ex& k) { return k.is_equal(p); })) {
        out.coefficients.push_back(p);
      }
    }
  }
  identifiability(model_, out);
  return out;
}

std::string names_of(const Model& model, const std::vector<int>& parameters) {
  std::string out;
  for (std::size_t i = 0; i < parameters.size(); ++i) {
    out += (i == 0                       ? ""
            : i + 1 == parameters.size() ? " and "
                                         : ", ") +
           model.parameters()[static_cast<std::size_t>(parameters[i])].name;
  }
  return out;
}

// " + c*s", " - c*s" for a term moved to the right side (its sign turned).
std::string right_term(const Model& model, const EliminatedTerm& t) {
  const ex c = (-t.coefficient).normal();
  const std::string signal =
      t.monomial.degree() == 0 && t.order == 0 ? "" : derivative_text(model, t.monomial, t.order);
  const auto count_minus = [](const std::string& s) { return std::count(s.begin(), s.end(), '-'); };
  std::string sign = " + ", body = coefficient_text(model, c);
  const ex fraction = c.numer_denom();
  if (fraction.op(1).is_equal(1) && body.find(' ') != std::string::npos) {
    const std::string turned = coefficient_text(model, (-c).normal());
    if (count_minus(turned) < count_minus(body)) {
      sign = " - ";
      body = turned;
    }
    body = "(" + body + ")";
  } else if (body.front() == '-' && body.find(' ') == std::string::npos) {
    sign = " - ";
    body.erase(0, 1);
  } else if (body.find(' ') != std::string::npos) {
    const std::string turned = coefficient_text(model, (-c).normal());
    if (count_minus(turned) < count_minus(body)) {
      sign = " - ";
      body = turned;
    }
  }
  if (signal.empty()) return sign + body;
  return sign + (body == "1" ? "" : body + "*") + signal;
}

}  // namespace

std::string derivative_text(const Model& model, const Monomial& monomial, int order) {
  const std::string base = format_monomial(model, monomial);
  if (order == 0) return base;
  const bool single = monomial.degree() == 1 || std::count_if(monomial.begin(), monomial.end(),
                                                              [](int e) { return e != 0; }) == 0;
  return (single ? base : "(" + base + ")") + primes(order);
}

Elimination eliminate_latent(const Model& model, const std::vector<bool>& measured,
                             const std::map<std::string, double>& fixed) {
  const AlgebraLock lock;
  const LagDeriver deriver(model, measured);
  std::vector<int> latent;
  for (std::size_t s = 0; s < model.states().size(); ++s) {
    if (deriver.observation(static_cast<int>(s)).base < 0) latent.push_back(static_cast<int>(s));
  }
  if (latent.empty()) return {};
  std::vector<bool> shown_functions;
  for (std::size_t f = 0; f < model.functions().size(); ++f) {
    const int v = model.variable_index(model.functions()[f].name);
    shown_functions.push_back(v >= 0 && deriver.observation(v).base >= 0);
  }
  return Eliminator(model, latent, fixed).run(shown_functions);
}

Model coefficient_model(const Model& model, const Elimination& elimination) {
  const AlgebraLock lock;
  Model out = model;
  GiNaC::exmap nominal;
  for (std::size_t p = 0; p < model.parameters().size(); ++p) {
    if (const auto& value = model.parameters()[p].value) {
      nominal[model.parameter_symbol(static_cast<int>(p))] = *value;
    }
  }
  out.parameters_.clear();
  out.parameter_symbols_.clear();
  for (const ex& c : elimination.coefficients) {
    Declaration d{.name = coefficient_text(model, c), .kind = SymbolKind::kParameter};
    d.where = model.parameters().empty() ? SourceLocation{} : model.parameters().front().where;
    if (const ex value = c.subs(nominal).normal(); GiNaC::is_a<GiNaC::numeric>(value)) {
      d.value = GiNaC::ex_to<GiNaC::numeric>(value);
    }
    out.parameter_symbols_.emplace_back(d.name);
    out.parameters_.push_back(std::move(d));
  }
  // The index of the coefficient that is +c or -c, and the sign.
  const auto coefficient_of = [&](const ex& c) -> std::pair<int, int> {
    for (std::size_t j = 0; j < elimination.coefficients.size(); ++j) {
      const ex& k = elimination.coefficients[j];
      if ((k - c).normal().is_zero()) return {static_cast<int>(j), 1};
      if ((k + c).normal().is_zero()) return {static_cast<int>(j), -1};
    }
    return {-1, 0};
  };
  std::string without;
  for (int j : elimination.latent) {
    without +=
        (without.empty() ? "without " : ", ") + model.states()[static_cast<std::size_t>(j)].name;
  }
  std::vector<Equation> equations;
  std::vector<bool> source(model.equations().size(), false);
  for (const EliminatedEquation& eq : elimination.equations) {
    for (int e : eq.sources) source[static_cast<std::size_t>(e)] = true;
  }
  for (std::size_t e = 0; e < model.equations().size(); ++e) {
    if (source[e]) continue;
    Equation kept = model.equations()[e];
    for (Term& t : kept.terms) {
      if (t.parameter < 0) continue;
      const Declaration& d = model.parameters()[static_cast<std::size_t>(t.parameter)];
      if (const auto known = elimination.fixed.find(t.parameter);
          known != elimination.fixed.end()) {
        t.coefficient *= known->second;
        t.parameter = -1;
        continue;
      }
      const auto [j, sign] = coefficient_of(model.parameter_symbol(t.parameter));
      if (j < 0)
        throw ModelError(kept.where, "parameter " + d.name + " is lost in the elimination");
      t.parameter = j;
      t.coefficient *= sign;
    }
    equations.push_back(std::move(kept));
  }
  for (std::size_t i = 0; i < elimination.equations.size(); ++i) {
    const EliminatedEquation& eliminated = elimination.equations[i];
    Equation eq;
    eq.label =
        without + (elimination.equations.size() > 1 ? " (" + std::to_string(i + 1) + ")" : "");
    eq.where = model.equations()[static_cast<std::size_t>(eliminated.equation)].where;
    eq.lhs = 0;
    eq.rhs = 0;
    for (const EliminatedTerm& t : eliminated.terms) {
      Term term{.coefficient = 1,
                .parameter = -1,
                .monomial = t.monomial,
                .derivative = -1,
                .order = t.order};
      ex factor = 1;
      for (std::size_t v = 0; v < t.monomial.size(); ++v) {
        factor *= GiNaC::pow(model.variable_symbol(v), t.monomial[v]);
      }
      if (GiNaC::is_a<GiNaC::numeric>(t.coefficient)) {
        term.coefficient = GiNaC::ex_to<GiNaC::numeric>(t.coefficient);
        eq.lhs += t.coefficient * factor;
      } else {
        // The coefficients are the right side's: the term, on the left, is minus one of them.
        const auto [j, sign] = coefficient_of(-t.coefficient);
        if (j < 0) throw ModelError(eq.where, "a coefficient is lost in the elimination");
        term.parameter = j;
        term.coefficient = -sign;
        eq.lhs += -sign * out.parameter_symbols_[static_cast<std::size_t>(j)] * factor;
      }
      eq.terms.push_back(std::move(term));
    }
    equations.push_back(std::move(eq));
  }
  for (std::size_t e = 0; e < equations.size(); ++e) equations[e].number = static_cast<int>(e) + 1;
  out.equations_ = std::move(equations);
  out.multipliers_.clear();
  return out;
}

std::string format_text(const Model& model, const Elimination& elimination) {
  const AlgebraLock lock;
  std::string out = "latent states (no channel shows them; they enter linearly): ";
  std::vector<std::string> latent;
  for (int j : elimination.latent)
    latent.push_back(model.states()[static_cast<std::size_t>(j)].name);
  for (std::size_t i = 0; i < latent.size(); ++i) out += (i ? ", " : "") + latent[i];
  out += "\nthe equations without them:\n";
  for (const EliminatedEquation& eq : elimination.equations) {
    std::string from;
    for (std::size_t i = 0; i < eq.sources.size(); ++i) {
      from += (i == 0                       ? ""
               : i + 1 == eq.sources.size() ? " and "
                                            : ", ") +
              model.equations()[static_cast<std::size_t>(eq.sources[i])].name();
    }
    const EliminatedTerm& lead = eq.terms.front();
    std::string rhs;
    for (std::size_t i = 1; i < eq.terms.size(); ++i) rhs += right_term(model, eq.terms[i]);
    if (rhs.empty()) rhs = " + 0";
    out += "  " + derivative_text(model, lead.monomial, lead.order) + " =" +
           (rhs.substr(0, 3) == " - " ? " -" + rhs.substr(3) : rhs.substr(2)) + "   (equations " +
           from + ")\n";
  }
  const std::size_t free = elimination.parameters.size();
  out += "coefficients the data can estimate: " + std::to_string(elimination.coefficients.size()) +
         ", which determine " + std::to_string(elimination.rank) + " combinations of the " +
         std::to_string(free) + " parameters\n";
  for (const ex& c : elimination.coefficients) out += "  " + coefficient_text(model, c) + "\n";
  if (elimination.undetermined.empty()) {
    out += "every parameter is determined\n";
  }
  for (const Elimination::Undetermined& u : elimination.undetermined) {
    const std::string who = names_of(model, u.parameters);
    const std::string& first =
        model.parameters()[static_cast<std::size_t>(u.parameters.front())].name;
    out += "not determined: " + who +
           (u.parameters.size() == 1 ? " (no coefficient holds it: fix it"
                                     : " (the coefficients hold them only in combinations: fix " +
                                           std::to_string(u.to_fix) + " of them") +
           ", e.g. `param " + first + " = 1 fixed`)\n";
  }
  return out;
}

std::string format_json(const Model& model, const Elimination& elimination) {
  const AlgebraLock lock;
  nlohmann::ordered_json out;
  out["model"] = model.name();
  nlohmann::ordered_json& latent = out["latent"] = nlohmann::ordered_json::array();
  for (int j : elimination.latent)
    latent.push_back(model.states()[static_cast<std::size_t>(j)].name);
  nlohmann::ordered_json& equations = out["equations"] = nlohmann::ordered_json::array();
  for (const EliminatedEquation& eq : elimination.equations) {
    nlohmann::ordered_json e;
    nlohmann::ordered_json& sources = e["sources"] = nlohmann::ordered_json::array();
    for (int s : eq.sources)
      sources.push_back(model.equations()[static_cast<std::size_t>(s)].name());
    nlohmann::ordered_json& terms = e["terms"] = nlohmann::ordered_json::array();
    for (const EliminatedTerm& t : eq.terms) {
      terms.push_back({{"coefficient", coefficient_text(model, t.coefficient)},
                       {"signal", derivative_text(model, t.monomial, t.order)},
                       {"order", t.order}});
    }
    equations.push_back(std::move(e));
  }
  nlohmann::ordered_json& coefficients = out["coefficients"] = nlohmann::ordered_json::array();
  for (const ex& c : elimination.coefficients) coefficients.push_back(coefficient_text(model, c));
  out["rank"] = elimination.rank;
  out["parameters"] = elimination.parameters.size();
  nlohmann::ordered_json& undetermined = out["undetermined"] = nlohmann::ordered_json::array();
  for (const Elimination::Undetermined& u : elimination.undetermined) {
    nlohmann::ordered_json names = nlohmann::ordered_json::array();
    for (int p : u.parameters)
      names.push_back(model.parameters()[static_cast<std::size_t>(p)].name);
    undetermined.push_back({{"parameters", names}, {"to_fix", u.to_fix}});
  }
  return out.dump(2) + "\n";
}

}  // namespace momentid
