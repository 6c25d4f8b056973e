// The momentid command line: maps options to library calls and prints. Exit status: 0 success,
// 1 usage error, 2 bad model or data, 3 nothing identifiable.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <optional>

#include "momentid/data_pass.hpp"
#include "momentid/derive.hpp"
#include "momentid/model.hpp"
#include "momentid/simulate.hpp"
#include "momentid/writer.hpp"
#include "solve/report.hpp"

namespace {

constexpr int kNothingIdentifiable = 3;

struct DeriveCommand {
  std::string model;
  std::optional<std::string> multipliers;
  int degree = 0;
  std::string format = "text";
};

// The moment equations with the multipliers from `--multipliers` or `--degree`.
momentid::MomentSystem derive_with(const momentid::Model& model,
                                   const std::optional<std::string>& multipliers, int degree) {
  momentid::DeriveOptions options;
  if (multipliers) {
    options.multipliers = momentid::parse_multiplier_list(model, *multipliers, "--multipliers");
  }
  options.degree = degree;
  return momentid::derive(model, options);
}

int run_derive(const DeriveCommand& command) {
  const momentid::Model model = momentid::parse_model_file(command.model);
  const momentid::MomentSystem system = derive_with(model, command.multipliers, command.degree);
  if (command.format == "latex") {
    std::cout << momentid::format_latex(system);
  } else if (command.format == "json") {
    std::cout << momentid::format_json(system);
  } else {
    std::cout << momentid::format_text(system);
  }
  if (system.equations.empty()) {
    std::cerr << "momentid: no moment equation could be derived for " << command.model
              << (model.parameters().empty() ? ": the model has no unknown parameters" : "")
              << "\n";
    return kNothingIdentifiable;
  }
  return 0;
}

struct SimulateCommand {
  std::string model;
  std::vector<std::string> set;
  std::vector<std::string> inputs;
  double dt = 0.01;
  std::size_t samples = 10000;
  std::size_t burn_in = 10000;
  std::size_t runs = 1;
  bool continue_runs = false;
  std::uint64_t seed = 1;
  std::string format = "csv";
  std::string output = "-";
};

// One spec per model input: `name=SPEC` entries, or a single SPEC when the model has one input.
std::vector<momentid::InputSpec> input_specs(const momentid::Model& model,
                                             const std::vector<std::string>& given) {
  const auto& inputs = model.inputs();
  std::vector<momentid::InputSpec> specs(inputs.size());
  std::vector<bool> seen(inputs.size(), false);
  for (const std::string& text : given) {
    std::size_t index = inputs.size();
    std::string spec = text;
    const std::size_t eq = text.find('=');
    for (std::size_t i = 0; i < inputs.size() && eq != std::string::npos; ++i) {
      if (text.compare(0, eq, inputs[i].name) == 0 && eq == inputs[i].name.size()) {
        index = i;
        spec = text.substr(eq + 1);
      }
    }
    if (index == inputs.size()) {
      if (inputs.size() != 1) {
        throw momentid::UsageError("--input: with several inputs write NAME=SPEC, found '" + text +
                                   "'");
      }
      index = 0;
    }
    if (seen[index]) {
      throw momentid::UsageError("--input: input '" + inputs[index].name + "' is given twice");
    }
    seen[index] = true;
    specs[index] = momentid::InputSpec::parse(spec, "--input " + inputs[index].name);
  }
  return specs;
}

int run_simulate(const SimulateCommand& command) {
  const momentid::Model model = momentid::parse_model_file(command.model);
  momentid::SimulationOptions options;
  options.parameters = momentid::parameter_values(model, command.set);
  options.inputs = input_specs(model, command.inputs);
  options.dt = command.dt;
  options.samples = command.samples;
  options.burn_in = command.burn_in;
  options.runs = command.runs;
  options.continue_runs = command.continue_runs;
  options.seed = command.seed;

  momentid::simulate_to_file(model, options, command.output,
                             command.format == "bin" ? momentid::DataWriter::Format::kBinary
                                                     : momentid::DataWriter::Format::kCsv);
  return 0;
}

// `--columns v=velocity,x=force`: the model's names mapped to the file's columns.
std::map<std::string, std::string> column_map(const std::vector<std::string>& entries) {
  std::map<std::string, std::string> out;
  for (const std::string& e : entries) {
    const std::size_t eq = e.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == e.size()) {
      throw momentid::UsageError("--columns: expected NAME=COLUMN, found '" + e + "'");
    }
    out[e.substr(0, eq)] = e.substr(eq + 1);
  }
  return out;
}

