#include "momentid/simulate.hpp"

#include <charconv>
#include <cmath>
#include <map>
#include <string_view>

#include "common/decimal.hpp"
#include "momentid/error.hpp"

namespace momentid {
namespace {

using GiNaC::numeric;
using Terms = std::map<Monomial, numeric>;

void add_term(Terms& into, const Monomial& m, const numeric& c) {
  if (c.is_zero()) return;
  auto [it, inserted] = into.emplace(m, c);
  if (!inserted) {
    it->second += c;
    if (it->second.is_zero()) into.erase(it);
  }
}

bool is_constant(const Terms& t) {
  for (const auto& [m, c] : t) {
    for (int e : m) {
      if (e != 0) return false;
    }
  }
  return true;
}

std::string parameter_list(const Model& model, const std::vector<numeric>& values) {
  std::string out;
  for (std::size_t p = 0; p < values.size(); ++p) {
    out += (p ? ", " : "") + model.parameters()[p].name + "=" +
           shortest_decimal(values[p].to_double());
  }
  return out;
}

}  // namespace

CompiledModel::CompiledModel(const Model& model, const std::vector<numeric>& parameters)
    : states_(static_cast<int>(model.states().size())),
      variables_(static_cast<int>(model.variables().size())) {
  const auto& equations = model.equations();
  if (equations.size() != static_cast<std::size_t>(states_)) {
    throw ModelError(equations.front().where,
                     "simulation needs one equation per state: the model has " +
                         std::to_string(equations.size()) + " equations for " +
                         std::to_string(states_) + " states");
  }
  // M y' = h: M[e][j] is the coefficient of yj' in equation e (lhs - rhs), h = -(the rest).
  const std::size_t n = static_cast<std::size_t>(states_);
  std::vector<Terms> m(n * n), h(n);
  max_power_.assign(static_cast<std::size_t>(variables_), 1);
  for (std::size_t e = 0; e < n; ++e) {
    for (const Term& t : equations[e].terms) {
      numeric c = t.coefficient;
      if (t.parameter >= 0) c *= parameters[static_cast<std::size_t>(t.parameter)];
      if (t.derivative >= 0) {
        add_term(m[e * n + static_cast<std::size_t>(t.derivative)], t.monomial, c);
      } else {
        add_term(h[e], t.monomial, -c);
      }
      for (std::size_t v = 0; v < t.monomial.size(); ++v) {
        max_power_[v] = std::max(max_power_[v], t.monomial[v]);
      }
    }
  }
  std::uint32_t offset = 0;
  for (int power : max_power_) {
    power_offset_.push_back(offset);
    offset += static_cast<std::uint32_t>(power) + 1;
  }
  powers_.assign(offset, 1.0);
  for (const Terms& entry : m) constant_matrix_ = constant_matrix_ && is_constant(entry);
  if (constant_matrix_) {
    // Solve once, exactly: f = M^-1 h.
    GiNaC::matrix a(static_cast<unsigned>(n), static_cast<unsigned>(n));
    const Monomial one(static_cast<std::size_t>(variables_), 0);
    for (std::size_t i = 0; i < n * n; ++i) {
      const auto it = m[i].find(one);
      a(static_cast<unsigned>(i / n), static_cast<unsigned>(i % n)) =
          it == m[i].end() ? numeric(0) : it->second;
    }
    if (a.determinant().is_zero()) {
      throw ModelError(equations.front().where,
                       "the equations cannot be solved for the derivatives with " +
                           parameter_list(model, parameters) +
                           " (the coefficients of the derivatives form a singular matrix)");
    }
    const GiNaC::matrix inverse = a.inverse();
    for (std::size_t j = 0; j < n; ++j) {
      Terms f;
      for (std::size_t e = 0; e < n; ++e) {
        const numeric w =
            GiNaC::ex_to<numeric>(inverse(static_cast<unsigned>(j), static_cast<unsigned>(e)));
        if (w.is_zero()) continue;
        for (const auto& [mono, c] : h[e]) add_term(f, mono, w * c);
      }
      compile(f);
    }
  } else {
    for (const Terms& entry : m) compile(entry);
    for (const Terms& entry : h) compile(entry);
    scratch_.resize(2 * n * (n + 1));
  }
}

std::size_t CompiledModel::compile(const Terms& terms) {
  for (const auto& [mono, c] : terms) {
    TermRef t{c.to_double(), static_cast<std::uint32_t>(factor_index_.size()), 0,
              static_cast<std::uint32_t>(first_term_.size() - 1)};
    for (std::size_t v = 0; v < mono.size(); ++v) {
      if (mono[v] == 0) continue;
      factor_index_.push_back(power_offset_[v] + static_cast<std::uint32_t>(mono[v]));
      ++t.factors;
    }
    terms_.push_back(t);
  }
  first_term_.push_back(static_cast<std::uint32_t>(terms_.size()));
  return first_term_.size() - 2;
}

bool CompiledModel::solve(double* dydt) const {
  const int n = states_;
  // Gaussian elimination with partial pivoting on [M | h].
  const int w = n + 1;
  // Polynomials 0..n*n-1 are M row by row, n*n..n*n+n-1 are h: build [M | h] from them.
  double* values = scratch_.data() + n * w;
  evaluate_all(values, static_cast<std::size_t>(n * w));
  double* a = scratch_.data();
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) a[r * w + c] = values[r * n + c];
    a[r * w + n] = values[n * n + r];
  }
  for (int c = 0; c < n; ++c) {
    int pivot = c;
    for (int r = c + 1; r < n; ++r) {
      if (std::abs(a[r * w + c]) > std::abs(a[pivot * w + c])) pivot = r;
    }
    if (!(std::abs(a[pivot * w + c]) > 0)) return false;
    if (pivot != c) {
      for (int k = 0; k < w; ++k) std::swap(a[c * w + k], a[pivot * w + k]);
    }
    for (int r = c + 1; r < n; ++r) {
      const double factor = a[r * w + c] / a[c * w + c];
      for (int k = c; k < w; ++k) a[r * w + k] -= factor * a[c * w + k];
    }
  }
  for (int r = n - 1; r >= 0; --r) {
    double sum = a[r * w + n];
    for (int k = r + 1; k < n; ++k) sum -= a[r * w + k] * dydt[k];
    dydt[r] = sum / a[r * w + r];
  }
  return true;
}

