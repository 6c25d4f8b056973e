// The dynamical moment technique, symbolically: multiply each equation by monomials in the
// states, take expectations, and reduce every derivative moment E[y^a * yj'] with a column that
// measures yj', kinematic equations or the stationarity identities E[d/dt y^b] = 0.

#include "momentid/derive.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <optional>
#include <random>
#include <set>

#include "momentid/algebra_lock.hpp"

namespace momentid {
namespace {

using GiNaC::numeric;

// E[monomial * state_j'], a moment with one derivative factor.
struct DerivativeMoment {
  Monomial monomial;
  int state = 0;
  bool operator<(const DerivativeMoment& o) const {
    if (state != o.state) return state < o.state;
    return MomentOrder()(monomial, o.monomial);
  }
};

// A linear combination of observable and derivative moments.
struct Linear {
  MomentCombination moments;
  std::map<DerivativeMoment, numeric> derivatives;
};

// One moment equation while it is being reduced: component 0 is the parameter-free part,
// component p + 1 the coefficient of parameter p; the equation is sum = 0.
struct Row {
  std::vector<RowSource> sources;
  std::vector<Linear> parts;
};

template <typename Map>
void add_to(Map& into, const typename Map::key_type& key, const numeric& value) {
  if (value.is_zero()) return;
  auto [it, inserted] = into.emplace(key, value);
  if (!inserted) {
    it->second += value;
    if (it->second.is_zero()) into.erase(it);
  }
}

template <typename Map>
void add_scaled(Map& into, const Map& from, const numeric& factor) {
  for (const auto& [key, value] : from) add_to(into, key, value * factor);
}

Monomial operator+(const Monomial& a, const Monomial& b) {
  Monomial out(a);
  for (std::size_t i = 0; i < b.size(); ++i) out[i] += b[i];
  return out;
}

class Deriver {
 public:
  Deriver(const Model& model, bool rates)
      : model_(model),
        rates_(rates),
        states_(static_cast<int>(model.states().size())),
        variables_(static_cast<int>(model.variables().size())),
        parameters_(static_cast<int>(model.parameters().size())),
        kinematic_(model.states().size()),
        kinematic_source_(model.states().size(), -1) {
    classify_equations();
  }

  // The equations that have parameters and are therefore multiplied.
  const std::vector<int>& dynamic_equations() const { return dynamic_; }

  MomentSystem run(const std::vector<std::vector<Monomial>>& multipliers) {
    MomentSystem system;
    system.model = &model_;
    system.notes = notes_;
    std::vector<Row> rows;
    for (int e : dynamic_) {
      for (const Monomial& m : multipliers[e]) rows.push_back(multiply(e, m));
    }
    for (Row& row : rows) reduce_derivatives(row);
    std::vector<Row> usable = eliminate_unreduced(rows, system.skipped);
    apply_identities(usable, system);
    int vanished = 0;
    for (Row& row : usable) {
      MomentEquation eq;
      eq.sources = row.sources;
      bool any = false;
      for (int p = 0; p < parameters_; ++p) {
        eq.coefficients.push_back(row.parts[p + 1].moments);
        any = any || !row.parts[p + 1].moments.empty();
      }
      for (const auto& [m, c] : row.parts[0].moments) eq.rhs[m] = -c;
      if (!any) {
        if (eq.rhs.empty()) {
          ++vanished;
        } else {
          system.skipped.push_back({row.sources[0].equation, row.sources[0].multiplier,
                                    "no parameter remains: the equation says only 0 = " +
                                        format_combination(model_, eq.rhs)});
        }
        continue;
      }
      system.equations.push_back(std::move(eq));
    }
    if (vanished > 0) {
      system.notes.push_back(std::to_string(vanished) +
                             (vanished == 1 ? " product reduces" : " products reduce") +
                             " to 0 = 0 and gives no equation");
    }
    if (parameters_ == 0) system.notes.push_back("the model has no unknown parameters");
    std::set<Monomial, MomentOrder> needed;
    for (const MomentEquation& eq : system.equations) {
      for (const auto& c : eq.coefficients) {
        for (const auto& [m, v] : c) needed.insert(m);
      }
      for (const auto& [m, v] : eq.rhs) needed.insert(m);
    }
    needed.erase(Monomial(variables_, 0));
    system.moments.assign(needed.begin(), needed.end());
    system.generic_rank = rank(system, /*symmetric=*/false, /*with_rhs=*/false);
    system.symmetric_rank = rank(system, /*symmetric=*/true, /*with_rhs=*/false);
    system.symmetric_rank_with_rhs = rank(system, /*symmetric=*/true, /*with_rhs=*/true);
    return system;
  }

