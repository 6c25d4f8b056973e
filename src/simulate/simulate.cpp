#include "momentid/simulate.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string_view>

#include "common/decimal.hpp"
#include "momentid/algebra_lock.hpp"
#include "momentid/error.hpp"
#include "simulate/step.hpp"
#include "simulate/switching.hpp"

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

std::string join(const std::vector<std::string>& items, const std::string& separator) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? separator : "") + items[i];
  return out;
}

}  // namespace

CompiledModel::CompiledModel(const Model& model, const std::vector<numeric>& parameters)
    : states_(static_cast<int>(model.states().size())),
      channels_(static_cast<int>(model.states().size() + model.inputs().size())),
      variables_(static_cast<int>(model.variables().size())) {
  const AlgebraLock lock;
  for (const VariableFunction& f : model.functions()) {
    Function& compiled = functions_.emplace_back();
    compiled.sign = f.kind == FunctionKind::kSign;
    for (const auto& [coefficient, monomial] : f.argument) {
      auto& term =
          compiled.terms.emplace_back(coefficient.to_double(), std::vector<std::pair<int, int>>{});
      for (std::size_t v = 0; v < monomial.size(); ++v) {
        if (monomial[v] != 0) term.second.emplace_back(static_cast<int>(v), monomial[v]);
      }
    }
    // A switch that moves with the input would slide along a moving surface, which the
    // sliding motion (equivalent control over the states' rates) does not follow.
    bool of_states = false, of_inputs = false;
    for (const auto& term : compiled.terms) {
      for (const auto& [v, power] : term.second) (v < states_ ? of_states : of_inputs) = true;
    }
    if (of_states && of_inputs) {
      throw ModelError(f.where, f.name +
                                    " mixes states and inputs: simulate and validate take abs "
                                    "and sign of the states alone or of the inputs alone");
    }
    std::size_t linear = 0, constant = 0;
    for (const auto& [coefficient, factors] : compiled.terms) {
      if (factors.empty()) {
        ++constant;
      } else if (factors.size() == 1 && factors[0].second == 1 && factors[0].first < states_) {
        ++linear;
        compiled.linear_state = factors[0].first;
        compiled.linear_coefficient = coefficient;
      }
    }
    if (linear != 1 || linear + constant != compiled.terms.size()) compiled.linear_state = -1;
  }
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

double CompiledModel::argument(std::size_t k, const double* y, const double* u) const {
  double sum = 0;
  for (const auto& [coefficient, factors] : functions_[k].terms) {
    double product = coefficient;
    for (const auto& [v, power] : factors) {
      const double x = v < states_ ? y[v] : u[v - states_];
      for (int i = 0; i < power; ++i) product *= x;
    }
    sum += product;
  }
  return sum;
}

double CompiledModel::argument_rate(std::size_t k, const double* y, const double* u,
                                    const double* dydt) const {
  double sum = 0;
  for (const auto& [coefficient, factors] : functions_[k].terms) {
    // The product rule over the term's state factors.
    for (std::size_t d = 0; d < factors.size(); ++d) {
      if (factors[d].first >= states_) continue;
      double product = coefficient * factors[d].second * dydt[factors[d].first];
      for (std::size_t f = 0; f < factors.size(); ++f) {
        const auto [v, power] = factors[f];
        const double x = v < states_ ? y[v] : u[v - states_];
        for (int i = 0; i < power - (f == d ? 1 : 0); ++i) product *= x;
      }
      sum += product;
    }
  }
  return sum;
}

void CompiledModel::project(std::size_t k, double* y, const double* u) const {
  const Function& f = functions_[k];
  if (f.linear_state >= 0) y[f.linear_state] -= argument(k, y, u) / f.linear_coefficient;
}

double CompiledModel::function_value(std::size_t k, const double* y, const double* u) const {
  const Function& f = functions_[k];
  if (f.sign && !std::isnan(f.mode)) return f.mode;
  const double p = argument(k, y, u);
  if (!std::isnan(f.mode)) return f.mode * p;
  if (f.sign) return p > 0 ? 1.0 : p < 0 ? -1.0 : 0.0;
  return std::abs(p);
}

bool CompiledModel::slide(const double* y, const double* u, double* dydt) const {
  // The rates of the sliding arguments are affine in the sliding values sigma: d(sigma) = d0 +
  // G sigma, from the derivatives at sigma = 0 and at each unit vector; d(sigma) = 0 solved.
  const auto q = static_cast<Eigen::Index>(sliding_.size());
  Eigen::VectorXd d0(q);
  Eigen::MatrixXd g(q, q);
  for (std::size_t k : sliding_) set_mode(k, 0);
  if (!smooth_derivative(y, u, dydt)) return false;
  for (Eigen::Index i = 0; i < q; ++i) d0(i) = argument_rate(sliding_[i], y, u, dydt);
  for (Eigen::Index j = 0; j < q; ++j) {
    set_mode(sliding_[static_cast<std::size_t>(j)], 1);
    if (!smooth_derivative(y, u, dydt)) return false;
    for (Eigen::Index i = 0; i < q; ++i) {
      g(i, j) = argument_rate(sliding_[static_cast<std::size_t>(i)], y, u, dydt) - d0(i);
    }
    set_mode(sliding_[static_cast<std::size_t>(j)], 0);
  }
  const Eigen::VectorXd sigma = g.fullPivLu().solve(-d0);
  if (!sigma.allFinite()) return false;
  for (Eigen::Index j = 0; j < q; ++j) set_mode(sliding_[static_cast<std::size_t>(j)], sigma(j));
  return smooth_derivative(y, u, dydt);
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
  const auto count = [&](std::size_t found, std::size_t expected, const std::string& field,
                         const std::string& what) {
    if (found != expected) {
      throw UsageError(field, "model " + model.name() + " needs " + std::to_string(expected) + " " +
                                  what + ", found " + std::to_string(found));
    }
  };
  parameter_vector(model, parameters);  // every name the model's, every parameter with a value
  count(inputs.size(), model.inputs().size(), "inputs", "input processes");
  if (!(std::isfinite(dt) && dt >= kMinStep && dt <= kMaxStep)) {
    throw UsageError("dt", "expected a number from 1e-9 to 1e6, found " + shortest_decimal(dt));
  }
  if (samples == 0) throw UsageError("samples", "expected at least 1, found 0");
  if (runs == 0) throw UsageError("runs", "expected at least 1, found 0");
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    inputs[i].validate(UsageError::mention("inputs") + " " + model.inputs()[i].name, dt);
  }
  const std::vector<std::string> channels = model.channel_names();
  // The index of channel `name`, or a UsageError from `option` listing the channels.
  const auto channel = [&](const std::string& name, const std::string& option) {
    const auto it = std::find(channels.begin(), channels.end(), name);
    if (it == channels.end()) {
      throw UsageError(option, "'" + name + "' is not a channel of model " + model.name() +
                                   " (channels: " + join(channels, ", ") + ")");
    }
    return static_cast<std::size_t>(it - channels.begin());
  };
  std::vector<bool> observed(channels.size(), observe.empty());
  for (const std::string& name : observe) {
    const std::size_t c = channel(name, "observe");
    if (observed[c]) throw UsageError("observe", "channel '" + name + "' is given twice");
    observed[c] = true;
  }
  // A derivative of a state that a held input drives jumps at every sample: the record could
  // not be averaged over its intervals.
  for (std::size_t i = 0; i < model.measured_derivatives().size(); ++i) {
    const MeasuredDerivative& d = model.measured_derivatives()[i];
    const std::size_t c = model.states().size() + model.inputs().size() + i;
    for (std::size_t k = 0; k < inputs.size() && observed[c]; ++k) {
      if (!inputs[k].held()) continue;
      const std::string& input = model.inputs()[k].name;
      std::vector<std::string> others;
      for (std::size_t o = 0; o < channels.size(); ++o) {
        if (o != c && observed[o]) others.push_back(channels[o]);
      }
      throw UsageError("inputs", "the measured column '" + d.name + "' (" + d.written +
                                     ") would jump at every sample of the held input " + input +
                                     ": give " + input + " a smooth process (" + input +
                                     "=multisine:f1=F1,f2=F2,lines=L) or leave the column out (" +
                                     UsageError::mention("observe") + " " + join(others, ",") +
                                     ")");
    }
  }
  std::vector<bool> noisy(channels.size(), false);
  for (const ChannelNoise& n : noise) {
    const std::size_t c = channel(n.channel, "noise");
    if (noisy[c]) throw UsageError("noise", "channel '" + n.channel + "' is given twice");
    noisy[c] = true;
    if (!(std::isfinite(n.relative) && n.relative >= 0)) {
      throw UsageError("noise", "the level of '" + n.channel +
                                    "' must be a finite number of at least 0, found " +
                                    shortest_decimal(n.relative));
    }
    if (!observed[c]) {
      throw UsageError("noise", "channel '" + n.channel + "' is not observed (" +
                                    UsageError::mention("observe") + " " + join(observe, ",") +
                                    ")");
    }
  }
}