void SimulationOptions::validate(const Model& model) const {
  const auto count = [&](std::size_t found, std::size_t expected, const std::string& what) {
    if (found != expected) {
      throw UsageError("simulate: model " + model.name() + " needs " + std::to_string(expected) +
                       " " + what + ", found " + std::to_string(found));
    }
  };
  count(parameters.size(), model.parameters().size(), "parameter values");
  count(inputs.size(), model.inputs().size(), "input processes");
  if (!(std::isfinite(dt) && dt >= kMinStep && dt <= kMaxStep)) {
    throw UsageError("simulate: dt must be a number from 1e-9 to 1e6, found " +
                     shortest_decimal(dt));
  }
  if (samples == 0) throw UsageError("simulate: the number of samples must be at least 1");
  if (runs == 0) throw UsageError("simulate: the number of runs must be at least 1");
}

void simulate(const Model& model, const SimulationOptions& options, SampleSink& sink) {
  options.validate(model);
  const CompiledModel f(model, options.parameters);
  const std::size_t n = static_cast<std::size_t>(f.states());
  const std::size_t m = static_cast<std::size_t>(f.inputs());
  std::vector<InputProcess> inputs;
  for (std::size_t i = 0; i < m; ++i) {
    inputs.emplace_back(options.inputs[i], options.dt, options.seed, i);
  }
  std::vector<double> k1(n), k2(n), k3(n), k4(n), trial(n);
  std::vector<double> values(n + m);
  double* y = values.data();
  double* u = values.data() + n;
  const double h = options.dt;
  std::size_t run = 0;
  double t = 0;
  bool burning_in = false;

  const auto fail = [&](const std::string& what) {
    const std::string when =
        burning_in ? "during the burn-in of run " + std::to_string(run + 1)
                   : "at t = " + shortest_decimal(t) + " in run " + std::to_string(run + 1);
    throw Error("the simulation " + what + " " + when + " with " +
                parameter_list(model, options.parameters) +
                ": the model is unstable for these values, or the step dt is too large");
  };
  const auto rates = [&](const double* state, double* out) {
    if (!f.derivative(state, u, out)) {
      fail("met a point where the derivatives cannot be solved for");
    }
  };
  // One Runge-Kutta step from t to t + h with the inputs u held constant.
  const auto integrate = [&] {
    rates(y, k1.data());
    for (std::size_t j = 0; j < n; ++j) trial[j] = y[j] + 0.5 * h * k1[j];
    rates(trial.data(), k2.data());
    for (std::size_t j = 0; j < n; ++j) trial[j] = y[j] + 0.5 * h * k2[j];
    rates(trial.data(), k3.data());
    for (std::size_t j = 0; j < n; ++j) trial[j] = y[j] + h * k3[j];
    rates(trial.data(), k4.data());
    bool finite = true;
    for (std::size_t j = 0; j < n; ++j) {
      y[j] += h / 6 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]);
      finite = finite && std::abs(y[j]) <= kBlowUpBound;
    }
    if (!finite) {
      t += h;
      for (std::size_t j = 0; j < n; ++j) {
        if (!(std::abs(y[j]) <= kBlowUpBound)) {
          fail("blew up: state '" + model.states()[j].name + "' reached " + shortest_decimal(y[j]));
        }
      }
    }
  };
  const auto draw_inputs = [&] {
    for (std::size_t i = 0; i < m; ++i) u[i] = inputs[i].next();
  };

  for (run = 0; run < options.runs; ++run) {
    if (run == 0 || !options.continue_runs) {
      std::fill(y, y + n, 0.0);
      burning_in = true;
      for (std::size_t s = 0; s < options.burn_in; ++s) {
        draw_inputs();
        integrate();
      }
      burning_in = false;
    }
    // Row s: the state at t_s and the input held over [t_s, t_s+1).
    for (std::size_t s = 0; s < options.samples; ++s) {
      t = static_cast<double>(s) * h;
      draw_inputs();
      sink.sample(t, values.data(), run);
      integrate();
    }
  }
}