 private:
  // A kinematic equation is parameter-free with one derivative term c*yj' (c a number) and no
  // other derivative: it gives yj' = f(y, u) exactly.
  void classify_equations() {
    const auto& eqs = model_.equations();
    for (std::size_t e = 0; e < eqs.size(); ++e) {
      bool has_parameter = false;
      int derivative_terms = 0;
      const Term* lead = nullptr;
      for (const Term& t : eqs[e].terms) {
        has_parameter = has_parameter || t.parameter >= 0;
        if (t.derivative >= 0) {
          ++derivative_terms;
          lead = &t;
        }
      }
      if (has_parameter) {
        dynamic_.push_back(static_cast<int>(e));
        continue;
      }
      const bool explicit_in_one = derivative_terms == 1 && lead->monomial.degree() == 0;
      if (explicit_in_one && kinematic_[lead->derivative]) {
        notes_.push_back("equation " + eqs[e].name() + " gives " +
                         model_.states()[lead->derivative].name + "' again (equation " +
                         eqs[kinematic_source_[lead->derivative]].name() +
                         " already does): it gives no moment equations");
        continue;
      }
      if (!explicit_in_one) {
        notes_.push_back("equation " + eqs[e].name() +
                         " has no unknown parameters and is not of the form y' = f(y, u): "
                         "it gives no moment equations");
        continue;
      }
      MomentCombination f;
      for (const Term& t : eqs[e].terms) {
        if (&t != lead) add_to(f, t.monomial, -t.coefficient / lead->coefficient);
      }
      kinematic_[lead->derivative] = std::move(f);
      kinematic_source_[lead->derivative] = static_cast<int>(e);
    }
  }

  Row multiply(int e, const Monomial& multiplier) {
    Row row;
    row.sources.push_back({e, multiplier, 1});
    row.parts.resize(parameters_ + 1);
    Monomial m = multiplier;
    m.resize(static_cast<std::size_t>(variables_));
    for (const Term& t : model_.equations()[e].terms) {
      Linear& part = row.parts[t.parameter + 1];
      if (t.derivative >= 0) {
        add_to(part.derivatives, DerivativeMoment{t.monomial + m, t.derivative}, t.coefficient);
      } else {
        add_to(part.moments, t.monomial + m, t.coefficient);
      }
    }
    return row;
  }

  // Whether `m` holds an input or a function.
  bool has_input(const Monomial& m) const {
    for (std::size_t i = 0; i < m.size(); ++i) {
      if (m[i] != 0 && model_.variables()[i].kind != VariableKind::kState) return true;
    }
    return false;
  }

  // E[monomial * f_j] for a kinematic state j.
  void add_kinematic(MomentCombination& into, const Monomial& monomial, int j,
                     const numeric& factor) const {
    for (const auto& [nu, c] : *kinematic_[j]) add_to(into, monomial + nu, c * factor);
  }

  // The states whose derivatives appear, unknown, in the stationarity identity of E[y^beta]:
  // sum over j of beta_j * E[y^(beta - e_j) * yj'] = 0.
  std::vector<int> dynamic_in(const Monomial& beta) const {
    std::vector<int> out;
    for (int j = 0; j < states_; ++j) {
      if (beta[j] > 0 && !kinematic_[j]) out.push_back(j);
    }
    return out;
  }