std::vector<ChannelNoise> parse_noise(const std::vector<std::string>& items) {
  std::vector<ChannelNoise> out;
  for (const std::string& item : items) {
    const std::size_t eq = item.find('=');
    if (eq == std::string::npos) {
      throw UsageError("noise", "expected CHANNEL=LEVEL, found '" + item + "'");
    }
    ChannelNoise n{item.substr(0, eq), 0};
    const std::string text = item.substr(eq + 1);
    const char* end = text.data() + text.size();
    const auto result = std::from_chars(text.data(), end, n.relative);
    if (text.empty() || result.ec != std::errc() || result.ptr != end) {
      throw UsageError("noise",
                       "the level of '" + n.channel + "' must be a number, found '" + text + "'");
    }
    out.push_back(std::move(n));
  }
  return out;
}

namespace {

// The clean simulation: every channel as the model produces it.
void simulate_clean(const Model& model, const SimulationOptions& options, SampleSink& sink) {
  const std::vector<numeric> parameters = parameter_vector(model, options.parameters);
  const CompiledModel f(model, parameters);
  const std::size_t n = static_cast<std::size_t>(f.states());
  const std::size_t m = static_cast<std::size_t>(f.inputs());
  std::vector<InputProcess> inputs;
  bool smooth = false;  // some input is evaluated at each stage rather than held
  for (std::size_t i = 0; i < m; ++i) {
    inputs.emplace_back(options.inputs[i], options.dt, options.seed, i);
    smooth = smooth || !options.inputs[i].held();
  }
  SwitchingStep step(f);
  // A row: the states, the inputs, then the columns that measure derivatives.
  std::vector<double> values(model.channel_count());
  double* y = values.data();
  double* u = values.data() + n;
  std::vector<double> rates(model.measured_derivatives().empty() ? 0 : n);
  // The inputs at the middle and the end of the step: the held values unless an input is smooth.
  std::vector<double> middle(m), end(m);
  const double* u_middle = smooth ? middle.data() : u;
  const double* u_end = smooth ? end.data() : u;
  const double h = options.dt;
  std::size_t run = 0;
  double t = 0;
  bool burning_in = false, started = false;

  const auto fail = [&](const std::string& what) {
    const std::string when =
        burning_in ? "during the burn-in of run " + std::to_string(run + 1)
                   : "at t = " + shortest_decimal(t) + " in run " + std::to_string(run + 1);
    throw Error("the simulation " + what + " " + when + " with " +
                parameter_list(model, parameters) +
                ": the model is unstable for these values, or the step dt is too large");
  };
  // One Runge-Kutta step from t to t + h.
  const auto integrate = [&] {
    if (!started && !step.start(y, u)) {
      fail("met a point where the derivatives cannot be solved for");
    }
    started = true;
    if (!step(y, u, u_middle, u_end, h)) {
      fail("met a point where the derivatives cannot be solved for");
    }
    const int blown = step.blown_up(y);
    if (blown >= 0) {
      t += h;
      fail("blew up: state '" + model.states()[static_cast<std::size_t>(blown)].name +
           "' reached " + shortest_decimal(y[blown]));
    }
  };
  const auto draw_inputs = [&] {
    for (std::size_t i = 0; i < m; ++i) u[i] = inputs[i].next();
    if (!smooth) return;
    for (std::size_t i = 0; i < m; ++i) {
      const bool held = options.inputs[i].held();
      middle[i] = held ? u[i] : inputs[i].middle();
      end[i] = held ? u[i] : inputs[i].end();
    }
  };

  for (run = 0; run < options.runs; ++run) {
    if (run == 0 || !options.continue_runs) {
      std::fill(y, y + n, 0.0);
      started = false;
      for (InputProcess& input : inputs) input.start_record(options.burn_in);
      burning_in = true;
      for (std::size_t s = 0; s < options.burn_in; ++s) {
        draw_inputs();
        integrate();
      }
      burning_in = false;
    }
    // Row s: the state at t_s and the input held over [t_s, t_s+1) or, smooth, at t_s.
    for (std::size_t s = 0; s < options.samples; ++s) {
      t = static_cast<double>(s) * h;
      draw_inputs();
      if (!rates.empty()) {
        if (!f.derivative(y, u, rates.data())) {
          fail("met a point where the derivatives cannot be solved for");
        }
        for (std::size_t i = 0; i < model.measured_derivatives().size(); ++i) {
          const auto state = static_cast<std::size_t>(model.measured_derivatives()[i].state);
          values[n + m + i] = rates[state];
        }
      }
      sink.sample(t, values.data(), run);
      integrate();
    }
  }
}

// The channel index of each noise entry.
std::vector<std::size_t> noise_channels(const Model& model, const SimulationOptions& options) {
  std::vector<std::size_t> out;
  for (const ChannelNoise& n : options.noise) {
    out.push_back(static_cast<std::size_t>(model.variable_index(n.channel)));
  }
  return out;
}

// Accumulates the mean and variance of some channels over the samples (Welford's update, which
// keeps its accuracy when the mean is large compared with the spread).
class ChannelSpread : public SampleSink {
 public:
  explicit ChannelSpread(std::vector<std::size_t> channels)
      : channels_(std::move(channels)), mean_(channels_.size()), squares_(channels_.size()) {}
  void sample(double, const double* values, std::size_t) override {
    ++count_;
    const double weight = 1 / static_cast<double>(count_);
    for (std::size_t k = 0; k < channels_.size(); ++k) {
      const double x = values[channels_[k]];
      const double before = x - mean_[k];
      mean_[k] += before * weight;
      squares_[k] += before * (x - mean_[k]);
    }
  }
  // Divided by the number of samples.
  double standard_deviation(std::size_t k) const {
    return std::sqrt(squares_[k] / static_cast<double>(count_));
  }

