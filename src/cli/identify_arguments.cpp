#include "cli/identify_arguments.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "momentid/simulate.hpp"

namespace momentid::cli {
namespace {

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

}  // namespace

IdentifyInputs read_identify_arguments(IdentifyArguments& a, const std::string& usage) {
  IdentifyOptions& options = a.options;
  options.record.columns = column_map(a.columns);
  const Model file = model_argument(a.model, a.data.front(), usage);
  // Once: a pipe or standard input is read whole into a file of its own.
  DataSource source = data_sources(a.data);
  Model model = declare_derivative_columns(file, options.record, source);
  options.record.hold = hold_option(a.hold);
  if (a.lags) options.lags = lag_range(*a.lags);
  options.noise = noise_option(model, a.noise);
  if (a.instruments) {
    options.instruments = parse_instrument_list(model, *a.instruments, "--instruments");
  }
  // --fix k=9,...: the values read as --set reads them, exact decimals rounded once (the
  // parameters not fixed at 0, so that none lacks a value).
  const ParameterValues fixed = parse_parameter_values(model, a.fix, "fixed");
  ParameterValues every;
  for (const Declaration& p : model.parameters()) every[p.name] = 0.0;
  for (const auto& entry : fixed) every[entry.first] = entry.second;
  const std::vector<GiNaC::numeric> values = parameter_vector(model, every, "fixed");
  for (const auto& entry : fixed) {
    const auto index = static_cast<std::size_t>(model.parameter_index(entry.first));
    options.fixed[entry.first] = values[index].to_double();
  }
  if (a.center.size() == 1 && a.center[0] == "all") {
    options.center = model.channel_names();
  } else {
    options.center = a.center;
  }
  return {std::move(model), std::move(source)};
}

CLI::Option* add_identify_arguments(CLI::App* sub, IdentifyArguments& a) {
  IdentifyOptions& options = a.options;
  sub->add_option("MODEL", a.model, "model file")->required();
  sub->add_option("DATA", a.data,
                  "data files (CSV, binary, .npy, .mat, HDF5), glob patterns or @LIST files "
                  "naming one per line, each file its own runs; - for standard input")
      ->required();
  sub->add_option("--input-hold", a.hold,
                  "how the inputs were sampled (default: the file's metadata, else sample)")
      ->check(CLI::IsMember(names_of<InputHold>()));
  sub->add_option("--batches", options.batches,
                  "batches for the standard errors (default one per 200 samples, 100 to 1000, and "
                  "at least 4 per equation for the optimal weighting)")
      ->check(CLI::Range(IdentifyOptions::kMinBatches, IdentifyOptions::kMaxBatches));
  sub->add_option("--format", a.format, "output format")->check(CLI::IsMember({"text", "json"}));
  sub->add_option("--columns", a.columns, "NAME=COLUMN: where a model variable is");
  sub->add_option("--input-shift", options.input_shift,
                  "pair input row n with state row n + k (delayed measurements)")
      ->check(CLI::Range(-IdentifyOptions::kMaxInputShift, IdentifyOptions::kMaxInputShift));
  CLI::Option* lags = sub->add_option(
      "--lags", a.lags,
      "lagged moment equations at lags FIRST..LAST samples, e.g. 3..40 (the default "
      "when the data lack a state that a kinematic equation defines)");
  sub->add_option("--instruments", a.instruments,
                  "instruments for the lagged equations, e.g. \"y, y^3\"");
  sub->add_option("--noise", a.noise,
                  "white sensor noise on the states for the lagged equations: auto (estimated), "
                  "none, or NAME=VARIANCE,...");
  sub->add_option("--dt", options.record.dt,
                  "sample interval, overriding the data's: the time column is then not read")
      ->check(CLI::PositiveNumber);
  sub->add_option("--fix", a.fix,
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
  sub->add_option("--center", a.center,
                  "remove the means of these channels (NAME,... or all) before forming the "
                  "moments: a sensor offset on a symmetric system")
      ->delimiter(',');
  add_layout_options(sub, options.record.layout);
  add_pass_options(sub, options.record.control);
  sub->add_flag("-q,--quiet", a.quiet,
                "no progress on standard error (shown only on a terminal, never with JSON)");
  return lags;
}

}  // namespace momentid::cli