  // Replaces every derivative moment that kinematics or a stationarity identity determine.
  // Within one identity with several unknown derivative moments, the one of the highest state is
  // expressed through the others, so what remains is in a canonical set of free moments.
  void reduce_derivatives(Row& row) const {
    for (Linear& part : row.parts) {
      std::map<DerivativeMoment, numeric> pending;
      pending.swap(part.derivatives);
      for (const auto& [d, c] : pending) {
        if (const int a = model_.measured_derivative_of(d.state); a >= 0) {
          // E[g*v'] with a column holding v': a data moment, E[g*a].
          Monomial moment = d.monomial;
          moment[static_cast<std::size_t>(a)] += 1;
          add_to(part.moments, moment, c);
          continue;
        }
        if (kinematic_[d.state]) {
          add_kinematic(part.moments, d.monomial, d.state, c);
          continue;
        }
        if (has_input(d.monomial)) {
          add_to(part.derivatives, d, c);
          continue;
        }
        Monomial beta = d.monomial;
        beta[d.state] += 1;
        const std::vector<int> unknown = dynamic_in(beta);
        if (unknown.back() != d.state) {
          add_to(part.derivatives, d, c);
          continue;
        }
        // beta_j * D_j = E[(y^beta)'] - (sum over the other states j' of beta_j' * D_j')
        const numeric scale = -c / beta[d.state];
        if (rates_) add_to(part.moments, beta.as_rate(), c / beta[d.state]);
        for (int j = 0; j < states_; ++j) {
          if (j == d.state || beta[j] == 0) continue;
          Monomial alpha = beta;
          alpha[j] -= 1;
          if (kinematic_[j]) {
            add_kinematic(part.moments, alpha, j, scale * beta[j]);
          } else {
            add_to(part.derivatives, DerivativeMoment{alpha, j}, scale * beta[j]);
          }
        }
      }
    }
  }

  // Rows that still hold derivative moments are added together, with numeric factors, so that
  // those moments cancel in every parameter's coefficient; rows that cannot be part of such a
  // combination are skipped.
  std::vector<Row> eliminate_unreduced(const std::vector<Row>& rows,
                                       std::vector<SkippedMultiplier>& skipped) const {
    using Key = std::pair<int, DerivativeMoment>;
    struct Pivot {
      Key key;
      std::map<Key, numeric> residual;
      std::map<int, numeric> combination;
    };
    std::vector<Row> out;
    std::vector<Pivot> pivots;
    std::vector<bool> used(rows.size(), false);
    std::vector<std::map<int, numeric>> combinations;
    for (std::size_t r = 0; r < rows.size(); ++r) {
      std::map<Key, numeric> residual;
      for (std::size_t p = 0; p < rows[r].parts.size(); ++p) {
        for (const auto& [d, c] : rows[r].parts[p].derivatives) {
          residual[{static_cast<int>(p), d}] = c;
        }
      }
      if (residual.empty()) {
        used[r] = true;
        out.push_back(rows[r]);
        continue;
      }
      std::map<int, numeric> combination{{static_cast<int>(r), 1}};
      for (const Pivot& pivot : pivots) {
        auto it = residual.find(pivot.key);
        if (it == residual.end()) continue;
        const numeric factor = -it->second / pivot.residual.at(pivot.key);
        add_scaled(residual, pivot.residual, factor);
        add_scaled(combination, pivot.combination, factor);
      }
      if (residual.empty()) {
        combinations.push_back(combination);
      } else {
        const Key key = residual.begin()->first;
        pivots.push_back({key, std::move(residual), std::move(combination)});
      }
    }
    for (const auto& combination : combinations) {
      Row sum;
      sum.parts.resize(parameters_ + 1);
      for (const auto& [r, factor] : combination) {
        used[r] = true;
        for (const RowSource& s : rows[r].sources)
          sum.sources.push_back({s.equation, s.multiplier, s.factor * factor});
        for (std::size_t p = 0; p < sum.parts.size(); ++p) {
          add_scaled(sum.parts[p].moments, rows[r].parts[p].moments, factor);
        }
      }
      out.push_back(std::move(sum));
    }
    for (std::size_t r = 0; r < rows.size(); ++r) {
      if (used[r]) continue;
      skipped.push_back(
          {rows[r].sources[0].equation, rows[r].sources[0].multiplier, unreduced_reason(rows[r])});
    }
    return out;
  }

