#include <doctest/doctest.h>

#include <cmath>
#include <string>

#include "momentid/identify.hpp"
#include "momentid/model.hpp"
#include "momentid/refine.hpp"
#include "momentid/simulate.hpp"
#include "test_support.hpp"

namespace {

using momentid::Model;
using momentid::RefineOptions;
using momentid::RefineResult;
using momentid::testing::error_from;
using momentid::testing::model_file;

// A Duffing record (c 0.5, k 4, eps 1) with 2% noise on y and none on the held force.
struct NoisyDuffing {
  momentid::testing::Directory directory{"momentid_test_refine"};
  Model model = model_file("duffing.mom");
  std::string path = directory / "duffing.csv";
  NoisyDuffing() {
    momentid::SimulationOptions options;
    options.inputs = {momentid::InputSpec::parse("ma:K=10,w=0.1,sigma=20", "test")};
    options.samples = 50000;
    options.noise = {{"y", 0.02}};
    momentid::simulate_to_file(model, options, path, momentid::DataWriter::Format::kCsv);
  }
};

void check_truth(const RefineResult& r) {
  const std::map<std::string, double> truth = {{"c", 0.5}, {"k", 4}, {"eps", 1}};
  REQUIRE(r.parameters.size() == 3);
  for (const momentid::RefinedParameter& p : r.parameters) {
    INFO(p.name << " = " << p.refined.estimate << " +- " << p.refined.std_error);
    CHECK(std::abs(p.refined.estimate - truth.at(p.name)) < 4 * p.refined.std_error);
  }
}

}  // namespace

TEST_SUITE("refine") {
  TEST_CASE("the refinement finds the parameters from a start 10% off, within their errors") {
    const NoisyDuffing record;
    RefineOptions options;
    options.replay.parameters = {{"c", 0.55}, {"k", 3.6}, {"eps", 1.1}};
    const RefineResult r =
        momentid::refine(record.model, momentid::DataSource::file(record.path), options);
    check_truth(r);
    CHECK(r.converged);
    CHECK(r.warnings.empty());
    CHECK(r.noise_replicates == 0);  // the force is exact
    REQUIRE(r.outputs.size() == 2);  // y and v
    CHECK(r.outputs[0].rms < r.outputs[0].rms_start);
    CHECK(r.cost < r.cost_start);
  }

  TEST_CASE("identify --refine refines the moment estimate and keeps within its interval") {
    const NoisyDuffing record;
    const momentid::IdentifyResult r =
        momentid::identify(record.model, momentid::DataSource::file(record.path), {.refine = true});
    REQUIRE(r.refinement);
    CHECK(r.refinement->start_from == "the moment estimate");
    check_truth(*r.refinement);
    CHECK_FALSE(r.refinement->moved());
    // The refined errors are smaller than the moments': the simulation error uses every sample.
    for (std::size_t p = 0; p < 3; ++p) {
      CHECK(r.refinement->parameters[p].refined.std_error < r.parameters()[p].std_error);
    }
  }

  TEST_CASE("a wrong model's refinement moves beyond the moment estimate's interval") {
    // The linear oscillator on a strongly hardening record: the moments and the simulation error
    // weigh the missing term differently.
    const NoisyDuffing record;
    const Model linear = momentid::parse_model(R"(model linear "no cubic term"
state y, v
input x
param c = 0.5, k = 4
y' = v
v' = -c*v - k*y + x
)",
                                               "linear.mom");
    const momentid::IdentifyResult r =
        momentid::identify(linear, momentid::DataSource::file(record.path), {.refine = true});
    REQUIRE(r.refinement);
    CHECK(r.refinement->moved());
    CHECK(momentid::status(r) == momentid::Status::kDoubtful);
  }

  TEST_CASE("a refinement that cannot run leaves the moment estimate with a doubt") {
    // A softening cubic of this size makes the identified oscillator run away in the simulation.
    const NoisyDuffing record;
    const Model softening = momentid::parse_model(R"(model softening "a cubic that runs away"
state y, v
input x
param c = 0.5, k = 4
const eps = -3
y' = v
v' = -c*v - k*y - eps*y^3 + x
)",
                                                  "softening.mom");
    const momentid::IdentifyResult r =
        momentid::identify(softening, momentid::DataSource::file(record.path), {.refine = true});
    CHECK_FALSE(r.refinement);
    CHECK(r.refinement_failure.find("the simulation blew up") != std::string::npos);
    CHECK(momentid::status(r) == momentid::Status::kDoubtful);
  }

  TEST_CASE("options that cannot be refined with are refused, naming the option") {
    const NoisyDuffing record;
    RefineOptions options;
    options.free = {"q"};
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::refine(record.model, momentid::DataSource::file(record.path),
                                         options);
                      }).what()) == "free: 'q' is not a parameter of model duffing");
    options.free.clear();
    options.max_iterations = 0;
    CHECK(std::string(error_from<momentid::UsageError>([&] {
                        momentid::refine(record.model, momentid::DataSource::file(record.path),
                                         options);
                      }).what()) == "max-iterations: expected a number from 1 to 10000, found 0");
  }
}