 private:
  std::vector<std::size_t> channels_;
  std::vector<double> mean_, squares_;
  std::size_t count_ = 0;
};

// Adds white Gaussian noise to some channels and passes the samples on.
class NoisySamples : public SampleSink {
 public:
  NoisySamples(SampleSink& out, std::size_t values, const std::vector<std::size_t>& channels,
               const std::vector<double>& sd, std::uint64_t seed)
      : out_(out), noisy_(values) {
    for (std::size_t k = 0; k < channels.size(); ++k) {
      if (!(sd[k] > 0)) continue;
      channels_.push_back(channels[k]);
      sd_.push_back(sd[k]);
      random_.emplace_back(seed, SimulationOptions::kNoiseStream + channels[k]);
    }
  }
  void sample(double t, const double* values, std::size_t run) override {
    std::copy(values, values + noisy_.size(), noisy_.begin());
    for (std::size_t k = 0; k < channels_.size(); ++k) {
      noisy_[channels_[k]] += sd_[k] * random_[k].normal();
    }
    out_.sample(t, noisy_.data(), run);
  }

 private:
  SampleSink& out_;
  std::vector<double> noisy_;
  std::vector<std::size_t> channels_;
  std::vector<double> sd_;
  std::vector<PortableRandom> random_;
};

}  // namespace

