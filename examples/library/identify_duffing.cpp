// momentid as a library: derive the Duffing oscillator's moment equations, simulate a record
// with known parameters, and identify them from it.
#include <iostream>
#include <momentid/momentid.hpp>

int main(int argc, char** argv) try {
  const momentid::Model model = momentid::parse_model_file(argc > 1 ? argv[1] : "duffing.mom");
  std::cout << momentid::format_text(momentid::derive(model, {.degree = 3}));

  momentid::SimulationOptions simulation;
  simulation.parameters = momentid::parameter_values(model, {});  // the nominal values
  simulation.inputs = {momentid::InputSpec::parse("ma:K=10,w=0.1,sigma=20", "input")};
  simulation.samples = 100000;
  momentid::simulate_to_file(model, simulation, "duffing.csv", momentid::DataWriter::Format::kCsv);

  const momentid::IdentifyResult result =
      momentid::identify(model, momentid::DataSource::file("duffing.csv"), {.degree = 3});
  for (const momentid::ParameterEstimate& p : result.parameters()) {
    std::cout << p.name << " = " << p.estimate << " +- " << p.std_error << "\n";
  }
} catch (const momentid::Error& e) {
  std::cerr << e.what() << "\n";
  return e.exit_code();
}