std::optional<momentid::InputHold> hold_option(const std::string& text) {
  if (text == "zoh") return momentid::InputHold::kZeroOrderHold;
  if (text == "sample") return momentid::InputHold::kSample;
  return std::nullopt;
}

struct IdentifyCommand {
  std::string model;
  std::string data;
  std::optional<std::string> multipliers;
  int degree = 0;
  std::string hold;
  std::size_t batches = 50;
  std::string weighting = "ls";
  std::string format = "text";
  std::vector<std::string> columns;
  long input_shift = 0;
};

int run_identify(const IdentifyCommand& command) {
  const momentid::Model model = momentid::parse_model_file(command.model);
  const momentid::MomentSystem system = derive_with(model, command.multipliers, command.degree);
  for (const auto& column : column_map(command.columns)) {
    const auto& v = model.variables();
    if (std::find(v.begin(), v.end(), column.first) == v.end()) {
      throw momentid::UsageError("--columns: '" + column.first +
                                 "' is not a state or input of model " + model.name());
    }
  }
  momentid::DataOptions data_options;
  data_options.hold = hold_option(command.hold);
  data_options.batches = command.batches;
  data_options.rename = column_map(command.columns);
  data_options.min_rows = 2 * command.batches;
  data_options.input_shift = command.input_shift;
  std::vector<std::string> states, inputs;
  for (const auto& d : model.states()) states.push_back(d.name);
  for (const auto& d : model.inputs()) inputs.push_back(d.name);
  const std::vector<momentid::Monomial> moments = momentid::moments_to_estimate(system);
  const momentid::DataMoments data =
      momentid::moments_from_file(command.data, states, inputs, moments, data_options);
  const momentid::Estimate estimate =
      momentid::solve(system, data.estimates, {.gmm = command.weighting == "gmm"});
  const momentid::IdentifyReport report{
      &model, command.data, &data, &estimate, command.weighting == "gmm", &moments};
  std::cout << (command.format == "json" ? momentid::format_report_json(report)
                                         : momentid::format_report_text(report));
  if (estimate.status == momentid::Estimate::Status::kNothingIdentifiable) {
    std::cerr << "momentid: nothing identifiable: " << estimate.message << "\n";
    return kNothingIdentifiable;
  }
  return 0;
}

struct CheckCommand {
  std::string data;
  std::string model;
  std::size_t lags = 9;
  std::string hold;
  std::vector<std::string> columns;
};