std::vector<double> noise_standard_deviations(const Model& model,
                                              const SimulationOptions& options) {
  options.validate(model);
  std::vector<double> out(options.noise.size(), 0.0);
  bool needed = false;
  for (const ChannelNoise& n : options.noise) needed = needed || n.relative > 0;
  if (!needed) return out;
  ChannelSpread spread(noise_channels(model, options));
  simulate_clean(model, options, spread);
  for (std::size_t k = 0; k < out.size(); ++k) {
    out[k] = options.noise[k].relative * spread.standard_deviation(k);
  }
  return out;
}

void simulate(const Model& model, const SimulationOptions& options, SampleSink& sink,
              const std::vector<double>& noise_sd) {
  const AlgebraLock lock;
  options.validate(model);
  if (noise_sd.size() != options.noise.size()) {
    throw std::invalid_argument("simulate: one noise standard deviation per noise entry needed");
  }
  if (options.noise.empty()) return simulate_clean(model, options, sink);
  NoisySamples noisy(sink, model.channel_count(), noise_channels(model, options), noise_sd,
                     options.seed);
  simulate_clean(model, options, noisy);
}

void simulate(const Model& model, const SimulationOptions& options, SampleSink& sink) {
  const AlgebraLock lock;
  simulate(model, options, sink, noise_standard_deviations(model, options));
}

