// momentid as a library: identify the Duffing oscillator's parameters from a record, e.g. one
// that `momentid simulate models/duffing.mom --input ma:K=10,w=0.1,sigma=20 --samples 100000`
// wrote. The headers below do not include GiNaC (the test library.ginac_free checks it): the
// model stays an opaque value that load_model reads and identify takes.
#include <iostream>
#include <momentid/error.hpp>
#include <momentid/identify.hpp>
#include <momentid/model_file.hpp>

int main(int argc, char** argv) try {
  const std::shared_ptr<const momentid::Model> model =
      momentid::load_model(argc > 1 ? argv[1] : "duffing.mom");
  const momentid::IdentifyResult result = momentid::identify(
      *model, momentid::DataSource::file(argc > 2 ? argv[2] : "duffing.csv"), {.degree = 3});
  std::cout << momentid::format_text(result);
  for (const momentid::ParameterEstimate& p : result.parameters()) {
    std::cout << p.name << " = " << p.estimate << " +- " << p.std_error << "\n";
  }
} catch (const momentid::Error& e) {
  std::cerr << e.what() << "\n";
  return e.exit_code();
}
