// momentid simulate MODEL [options] [-o FILE]

#include "momentid/simulate.hpp"

#include <cmath>
#include <iostream>
#include <memory>

#include "cli/commands.hpp"
#include "momentid/convert.hpp"
#include "momentid/model.hpp"
#include "momentid/validate.hpp"

namespace momentid::cli {
namespace {

struct SimulateCommand {
  std::string model;
  std::vector<std::string> set;
  std::vector<std::string> inputs;
  std::vector<std::string> noise;
  SimulationOptions options;
  std::string format = to_string(FileFormat::kCsv);
  std::string output = "-";
  // The response to a recorded input instead.
  std::string input_file;
  std::string interpolation;
  std::vector<std::string> columns;
  std::optional<double> record_dt;
  std::optional<int> substeps;  // --dt with --input-file: overrides the record's interval
};

// One spec per model input: `name=SPEC` entries, or a single SPEC when the model has one input.
std::vector<InputSpec> input_specs(const Model& model, const std::vector<std::string>& given) {
  const auto& inputs = model.inputs();
  std::vector<InputSpec> specs(inputs.size());
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
        throw UsageError("--input: with several inputs write NAME=SPEC, found '" + text + "'");
      }
      index = 0;
    }
    if (seen[index]) {
      throw UsageError("--input: input '" + inputs[index].name + "' is given twice");
    }
    seen[index] = true;
    specs[index] = InputSpec::parse(spec, "--input " + inputs[index].name);
  }
  return specs;
}

int run_simulate(SimulateCommand& command, bool format_given) {
  const Model model = parse_model_file(command.model);
  const FileFormat format = simulation_format(
      command.output,
      format_given ? std::optional(parse_file_format(command.format, "format")) : std::nullopt);
  if (!command.input_file.empty()) {
    ReplayOptions options;
    options.parameters = parse_parameter_values(model, command.set);
    options.record.columns = column_map(command.columns);
    options.record.dt = command.record_dt;
    options.substeps = command.substeps;
    if (!command.interpolation.empty()) {
      options.interpolation = parse_interpolation(command.interpolation, "interpolation");
    }
    for (const std::string& note :
         write_replay(model, replay(model, DataSource::file(command.input_file), options),
                      command.output, format)) {
      std::cerr << "momentid: warning: " << note << "\n";
    }
    return 0;
  }
  command.options.parameters = parse_parameter_values(model, command.set);
  command.options.inputs = input_specs(model, command.inputs);
  command.options.noise = parse_noise(command.noise);
  for (const std::string& warning :
       simulate_to_file(model, command.options, command.output, format)) {
    std::cerr << "momentid: warning: " << warning << "\n";
  }
  return 0;
}

}  // namespace

Command add_simulate(CLI::App& app) {
  auto command = std::make_shared<SimulateCommand>();
  SimulationOptions& options = command->options;
  CLI::App* sub = app.add_subcommand("simulate",
                                     "simulate a model driven by random inputs and write the "
                                     "samples (CSV, binary, .npy, .mat or HDF5)");
  sub->add_option("MODEL", command->model, "model file")->required();
  sub->add_option("--set", command->set,
                  "parameter values NAME=VALUE, overriding the model's nominal values")
      ->delimiter(',');
  auto* input_file = sub->add_option(
      "--input-file", command->input_file,
      "simulate the response to the inputs of this record instead, from its initial state, "
      "and write it in the record's columns");
  sub->add_option("--interpolation", command->interpolation,
                  "with --input-file: the inputs between samples, zoh, foh, cubic or sinc "
                  "(default: zoh for held inputs, sinc otherwise)")
      ->needs(input_file);
  sub->add_option("--substeps", command->substeps,
                  "with --input-file: Runge-Kutta steps per sample interval (default: the fewest "
                  "that change the result by less than 1e-6)")
      ->check(CLI::Range(1, RecordSimulator::kMaxSubsteps))
      ->needs(input_file);
  sub->add_option("--columns", command->columns,
                  "with --input-file: NAME=COLUMN, where a model variable is")
      ->needs(input_file);
  sub->add_option(
      "--input", command->inputs,
      "input process [NAME=]SPEC: ma:K=10,w=0.1 | ma:T=SECONDS | ma:weights=[..] | ou:tau=T | "
      "white, with "
      "sigma= and mean= (default ma:K=10,w=0.1); multisine:f1=F1,f2=F2,lines=L with rms= and "
      "mean=");
  sub->add_option("--noise", command->noise,
                  "measurement noise CHANNEL=REL,...: white noise with REL times the channel's "
                  "standard deviation, added to the written samples")
      ->delimiter(',');
  sub->add_option("--observe", options.observe,
                  "the channels to write, in this order (default: the states, then the inputs)")
      ->delimiter(',');
  sub->add_option("--dt", options.dt, "integration and sampling step")
      ->check(CLI::Validator(
          [](const std::string& text) {
            double dt = 0;
            try {
              dt = std::stod(text);
            } catch (const std::exception&) {
              dt = 0;
            }
            return std::isfinite(dt) && dt >= SimulationOptions::kMinStep &&
                           dt <= SimulationOptions::kMaxStep
                       ? std::string()
                       : "expected a number from 1e-9 to 1e6, found '" + text + "'";
          },
          "1e-9 to 1e6"));
  sub->add_option("--samples", options.samples, "samples per run")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 40));
  sub->add_option("--burn-in", options.burn_in, "steps discarded before each run");
  sub->add_option("--runs", options.runs, "number of runs")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 30));
  sub->add_flag("--continue", options.continue_runs,
                "start each run from the previous run's last state");
  sub->add_option("--seed", options.seed, "random seed");
  sub->add_option("--format", command->format,
                  "csv, bin, npy, mat (level 5), mat73 (level 7.3) or h5; default: by the output's "
                  "name, CSV without an extension")
      ->check(CLI::IsMember(names_of<FileFormat>()));
  sub->add_option("-o,--output", command->output,
                  "output file, - for standard output (csv, bin or npy); without --format its "
                  "extension (.csv, .txt, .bin, .npy, .mat, .h5, .hdf5) chooses the format");
  for (const char* name : {"--input", "--noise", "--observe", "--samples", "--burn-in", "--runs",
                           "--continue", "--seed"}) {
    sub->get_option(name)->excludes(input_file);
  }
  return {sub, [command, sub] {
            if (!command->input_file.empty() && sub->count("--dt") > 0) {
              command->record_dt = command->options.dt;
            }
            return run_simulate(*command, sub->count("--format") > 0);
          }};
}

}  // namespace momentid::cli