DataMetadata simulation_metadata(const Model& model, const SimulationOptions& options,
                                 const std::vector<double>& noise_sd) {
  if (noise_sd.size() != options.noise.size()) {
    throw std::invalid_argument(
        "simulation_metadata: one noise standard deviation per noise entry needed");
  }
  std::size_t held = 0;
  for (const InputSpec& input : options.inputs) held += input.held() ? 1 : 0;
  const bool mixed = held != 0 && held != options.inputs.size();
  const std::string hold = held == options.inputs.size() ? to_string(InputHold::kZeroOrderHold)
                           : held == 0                   ? to_string(InputHold::kSample)
                                                         : "mixed";
  DataMetadata::Line first{{"model", model.name()},
                           {"dt", shortest_decimal(options.dt)},
                           {"input-hold", hold},
                           {"seed", std::to_string(options.seed)},
                           {"samples", std::to_string(options.samples)},
                           {"runs", std::to_string(options.runs)},
                           {"burn-in", std::to_string(options.burn_in)},
                           {"continue", options.continue_runs ? "yes" : "no"}};
  if (!options.observe.empty()) first.emplace_back("observe", join(options.observe, ","));
  DataMetadata metadata;
  metadata.add_line(std::move(first));
  DataMetadata::Line parameters;
  const std::vector<numeric> values = parameter_vector(model, options.parameters);
  for (std::size_t p = 0; p < values.size(); ++p) {
    parameters.emplace_back("param." + model.parameters()[p].name,
                            shortest_decimal(values[p].to_double()));
  }
  metadata.add_line(std::move(parameters));
  for (std::size_t i = 0; i < options.inputs.size(); ++i) {
    const std::string& name = model.inputs()[i].name;
    DataMetadata::Line line{{"input." + name, options.inputs[i].text()}};
    if (mixed)
      line.emplace_back(
          "input-hold." + name,
          to_string(options.inputs[i].held() ? InputHold::kZeroOrderHold : InputHold::kSample));
    metadata.add_line(std::move(line));
  }
  // The columns of derivatives, so that a model without the `measured` statement reads them.
  DataMetadata::Line measured;
  for (const MeasuredDerivative& d : model.measured_derivatives()) {
    if (options.observe.empty() || std::find(options.observe.begin(), options.observe.end(),
                                             d.name) != options.observe.end()) {
      measured.emplace_back("measured." + d.name, d.written);
    }
  }
  if (!measured.empty()) metadata.add_line(std::move(measured));
  if (!options.noise.empty()) {
    DataMetadata::Line noise;
    for (std::size_t k = 0; k < options.noise.size(); ++k) {
      const std::string& name = options.noise[k].channel;
      noise.emplace_back("noise." + name, shortest_decimal(options.noise[k].relative));
      noise.emplace_back("noise-sd." + name, shortest_decimal(noise_sd[k]));
    }
    metadata.add_line(std::move(noise));
  }
  return metadata;
}

std::vector<std::size_t> observed_channels(const Model& model, const SimulationOptions& options) {
  std::vector<std::size_t> channels;
  if (options.observe.empty()) {
    for (std::size_t c = 0; c < model.channel_count(); ++c) channels.push_back(c);
  } else {
    for (const std::string& name : options.observe) {
      channels.push_back(static_cast<std::size_t>(model.variable_index(name)));
    }
  }
  return channels;
}