  std::string derivative_name(const DerivativeMoment& d) const {
    const std::string m = format_monomial(model_, d.monomial);
    const std::string y = model_.states()[d.state].name + "'";
    return "E[" + (m == "1" ? y : m + "*" + y) + "]";
  }

  std::string unreduced_reason(const Row& row) const {
    for (const Linear& part : row.parts) {
      if (part.derivatives.empty()) continue;
      const DerivativeMoment& d = part.derivatives.begin()->first;
      if (has_input(d.monomial)) {
        return derivative_name(d) +
               " multiplies an input by a derivative: no stationarity identity reduces it";
      }
      Monomial beta = d.monomial;
      beta[d.state] += 1;
      std::string sum;
      for (int j : dynamic_in(beta)) {
        Monomial alpha = beta;
        alpha[j] -= 1;
        if (!sum.empty()) sum += " + ";
        if (beta[j] > 1) sum += std::to_string(beta[j]) + "*";
        sum += derivative_name({alpha, j});
      }
      return derivative_name(d) + " is known only in the sum " + sum + " (from E[d/dt " +
             format_monomial(model_, beta) +
             "] = 0), and no combination of the chosen equations eliminates it";
    }
    return "";
  }

  // --- Pure-data identities -------------------------------------------------------------------

  // The identity of E[y^beta] when every state in it is kinematic: a relation among observable
  // moments, sum over j of beta_j * E[y^(beta - e_j) * f_j] = 0.
  std::optional<MomentCombination> data_identity(const Monomial& beta) const {
    if (has_input(beta) || !dynamic_in(beta).empty()) return std::nullopt;
    MomentCombination out;
    for (int j = 0; j < states_; ++j) {
      if (beta[j] == 0) continue;
      Monomial alpha = beta;
      alpha[j] -= 1;
      add_kinematic(out, alpha, j, beta[j]);
    }
    return out;
  }

  // The relation `identity` = 0 of E[d/dt y^beta], less the record's rate with rates_.
  MomentCombination with_rate(MomentCombination identity, const Monomial& beta) const {
    if (rates_) add_to(identity, beta.as_rate(), numeric(-1));
    return identity;
  }