namespace {

// [+-] digits [. digits] [e [+-] digits], with digits on at least one side of the point.
bool is_decimal(std::string_view text) {
  std::size_t i = 0;
  auto digits = [&] {
    const std::size_t start = i;
    while (i < text.size() && text[i] >= '0' && text[i] <= '9') ++i;
    return i - start;
  };
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
  std::size_t mantissa = digits();
  if (i < text.size() && text[i] == '.') {
    ++i;
    mantissa += digits();
  }
  if (mantissa == 0) return false;
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
    if (digits() == 0) return false;
  }
  return i == text.size();
}

}  // namespace

std::vector<numeric> parameter_values(const Model& model,
                                      const std::vector<std::string>& assignments) {
  std::vector<std::optional<numeric>> values;
  for (const Declaration& p : model.parameters()) values.push_back(p.value);
  for (const std::string& a : assignments) {
    const std::size_t eq = a.find('=');
    if (eq == std::string::npos) {
      throw UsageError("--set: expected NAME=VALUE, found '" + a + "'");
    }
    const std::string name = a.substr(0, eq), text = a.substr(eq + 1);
    const int p = model.parameter_index(name);
    if (p < 0) {
      std::string known;
      for (const Declaration& d : model.parameters()) known += (known.empty() ? "" : ", ") + d.name;
      throw UsageError("--set: '" + name + "' is not a parameter of model " + model.name() +
                       " (parameters: " + known + ")");
    }
    if (!is_decimal(text)) {
      throw UsageError("--set: the value of '" + name + "' must be a number, found '" + text + "'");
    }
    const bool negative = text[0] == '-';
    const std::string digits = (text[0] == '-' || text[0] == '+') ? text.substr(1) : text;
    numeric v;
    try {
      v = parse_exact_number(digits);
    } catch (const std::out_of_range& e) {
      throw UsageError(std::string("--set: ") + e.what());
    }
    values[static_cast<std::size_t>(p)] = negative ? -v : v;
  }
  std::vector<numeric> out;
  for (std::size_t p = 0; p < values.size(); ++p) {
    if (!values[p]) {
      throw ModelError(model.parameters()[p].where,
                       "parameter '" + model.parameters()[p].name +
                           "' has no value: give a nominal value in the model or --set " +
                           model.parameters()[p].name + "=VALUE");
    }
    out.push_back(*values[p]);
  }
  return out;
}

DataMetadata simulation_metadata(const Model& model, const SimulationOptions& options) {
  DataMetadata metadata;
  metadata.add_line({{"model", model.name()},
                     {"dt", shortest_decimal(options.dt)},
                     {"input-hold", "zoh"},
                     {"seed", std::to_string(options.seed)},
                     {"samples", std::to_string(options.samples)},
                     {"runs", std::to_string(options.runs)},
                     {"burn-in", std::to_string(options.burn_in)},
                     {"continue", options.continue_runs ? "yes" : "no"}});
  DataMetadata::Line parameters;
  for (std::size_t p = 0; p < options.parameters.size(); ++p) {
    parameters.emplace_back("param." + model.parameters()[p].name,
                            shortest_decimal(options.parameters[p].to_double()));
  }
  metadata.add_line(std::move(parameters));
  for (std::size_t i = 0; i < options.inputs.size(); ++i) {
    metadata.add_line({{"input." + model.inputs()[i].name, options.inputs[i].text()}});
  }
  return metadata;
}

void simulate_to_file(const Model& model, const SimulationOptions& options, const std::string& path,
                      DataWriter::Format format) {
  options.validate(model);
  std::vector<std::string> columns{"t"};
  for (const std::string& v : model.variables()) columns.push_back(v);
  const bool with_run = options.runs > 1;
  if (with_run) columns.push_back("run");
  DataWriter out(path, format, simulation_metadata(model, options), columns);
  SampleRows rows(out, model.variables().size(), with_run);
  simulate(model, options, rows);
  out.commit();
}

}  // namespace momentid