std::vector<std::string> simulate_to_file(const Model& model, const SimulationOptions& options,
                                          const std::string& path, DataWriter::Format format) {
  const AlgebraLock lock;
  options.validate(model);
  const std::vector<double> noise_sd = noise_standard_deviations(model, options);
  const std::vector<std::size_t> channels = observed_channels(model, options);
  std::vector<std::string> columns{"t"};
  for (std::size_t c : channels) columns.push_back(model.variables()[c].name);
  const bool with_run = options.runs > 1;
  if (with_run) columns.push_back("run");
  DataWriter out(path, format, simulation_metadata(model, options, noise_sd), columns,
                 options.samples * options.runs);
  SampleRows rows(out, std::move(channels), with_run);
  StepCheck check(model, options, rows);
  simulate(model, options, check, noise_sd);
  out.commit();
  std::vector<std::string> warnings;
  if (auto w = check.warning()) warnings.push_back(std::move(*w));
  if (auto note = out.note()) warnings.push_back(std::move(*note));
  return warnings;
}

StepCheck::StepCheck(const Model& model, const SimulationOptions& options, SampleSink& next)
    : f_(model, parameter_vector(model, options.parameters)),
      next_(next),
      dt_(options.dt),
      stride_(std::max<std::size_t>(1, options.samples * options.runs / kPoints)) {}

void StepCheck::sample(double t, const double* values, std::size_t run) {
  next_.sample(t, values, run);
  if (seen_++ % stride_ != 0) return;
  const int n = f_.states();
  std::vector<double> y(values, values + n), plus(static_cast<std::size_t>(n)),
      minus(static_cast<std::size_t>(n));
  const double* u = values + n;
  // The dynamics on the side of each switch where the sample is: sign(p) is constant there.
  for (std::size_t k = 0; k < f_.functions(); ++k) {
    f_.set_mode(k, f_.argument(k, values, u) < 0 ? -1.0 : 1.0);
  }
  Eigen::MatrixXd jacobian(n, n);
  for (int j = 0; j < n; ++j) {
    // The central difference's error (h^2) and rounding (eps/h) balance near eps^(1/3).
    const double h = 6e-6 * std::max(1.0, std::abs(values[j]));
    y[static_cast<std::size_t>(j)] = values[j] + h;
    const bool up = f_.derivative(y.data(), u, plus.data());
    y[static_cast<std::size_t>(j)] = values[j] - h;
    const bool down = f_.derivative(y.data(), u, minus.data());
    y[static_cast<std::size_t>(j)] = values[j];
    if (!up || !down) return;
    for (int i = 0; i < n; ++i) {
      jacobian(i, j) =
          (plus[static_cast<std::size_t>(i)] - minus[static_cast<std::size_t>(i)]) / (2 * h);
    }
  }
  if (!jacobian.allFinite()) return;
  const double modulus =
      Eigen::EigenSolver<Eigen::MatrixXd>(jacobian, false).eigenvalues().cwiseAbs().maxCoeff();
  if (modulus * dt_ > largest_) {
    largest_ = modulus * dt_;
    largest_t_ = t;
    largest_run_ = run;
  }
}

std::optional<std::string> StepCheck::warning() const {
  if (!(largest_ > kLimit)) return std::nullopt;
  char when[32], text[64];
  // A step that puts |lambda| dt at 0.25, rounded down to one significant digit.
  const double wanted = 0.25 * dt_ / largest_;
  const double unit = std::pow(10.0, std::floor(std::log10(wanted)));
  std::snprintf(when, sizeof when, "%.6g", largest_t_);
  std::snprintf(text, sizeof text, "%.3g (|lambda| dt = %.2f)", largest_ / dt_, largest_);
  return std::string("the step is coarse for the model's dynamics: linearised at t = ") + when +
         " in run " + std::to_string(largest_run_ + 1) +
         ", the model has an eigenvalue of modulus " + text +
         "; fourth-order Runge-Kutta is accurate for |lambda| dt well below 1 and unstable "
         "beyond 2.8: use --dt " +
         shortest_decimal(std::floor(wanted / unit) * unit) + " or smaller";
}

}  // namespace momentid
