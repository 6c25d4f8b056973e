// momentid identify MODEL DATA [options]

#include "momentid/identify.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <iostream>
#include <memory>

#include "cli/commands.hpp"
#include "cli/progress.hpp"
#include "momentid/model.hpp"
#include "momentid/simulate.hpp"
#include "momentid/writer.hpp"

namespace momentid::cli {
namespace {

struct IdentifyCommand {
  std::string model;
  std::vector<std::string> data;
  bool quiet = false;
  std::optional<std::string> multipliers;
  IdentifyOptions options;
  std::string hold;
  std::string weighting = to_string(Weighting::kAuto);
  std::string method = to_string(Method::kAuto);
  std::string extrapolate;
  std::string format = "text";
  std::vector<std::string> columns;
  std::optional<std::string> lags;
  std::optional<std::string> instruments;
  std::string noise = "auto";
  std::vector<std::string> center;
  std::vector<std::string> fix;
};

// `--noise auto|none|NAME=VARIANCE,...`.
std::optional<std::map<std::string, double>> noise_option(const Model& model,
                                                          const std::string& text) {
  if (text == "auto") return std::nullopt;
  std::map<std::string, double> out;
  if (text == "none") return out;
  for (const auto& item : column_map_of(text, "--noise", "NAME=VARIANCE")) {
    // Named, not bound: clang 14 lets no lambda capture a structured binding.
    const std::string& name = item.first;
    const std::string& value = item.second;
    const auto& states = model.states();
    if (std::none_of(states.begin(), states.end(), [&](const auto& d) { return d.name == name; })) {
      throw UsageError("--noise: '" + name + "' is not a state of model " + model.name());
    }
    double variance = 0;
    const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), variance);
    if (error != std::errc() || end != value.data() + value.size() || !std::isfinite(variance) ||
        variance < 0) {
      throw UsageError("--noise: expected a variance of at least 0 for '" + name + "', found '" +
                       value + "'");
    }
    out[name] = variance;
  }
  return out;
}

int run_identify(IdentifyCommand& command) {
  IdentifyOptions& options = command.options;
  options.record.columns = column_map(command.columns);
  const Model file = model_argument(command.model, command.data.front(), "identify MODEL DATA...");
  // Once: a pipe or standard input is read whole into a file of its own.
  const DataSource source = data_sources(command.data);
  const Model model = declare_derivative_columns(file, options.record, source);
  if (command.multipliers) {
    options.multipliers = parse_multiplier_list(model, *command.multipliers, "--multipliers");
  }
  options.record.hold = hold_option(command.hold);
  options.weighting = parse_weighting(command.weighting, "weighting");
  options.method = parse_method(command.method, "method");
  options.extrapolate = command.extrapolate == "dt";
  if (command.lags) options.lags = lag_range(*command.lags);
  options.noise = noise_option(model, command.noise);
  if (command.instruments) {
    options.instruments = parse_instrument_list(model, *command.instruments, "--instruments");
  }
  // --fix k=9,...: the values read as --set reads them, exact decimals rounded once (the
  // parameters not fixed at 0, so that none lacks a value).
  const ParameterValues fixed = parse_parameter_values(model, command.fix, "fixed");
  ParameterValues every;
  for (const Declaration& p : model.parameters()) every[p.name] = 0.0;
  for (const auto& entry : fixed) every[entry.first] = entry.second;
  const std::vector<GiNaC::numeric> values = parameter_vector(model, every, "fixed");
  for (const auto& entry : fixed) {
    const auto index = static_cast<std::size_t>(model.parameter_index(entry.first));
    options.fixed[entry.first] = values[index].to_double();
  }
  if (command.center.size() == 1 && command.center[0] == "all") {
    options.center = model.channel_names();
  } else {
    options.center = command.center;
  }
  TerminalProgress progress(!command.quiet && command.format != "json");
  options.record.control.progress = progress.callback();
  const IdentifyResult result = identify(model, source, options);
  progress.finish();
  write_whole_file("-", command.format == "json" ? format_json(result) : format_text(result));
  if (result.estimate.status == Status::kNothingIdentifiable) {
    std::cerr << "momentid: nothing identifiable: " << result.estimate.message << "\n";
    return kNothingIdentifiable;
  }
  return 0;
}

}  // namespace