int run_check(const CheckCommand& command) {
  std::optional<momentid::Model> model;
  std::vector<std::string> states, inputs;
  std::vector<std::string> missing_inputs;
  const std::vector<std::string> columns =
      momentid::DataReader::open(command.data, {.names = {}, .rename = {}, .min_rows = 0})
          ->columns();
  if (!command.model.empty()) {
    model = momentid::parse_model_file(command.model);
    for (const auto& d : model->states()) states.push_back(d.name);
    // The statistics of the states and most identities need no input: inputs missing from the
    // file are left out rather than refused.
    const auto renamed = column_map(command.columns);
    for (const auto& d : model->inputs()) {
      const auto it = renamed.find(d.name);
      const std::string column = it == renamed.end() ? d.name : it->second;
      if (std::find(columns.begin(), columns.end(), column) == columns.end()) {
        missing_inputs.push_back(d.name);
      } else {
        inputs.push_back(d.name);
      }
    }
  } else {
    // Without a model every column but t and run is a channel.
    for (const std::string& c : columns) {
      if (!c.empty() && c != "t" && c != "run") states.push_back(c);
    }
  }
  std::optional<momentid::MomentSystem> system;
  std::vector<momentid::Monomial> moments;
  std::vector<momentid::Monomial> full_moments;  // over all the model's variables
  if (model) {
    system = momentid::derive(*model);
    if (!missing_inputs.empty()) inputs.clear();  // then the channels are the states only
    for (const momentid::Monomial& m : momentid::moments_to_estimate(*system)) {
      const auto first_input = m.begin() + static_cast<std::ptrdiff_t>(states.size());
      if (inputs.empty() && std::any_of(first_input, m.end(), [](int e) { return e != 0; })) {
        continue;
      }
      full_moments.push_back(m);
      moments.emplace_back(m.begin(), inputs.empty() ? first_input : m.end());
    }
  }
  momentid::DataOptions options;
  options.lags = command.lags;
  options.hold = hold_option(command.hold);
  options.rename = column_map(command.columns);
  const momentid::DataMoments data =
      momentid::moments_from_file(command.data, states, inputs, moments, options);

  std::printf("data %s: %zu rows in %zu %s", command.data.c_str(), data.rows, data.runs,
              data.runs == 1 ? "run" : "runs");
  if (data.time_step) std::printf(", dt = %g", *data.time_step);
  std::printf("\n\n%-10s %12s %12s  %-*s %s\n", "channel", "mean", "variance",
              static_cast<int>(6 * command.lags), "autocorrelation at lags 1, 2, ...",
              "corr. time");
  for (const momentid::ChannelStatistics& c : data.channels) {
    std::string lags;
    for (double r : c.autocorrelation) {
      char text[16];
      std::snprintf(text, sizeof text, "%5.2f ", r);
      lags += text;
    }
    std::string time = c.correlation_time > command.lags ? "> " + std::to_string(command.lags)
                                                         : std::to_string(c.correlation_time);
    std::printf("%-10s %12.5g %12.5g  %-*s %s\n", c.name.c_str(), c.mean, c.variance,
                static_cast<int>(6 * command.lags), lags.c_str(), time.c_str());
  }
  std::printf("\n");
  const std::vector<std::string> warnings = momentid::smoothness_warnings(data);
  for (const momentid::ChannelStatistics& c : data.channels) {
    if (!c.is_input || c.autocorrelation.empty()) continue;
    if (c.autocorrelation[0] >= 0.5) {
      std::printf(
          "input %s is smooth enough for the moment method (lag-1 autocorrelation "
          "%.3f)\n",
          c.name.c_str(), c.autocorrelation[0]);
    }
  }
  if (model) {
    for (const std::string& name : missing_inputs) {
      std::printf("input %s is not in the file: only the states are checked\n", name.c_str());
    }
    const auto identities = momentid::check_identities(*system, full_moments, data.estimates);
    if (identities.empty()) {
      std::printf("stationarity identities: none to check\n");
    } else {
      std::printf("stationarity identities (sample violation, z-score):\n");
    }
    for (const auto& c : identities) {
      std::printf("  %s: %.3g (z = %.2f)%s\n", c.identity.c_str(), c.violation, c.z,
                  std::abs(c.z) > 4 ? "  <- violated: not stationary, or not this model" : "");
    }
  }
  for (const std::string& w : warnings) std::printf("warning: %s\n", w.c_str());
  return 0;
}

}  // namespace

#if defined(__SANITIZE_ADDRESS__)
// CLN allocates a few bytes at start-up that it never frees; that is not momentid's leak.
extern "C" const char* __lsan_default_suppressions() { return "leak:libcln.so\n"; }
extern "C" const char* __lsan_default_options() { return "print_suppressions=0"; }
#endif