  // Finds the identities that touch the equations' moments (and those they bring in), solves
  // them for one moment each, and substitutes. Rates are never solved for: they are data.
  void apply_identities(std::vector<Row>& rows, MomentSystem& system) const {
    std::set<Monomial, MomentOrder> seen, done;
    std::vector<Monomial> work;
    auto visit = [&](const MomentCombination& c) {
      for (const auto& [m, v] : c) {
        if (!m.rate() && seen.insert(m).second) work.push_back(m);
      }
    };
    for (const Row& row : rows) {
      for (const Linear& part : row.parts) visit(part.moments);
    }
    // Identities are looked for only among moments no higher than the equations' own: with a
    // kinematic equation such as y' = 1 - y (or -y - y^3) each identity would otherwise bring in
    // moments of a higher degree without end.
    int top = 0;
    for (const Monomial& m : seen) top = std::max(top, m.degree());
    std::vector<MomentCombination> relations;
    // E[d/dt y] = 0 for every state given by a kinematic equation: E[f(y, u)] = 0. Its
    // constant part, if alone (y' = 1), says the model cannot be stationary at all.
    for (int j = 0; j < states_; ++j) {
      if (!kinematic_[j]) continue;
      Monomial beta(variables_, 0);
      beta[j] = 1;
      done.insert(beta);
      std::optional<MomentCombination> identity = data_identity(beta);
      if (!identity || identity->empty()) continue;
      const Monomial one(variables_, 0);
      bool contradiction = true, relevant = false;
      for (const auto& [m, w] : *identity) {
        contradiction = contradiction && m == one;
        relevant = relevant || seen.count(m) != 0;
      }
      if (contradiction || relevant) relations.push_back(with_rate(std::move(*identity), beta));
    }
    while (!work.empty()) {
      const Monomial mu = work.back();
      work.pop_back();
      for (int j = 0; j < states_; ++j) {
        if (!kinematic_[j]) continue;
        for (const auto& [nu, c] : *kinematic_[j]) {
          Monomial beta = mu;
          bool divides = true;
          for (int i = 0; i < variables_; ++i) {
            beta[i] -= nu[i];
            divides = divides && beta[i] >= 0;
          }
          if (!divides) continue;
          beta[j] += 1;
          if (!done.insert(beta).second) continue;
          std::optional<MomentCombination> identity = data_identity(beta);
          if (!identity || identity->empty()) continue;
          bool bounded = true;
          for (const auto& [m, w] : *identity) bounded = bounded && m.degree() <= top;
          if (!bounded) continue;
          visit(*identity);
          relations.push_back(with_rate(std::move(*identity), beta));
        }
      }
    }
    // Gauss-Jordan elimination over moments: each solved moment is written in the others.
    std::sort(relations.begin(), relations.end(), [](const auto& a, const auto& b) {
      return MomentOrder()(a.rbegin()->first, b.rbegin()->first);
    });
    std::map<Monomial, MomentCombination, MomentOrder> solved;
    const Monomial one(variables_, 0);
    for (MomentCombination relation : relations) {
      substitute(relation, solved);
      std::optional<Monomial> pivot;
      for (const auto& [m, v] : relation) {
        if (m == one || m.rate()) continue;
        if (!pivot || m.degree() > pivot->degree() ||
            (m.degree() == pivot->degree() && m < *pivot)) {
          pivot = m;
        }
      }
      if (!pivot) {
        std::erase_if(relation, [](const auto& term) { return term.first.rate(); });
        if (relation.count(one) != 0) {
          system.notes.push_back(
              "the model cannot be stationary: a stationarity identity says "
              "0 = " +
              format_combination(model_, relation));
        }
        continue;
      }
      MomentCombination value;
      const numeric lead = relation.at(*pivot);
      for (const auto& [m, v] : relation) {
        if (m != *pivot) value[m] = -v / lead;
      }
      for (auto& [m, other] : solved) {
        auto it = other.find(*pivot);
        if (it == other.end()) continue;
        const numeric factor = it->second;
        other.erase(it);
        add_scaled(other, value, factor);
      }
      solved[*pivot] = std::move(value);
    }
    for (Row& row : rows) {
      for (Linear& part : row.parts) substitute(part.moments, solved);
    }
    for (auto& [m, value] : solved) {
      std::erase_if(value, [](const auto& term) { return term.first.rate(); });
      const bool even = std::all_of(m.begin(), m.end(), [](int e) { return e % 2 == 0; });
      if (value.empty() && even) {
        system.notes.push_back("stationarity requires " + format_moment(model_, m) +
                               " = 0, which only a zero signal satisfies: check the "
                               "parameter-free equations");
      }
      system.identities.push_back({m, value});
    }
  }

  static void substitute(MomentCombination& c,
                         const std::map<Monomial, MomentCombination, MomentOrder>& solved) {
    for (const auto& [m, value] : solved) {
      auto it = c.find(m);
      if (it == c.end()) continue;
      const numeric factor = it->second;
      c.erase(it);
      add_scaled(c, value, factor);
    }
  }