Command add_identify(CLI::App& app) {
  auto command = std::make_shared<IdentifyCommand>();
  IdentifyOptions& options = command->options;
  CLI::App* sub = app.add_subcommand(
      "identify", "estimate the parameters of a model from data, with standard errors");
  sub->add_option("MODEL", command->model, "model file")->required();
  sub->add_option("DATA", command->data,
                  "data files (CSV, binary, .npy, .mat, HDF5), glob patterns or @LIST files "
                  "naming one per line, each file its own runs; - for standard input")
      ->required();
  auto* multipliers =
      sub->add_option("--multipliers", command->multipliers, "multipliers, as for derive");
  sub->add_option("--degree", options.degree, "multipliers up to this degree")
      ->check(CLI::Range(1, IdentifyOptions::kMaxDegree))
      ->excludes(multipliers);
  sub->add_option("--input-hold", command->hold,
                  "how the inputs were sampled (default: the file's metadata, else sample)")
      ->check(CLI::IsMember(names_of<InputHold>()));
  sub->add_option("--batches", options.batches,
                  "batches for the standard errors (default one per 200 samples, 100 to 1000, and "
                  "at least 4 per equation for the optimal weighting)")
      ->check(CLI::Range(IdentifyOptions::kMinBatches, IdentifyOptions::kMaxBatches));
  sub->add_option("--method", command->method,
                  "zero-lag, lagged, or auto: lagged for measured records (unbiased under white "
                  "sensor noise), zero-lag for records simulated without noise")
      ->check(CLI::IsMember(names_of<Method>()));
  sub->add_option("--weighting", command->weighting,
                  "ls (least squares), gmm (two-step optimal, with the J test), or auto: gmm "
                  "when the equations outnumber the parameters")
      ->check(CLI::IsMember(names_of<Weighting>()));
  sub->add_option("--format", command->format, "output format")
      ->check(CLI::IsMember({"text", "json"}));
  sub->add_option("--columns", command->columns, "NAME=COLUMN: where a model variable is");
  sub->add_option("--input-shift", options.input_shift,
                  "pair input row n with state row n + k (delayed measurements)")
      ->check(CLI::Range(-IdentifyOptions::kMaxInputShift, IdentifyOptions::kMaxInputShift));
  sub->add_option("--lags", command->lags,
                  "lagged moment equations at lags FIRST..LAST samples, e.g. 3..40 (the default "
                  "when the data lack a state that a kinematic equation defines)")
      ->excludes(multipliers);
  sub->add_option("--instruments", command->instruments,
                  "instruments for the lagged equations, e.g. \"y, y^3\"");
  sub->add_option("--noise", command->noise,
                  "white sensor noise on the states for the lagged equations: auto (estimated), "
                  "none, or NAME=VARIANCE,...");
  sub->add_option("--dt", options.record.dt,
                  "sample interval, overriding the data's: the time column is then not read")
      ->check(CLI::PositiveNumber);
  sub->add_option("--fix", command->fix,
                  "parameters taken as known, NAME=VALUE,...: their terms move to the right-hand "
                  "side")
      ->delimiter(',');
  sub->add_option("--integrate", options.integrate,
                  "form these states (NAME,...) from the column of their derivative, for a record "
                  "without them: integrated in the pass inside a high-pass filter on every channel")
      ->delimiter(',');
  sub->add_option("--integrate-corner", options.integrate_corner,
                  "the corner of --integrate's high-pass filter, Hz (default: half the lower edge "
                  "of the record's band)");
  sub->add_option("--center", command->center,
                  "remove the means of these channels (NAME,... or all) before forming the "
                  "moments: a sensor offset on a symmetric system")
      ->delimiter(',');
  sub->add_option("--extrapolate", command->extrapolate,
                  "dt: estimate the bias of sampling from every other sample, and remove it when "
                  "it exceeds its error (zero-lag equations, inputs sampled, not held)")
      ->check(CLI::IsMember({"dt"}));
  add_layout_options(sub, options.record.layout);
  add_pass_options(sub, options.record.control);
  sub->add_flag("-q,--quiet", command->quiet,
                "no progress on standard error (shown only on a terminal, never with JSON)");
  return {sub, [command] { return run_identify(*command); }};
}

}  // namespace momentid::cli