int main(int argc, char** argv) {
  momentid::remove_partial_output_on_interrupt();
  CLI::App app{"momentid: identify the parameters of polynomial ODE models from random data"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "momentid 0.1.0");

  DeriveCommand derive;
  CLI::App* derive_app = app.add_subcommand(
      "derive", "print the moment equations of a model: a linear system in its parameters");
  derive_app->add_option("MODEL", derive.model, "model file")->required();
  auto* multipliers = derive_app->add_option(
      "--multipliers", derive.multipliers,
      "comma-separated monomials in the states to multiply every equation by, e.g. \"y, v, y^3\"");
  derive_app
      ->add_option("--degree", derive.degree,
                   "multiply by every monomial in the states of degree 1..D")
      ->check(CLI::Range(1, 12))
      ->excludes(multipliers);
  derive_app->add_option("--format", derive.format, "output format")
      ->check(CLI::IsMember({"text", "latex", "json"}));

  SimulateCommand simulate;
  CLI::App* simulate_app = app.add_subcommand(
      "simulate", "simulate a model driven by random inputs and write the samples (CSV or binary)");
  simulate_app->add_option("MODEL", simulate.model, "model file")->required();
  simulate_app
      ->add_option("--set", simulate.set,
                   "parameter values NAME=VALUE, overriding the model's nominal values")
      ->delimiter(',');
  simulate_app->add_option(
      "--input", simulate.inputs,
      "input process [NAME=]SPEC: ma:K=10,w=0.1 | ma:weights=[..] | ou:tau=T | white, with "
      "sigma= and mean= (default ma:K=10,w=0.1)");
  simulate_app->add_option("--dt", simulate.dt, "integration and sampling step")
      ->check(CLI::Validator(
          [](const std::string& text) {
            double dt = 0;
            try {
              dt = std::stod(text);
            } catch (const std::exception&) {
              dt = 0;
            }
            return std::isfinite(dt) && dt >= 1e-9 && dt <= 1e6
                       ? std::string()
                       : "expected a number from 1e-9 to 1e6, found '" + text + "'";
          },
          "1e-9 to 1e6"));
  simulate_app->add_option("--samples", simulate.samples, "samples per run")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 40));
  simulate_app->add_option("--burn-in", simulate.burn_in, "steps discarded before each run");
  simulate_app->add_option("--runs", simulate.runs, "number of runs")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 30));
  simulate_app->add_flag("--continue", simulate.continue_runs,
                         "start each run from the previous run's last state");
  simulate_app->add_option("--seed", simulate.seed, "random seed");
  simulate_app->add_option("--format", simulate.format, "output format")
      ->check(CLI::IsMember({"csv", "bin"}));
  simulate_app->add_option("-o,--output", simulate.output, "output file, - for standard output");

  IdentifyCommand identify;
  CLI::App* identify_app = app.add_subcommand(
      "identify", "estimate the parameters of a model from data, with standard errors");
  identify_app->add_option("MODEL", identify.model, "model file")->required();
  identify_app->add_option("DATA", identify.data, "data file (CSV or binary)")->required();
  auto* identify_multipliers =
      identify_app->add_option("--multipliers", identify.multipliers, "multipliers, as for derive");
  identify_app->add_option("--degree", identify.degree, "multipliers up to this degree")
      ->check(CLI::Range(1, 12))
      ->excludes(identify_multipliers);
  identify_app
      ->add_option("--input-hold", identify.hold,
                   "how the inputs were sampled (default: the file's metadata, else sample)")
      ->check(CLI::IsMember({"sample", "zoh"}));
  identify_app->add_option("--batches", identify.batches, "batches for the standard errors")
      ->check(CLI::Range(std::size_t{2}, std::size_t{10000}));
  identify_app->add_option("--weighting", identify.weighting, "ls, or gmm for two-step optimal")
      ->check(CLI::IsMember({"ls", "gmm"}));
  identify_app->add_option("--format", identify.format, "output format")
      ->check(CLI::IsMember({"text", "json"}));
  identify_app->add_option("--columns", identify.columns, "NAME=COLUMN: where a model variable is")
      ->delimiter(',');
  identify_app
      ->add_option("--input-shift", identify.input_shift,
                   "pair input row n with state row n + k (delayed measurements)")
      ->check(CLI::Range(-1000L, 1000L));

  CheckCommand check;
  CLI::App* check_app = app.add_subcommand(
      "check", "statistics of a data file: autocorrelations, smoothness, stationarity");
  check_app->add_option("DATA", check.data, "data file (CSV or binary)")->required();
  check_app->add_option("MODEL", check.model, "model file: check its stationarity identities");
  check_app->add_option("--lags", check.lags, "autocorrelation lags")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1000}));
  check_app->add_option("--input-hold", check.hold, "how the inputs were sampled")
      ->check(CLI::IsMember({"sample", "zoh"}));
  check_app->add_option("--columns", check.columns, "NAME=COLUMN: where a model variable is")
      ->delimiter(',');

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int status = app.exit(e);
    return status == 0 ? 0 : 1;
  }

  try {
    if (derive_app->parsed()) return run_derive(derive);
    if (simulate_app->parsed()) return run_simulate(simulate);
    if (identify_app->parsed()) return run_identify(identify);
    if (check_app->parsed()) return run_check(check);
  } catch (const momentid::LocatedError& e) {
    std::cerr << momentid::render_with_caret(e) << "\n";
    return e.exit_code();
  } catch (const momentid::Error& e) {
    std::cerr << "momentid: " << momentid::printable(e.what()) << "\n";
    return e.exit_code();
  } catch (const std::exception& e) {
    // Everything momentid checks is reported above; this is a failure it did not foresee.
    std::cerr << "momentid: internal error: " << momentid::printable(e.what()) << "\n";
    return 2;
  }
  return 0;
}