  // The rank of the coefficient matrix (with `with_rhs`, of the matrix with the right-hand
  // sides as one more column) for random moment values, the record's rates of change at their
  // expectation 0. With `symmetric`, the moments that change sign with the states and inputs
  // (Parity::kOdd) are set to zero too, as they vanish for a system that is symmetric under
  // y, u -> -y, -u driven by a symmetric input.
  int rank(const MomentSystem& system, bool symmetric, bool with_rhs) const {
    if (system.equations.empty() || parameters_ == 0) return 0;
    std::mt19937_64 engine(20260101);
    std::uniform_real_distribution<double> draw(0.5, 2.0);
    std::map<Monomial, double> value;
    for (const Monomial& m : system.moments) {
      // A record's rate of change has expectation 0.
      const bool zero = m.rate() || (symmetric && parity(model_, m) == Parity::kOdd);
      value[m] = zero ? 0.0 : draw(engine);
    }
    value[Monomial(variables_, 0)] = 1.0;
    auto value_of = [&](const MomentCombination& combination) {
      double sum = 0;
      for (const auto& [m, c] : combination) sum += c.to_double() * value[m];
      return sum;
    };
    const int columns = parameters_ + (with_rhs ? 1 : 0);
    Eigen::MatrixXd a(system.equations.size(), columns);
    for (std::size_t r = 0; r < system.equations.size(); ++r) {
      const MomentEquation& eq = system.equations[r];
      const auto row = static_cast<Eigen::Index>(r);
      for (int p = 0; p < parameters_; ++p) a(row, p) = value_of(eq.coefficients[p]);
      if (with_rhs) a(row, parameters_) = value_of(eq.rhs);
    }
    for (int p = 0; p < columns; ++p) {
      const double norm = a.col(p).norm();
      if (norm > 0) a.col(p) /= norm;
    }
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
    qr.setThreshold(1e-9);
    return static_cast<int>(qr.rank());
  }

