// The momentid command line: maps options to library calls and prints. Exit status: 0 success,
// 1 usage error, 2 bad model or data, 3 nothing identifiable.

#include <CLI/CLI.hpp>
#include <iostream>

#include "data/writer.hpp"
#include "derive/moment_system.hpp"
#include "model/model.hpp"
#include "simulate/simulate.hpp"

namespace {

constexpr int kNothingIdentifiable = 3;

struct DeriveCommand {
  std::string model;
  std::string multipliers;
  int degree = 0;
  std::string format = "text";
};

int run_derive(const DeriveCommand& command) {
  const momentid::Model model = momentid::parse_model_file(command.model);
  momentid::DeriveOptions options;
  if (!command.multipliers.empty()) {
    options.multipliers =
        momentid::parse_multiplier_list(model, command.multipliers, "--multipliers");
  }
  options.degree = command.degree;
  const momentid::MomentSystem system = momentid::derive(model, options);
  if (command.format == "latex") {
    std::cout << momentid::format_latex(system);
  } else if (command.format == "json") {
    std::cout << momentid::format_json(system);
  } else {
    std::cout << momentid::format_text(system);
  }
  if (system.equations.empty()) {
    std::cerr << "momentid: no moment equation could be derived for " << command.model << "\n";
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
        throw momentid::UsageError("--input: with several inputs write NAME=SPEC, found '" +
                                   text + "'");
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

// Writes the simulated samples as rows t, states, inputs[, run].
class RowWriter : public momentid::SampleSink {
 public:
  RowWriter(momentid::DataWriter& out, std::size_t values, bool with_run)
      : out_(out), row_(values + 1 + (with_run ? 1 : 0)), with_run_(with_run) {}
  void sample(double t, const double* values, std::size_t run) override {
    row_[0] = t;
    std::copy(values, values + (row_.size() - 1 - (with_run_ ? 1 : 0)), row_.begin() + 1);
    if (with_run_) row_.back() = static_cast<double>(run + 1);
    out_.row(row_.data());
  }

 private:
  momentid::DataWriter& out_;
  std::vector<double> row_;
  bool with_run_;
};

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

  std::vector<std::string> metadata;
  metadata.push_back("# momentid: model=" + model.name() +
                     " dt=" + momentid::shortest_decimal(options.dt) +
                     " input-hold=zoh seed=" + std::to_string(options.seed) +
                     " samples=" + std::to_string(options.samples) +
                     " runs=" + std::to_string(options.runs) +
                     " burn-in=" + std::to_string(options.burn_in) +
                     " continue=" + (options.continue_runs ? "yes" : "no"));
  std::string parameters = "# momentid:";
  for (std::size_t p = 0; p < options.parameters.size(); ++p) {
    parameters += " param." + model.parameters()[p].name + "=" +
                  momentid::shortest_decimal(options.parameters[p].to_double());
  }
  metadata.push_back(parameters);
  for (std::size_t i = 0; i < options.inputs.size(); ++i) {
    metadata.push_back("# momentid: input." + model.inputs()[i].name + "=" +
                       options.inputs[i].text());
  }
  std::vector<std::string> columns{"t"};
  for (const std::string& v : model.variables()) columns.push_back(v);
  const bool with_run = options.runs > 1;
  if (with_run) columns.push_back("run");

  momentid::DataWriter out(command.output,
                           command.format == "bin" ? momentid::DataWriter::Format::kBinary
                                                   : momentid::DataWriter::Format::kCsv,
                           metadata, columns);
  RowWriter rows(out, model.variables().size(), with_run);
  momentid::simulate(model, options, rows);
  out.commit();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
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
      ->check(CLI::PositiveNumber);
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

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int status = app.exit(e);
    return status == 0 ? 0 : 1;
  }

  try {
    if (derive_app->parsed()) return run_derive(derive);
    if (simulate_app->parsed()) return run_simulate(simulate);
  } catch (const momentid::LocatedError& e) {
    std::cerr << momentid::render_with_caret(e) << "\n";
    return e.exit_code();
  } catch (const momentid::Error& e) {
    std::cerr << "momentid: " << e.what() << "\n";
    return e.exit_code();
  }
  return 0;
}