  const Model& model_;
  bool rates_;  // DeriveOptions::rates
  int states_, variables_, parameters_;
  std::vector<std::optional<MomentCombination>> kinematic_;
  std::vector<int> kinematic_source_;  // the equation that gave each kinematic state
  std::vector<int> dynamic_;
  std::vector<std::string> notes_;
};

}  // namespace

bool MomentOrder::operator()(const Monomial& a, const Monomial& b) const {
  // A rate E[(g)'] is listed among the moments of one degree more than g.
  const int da = a.degree() + a.rate(), db = b.degree() + b.rate();
  if (da != db) return da < db;
  return a > b;
}

std::vector<Monomial> monomials_up_to(int states, int max_degree) {
  std::vector<Monomial> out;
  std::vector<Monomial> level{Monomial(states, 0)};
  for (int d = 1; d <= max_degree; ++d) {
    std::set<Monomial, MomentOrder> next;
    for (const Monomial& m : level) {
      for (int i = 0; i < states; ++i) {
        Monomial n = m;
        ++n[i];
        next.insert(n);
      }
    }
    level.assign(next.begin(), next.end());
    out.insert(out.end(), level.begin(), level.end());
  }
  return out;
}

double count_monomials(int states, int degree) {
  double c = 1;
  for (int i = 1; i <= degree; ++i) c = c * (states + i) / i;
  return c - 1;
}

namespace {}  // namespace

MomentSystem derive(const Model& model, const DeriveOptions& options) {
  const AlgebraLock lock;
  Deriver deriver(model, options.rates);
  const int states = static_cast<int>(model.states().size());
  const auto& equations = model.equations();
  const double dynamic = static_cast<double>(deriver.dynamic_equations().size());
  if (options.degree > 0 && dynamic * count_monomials(states, options.degree) > kMaxProducts) {
    throw UsageError("--degree " + std::to_string(options.degree) + " on " +
                     std::to_string(states) + " states would multiply " +
                     std::to_string(static_cast<long>(dynamic)) + " equations by " +
                     std::to_string(static_cast<long>(count_monomials(states, options.degree))) +
                     " monomials each, more than " + std::to_string(kMaxProducts) +
                     " products: use a lower degree or give --multipliers");
  }
  std::vector<std::vector<Monomial>> multipliers(equations.size());
  auto all = [&](const std::vector<Monomial>& list) {
    for (auto& m : multipliers) m = list;
  };
  if (options.multipliers) {
    all(*options.multipliers);
  } else if (options.degree > 0) {
    all(monomials_up_to(states, options.degree));
  } else if (!model.multipliers().empty()) {
    // An equation's own statements win over those for all equations; statements of the same
    // kind add up.
    std::vector<std::vector<Monomial>> general(equations.size());
    for (const MultiplierSet& set : model.multipliers()) {
      for (std::size_t e = 0; e < equations.size(); ++e) {
        if (!set.equation.empty() && equations[e].label != set.equation) continue;
        auto& into = set.equation.empty() ? general[e] : multipliers[e];
        for (const Monomial& m : set.monomials) {
          if (std::find(into.begin(), into.end(), m) == into.end()) into.push_back(m);
        }
      }
    }
    for (std::size_t e = 0; e < equations.size(); ++e) {
      if (multipliers[e].empty()) multipliers[e] = general[e];
    }
    MomentSystem system = deriver.run(multipliers);
    const std::vector<int>& dynamic_equations = deriver.dynamic_equations();
    for (std::size_t e = 0; e < equations.size(); ++e) {
      const bool has_parameters = std::find(dynamic_equations.begin(), dynamic_equations.end(),
                                            static_cast<int>(e)) != dynamic_equations.end();
      if (has_parameters && multipliers[e].empty()) {
        system.notes.push_back("equation " + equations[e].name() +
                               " has no multipliers: no multipliers statement covers it");
      }
      if (!has_parameters && !equations[e].label.empty()) {
        for (const MultiplierSet& set : model.multipliers()) {
          if (set.equation == equations[e].label) {
            system.notes.push_back("the multipliers for equation " + equations[e].name() +
                                   " are not used: it has no unknown parameters");
            break;
          }
        }
      }
    }
    return system;
  } else {
    // The lowest degree, at least the model's own (its highest power of the states and inputs,
    // up to kMaxAutomaticDegree), that determines every parameter even when odd moments vanish
    // (as they do for symmetric systems under symmetric input) and leaves equations to spare
    // for the model's test; failing the spare ones, the lowest that determines them; failing
    // that, the lowest that does for generic moments. Below the model's degree the system is
    // square or nearly so, and its estimates are far poorer (docs/cli/derive.md).
    int model_degree = 1;
    for (const Equation& eq : equations) {
      for (const Term& t : eq.terms) model_degree = std::max(model_degree, t.monomial.degree());
    }
    const int parameters = static_cast<int>(model.parameters().size());
    std::optional<MomentSystem> full, low, generic;  // full: at or above the model's degree
    MomentSystem last;
    for (int d = 1; d <= kMaxAutomaticDegree; ++d) {
      if (d > 1 && dynamic * count_monomials(states, d) > kMaxProducts) break;
      all(monomials_up_to(states, d));
      last = deriver.run(multipliers);
      if (last.symmetric_rank == parameters) {
        if (d >= model_degree && last.symmetric_rank_with_rhs > parameters) return last;
        if (!full && d >= model_degree) full = last;
        if (!low) low = last;
      }
      if (!generic && last.generic_rank == parameters) generic = last;
    }
    return full ? *full : low ? *low : generic ? *generic : last;
  }
  return deriver.run(multipliers);
}

}  // namespace momentid
