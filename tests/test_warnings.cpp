// The warnings of identify that fire when they should and stay quiet when they should: a model
// that the J test rejects, an identity violated, a sensor offset, weakly determined and strongly
// correlated estimates, standard errors on few degrees of freedom.

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "common/number.hpp"
#include "momentid/identify.hpp"
#include "test_support.hpp"

namespace momentid {
namespace {

using testing::model_file;
using testing::options_for;
using testing::Recorder;

// A simulated Duffing record (c = 0.5, k = 4, eps = 1, MA input sigma = 20 unless `input` says
// otherwise) in memory, whose columns the tests may change before identifying.
struct Record {
  std::vector<std::string> names{"t", "y", "v", "x"};
  std::vector<std::vector<double>> columns;
  explicit Record(std::size_t samples, std::uint64_t seed = 7,
                  const std::string& input = "ma:K=10,w=0.1,sigma=20") {
    const Model model = model_file("duffing.mom");
    SimulationOptions options = options_for(model, samples, seed);
    options.inputs[0] = InputSpec::parse(input, "--input");
    Recorder recorder(model.channel_count());
    simulate(model, options, recorder);
    for (std::size_t c = 0; c < names.size(); ++c) columns.push_back(recorder.column(c));
  }
  std::vector<double>& column(const std::string& name) {
    return columns[static_cast<std::size_t>(std::find(names.begin(), names.end(), name) -
                                            names.begin())];
  }
  DataSource source() const {
    MemoryData data;
    for (std::size_t c = 0; c < names.size(); ++c) {
      data.columns.push_back({names[c], columns[c].data(), 1});
    }
    data.rows = columns[0].size();
    data.metadata.add_line({{"input-hold", "zoh"}});
    return DataSource::memory(std::move(data));
  }
};

bool mentions(const std::vector<std::string>& warnings, const std::string& text) {
  return std::any_of(warnings.begin(), warnings.end(),
                     [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

TEST_SUITE("warnings") {
  TEST_CASE("the true model on a clean record is ok and has no doubts, least squares is untested") {
    const Record record(50000);
    const Model model = model_file("duffing.mom");
    const IdentifyResult r = identify(model, record.source(), {.degree = 3});
    CHECK(r.estimate.optimal.has_value());
    CHECK(doubts(r).empty());
    CHECK(status(r) == Status::kOk);
    const IdentifyResult ls =
        identify(model, record.source(), {.degree = 3, .weighting = Weighting::kLeastSquares});
    CHECK(doubts(ls).empty());
    CHECK(status(ls) == Status::kUntested);
    CHECK(mentions(warnings(ls), "no test checked the model: least squares was asked for"));
  }

  TEST_CASE("standard errors on fewer than 10 degrees of freedom are a doubt") {
    // Sensor noise of 2% on y and v: the lagged equations, whose errors come from the batches.
    Record record(20000);
    std::mt19937_64 random(11);
    for (const char* name : {"y", "v"}) {
      std::vector<double>& x = record.column(name);
      double squares = 0;
      for (double value : x) squares += value * value;
      std::normal_distribution<double> noise(0, 0.02 * std::sqrt(squares / double(x.size())));
      for (double& value : x) value += noise(random);
    }
    const Model model = model_file("duffing.mom");
    const IdentifyResult enough = identify(model, record.source(), {});
    CHECK(enough.estimate.main().dof >= 10);
    CHECK_FALSE(mentions(doubts(enough), "degrees of freedom"));
    // Eight batches: the batch means taken as independent, on 7 degrees of freedom.
    const IdentifyResult few = identify(model, record.source(), {.batches = 8});
    MESSAGE("degrees of freedom: " << enough.estimate.main().dof << ", "
                                   << few.estimate.main().dof);
    REQUIRE(few.estimate.main().dof < 10);
    CHECK(mentions(doubts(few),
                   "the standard errors rest on 7 degrees of freedom (their long-run "
                   "covariance, from 8 batches): they are rough"));
    CHECK(status(few) == Status::kDoubtful);
  }

  TEST_CASE("a derivative order the data do not determine is a doubt, a determined mass is not") {
    const Record record(50000);
    // The Duffing record read by a model with a third derivative of y, whose coefficient m3 the
    // oscillator gives no part: its estimate falls either side of zero.
    const Model jerk = parse_model(R"(model jerk
state y, v, a
input x
param m3 = 0.001, c = 0.5, k = 4, eps = 1
y' = v
v' = a
m3*a' = -a - c*v - k*y - eps*y^3 + x
)",
                                   "jerk.mom");
    const IdentifyResult r = identify(jerk, record.source(), {});
    const ParameterEstimate& m3 = r.parameters().front();
    MESSAGE("m3 = " << m3.estimate << " +- " << m3.std_error);
    REQUIRE(std::abs(m3.estimate) < 2 * m3.std_error);
    CHECK(mentions(doubts(r),
                   "standard errors from zero: the data do not tell this model from "
                   "one without a', a derivative order they do not determine"));
    CHECK(status(r) == Status::kDoubtful);
    const Model mass = parse_model(R"(model mass
state y, v
input x
param m = 1, c = 0.5, k = 4, eps = 1
y' = v
m*v' = -c*v - k*y - eps*y^3 + x
)",
                                   "mass.mom");
    CHECK_FALSE(mentions(doubts(identify(mass, record.source(), {})), "derivative order"));
  }

  TEST_CASE("a square system is untested, and says why") {
    const Record record(50000);
    const Model model = model_file("duffing.mom");
    const IdentifyResult r =
        identify(model, record.source(),
                 {.multipliers = parse_multiplier_list(model, "y, v, y^3", "multipliers")});
    REQUIRE(r.estimate.rows == 3);
    CHECK(!r.estimate.j_pvalue.has_value());
    CHECK(status(r) == Status::kUntested);
    CHECK(mentions(warnings(r), "there are no more equations than parameters"));
  }

  TEST_CASE("a model without the cubic spring is rejected by the J test: doubtful") {
    const Record record(50000);
    const Model linear =
        parse_model("model linear\nstate y, v\ninput x\nparam c, k\ny' = v\nv' = -c*v - k*y + x\n",
                    "linear.mom");
    const IdentifyResult r =
        identify(linear, record.source(), {.degree = 3, .weighting = Weighting::kGmm});
    REQUIRE(r.estimate.j_pvalue);
    MESSAGE("J p-value " << *r.estimate.j_pvalue);
    CHECK(momentid::to_string(status(r)) == "doubtful");
    CHECK(mentions(doubts(r), "the J test rejects the model"));
    CHECK(warnings(r).front().find("the J test rejects the model") == 0);
  }

  TEST_CASE(
      "the J test's doubt names what the filter cuts from a formed state in a nonlinear "
      "term, and only then") {
    const Record record(50000);
    const Model linear =
        parse_model("model linear\nstate y, v\ninput x\nparam c, k\ny' = v\nv' = -c*v - k*y + x\n",
                    "linear.mom");
    IdentifyResult r =
        identify(linear, record.source(), {.degree = 3, .weighting = Weighting::kGmm});
    REQUIRE(r.estimate.j_pvalue);
    REQUIRE(*r.estimate.j_pvalue < 0.01);
    const std::string cut = "the filter cuts from 'y', formed from accelerations";
    CHECK_FALSE(mentions(doubts(r), cut));
    r.integration = IdentifyResult::Integration{};
    r.integration->formed.push_back({.state = "y", .variable = "a", .column = "a", .integrals = 2});
    CHECK_FALSE(mentions(doubts(r), cut));  // y held linearly
    r.integration->formed.back().cut = true;
    CHECK(mentions(doubts(r), cut));
    r.estimate.j_pvalue = 0.5;
    CHECK_FALSE(mentions(doubts(r), cut));
  }

  TEST_CASE("a velocity column shifted in time violates the identities: doubtful") {
    Record record(50000);
    std::vector<double>& v = record.column("v");
    std::rotate(v.begin(), v.begin() + 30, v.end());
    const IdentifyResult r = identify(model_file("duffing.mom"), record.source(), {.degree = 3});
    CHECK(momentid::to_string(status(r)) == "doubtful");
    CHECK(mentions(doubts(r), "the stationarity identity E[y*v] = 0 is violated"));
  }

  TEST_CASE("an offset on a symmetric model's state is a doubt that names --center") {
    Record record(50000);
    std::vector<double>& y = record.column("y");
    double mean = 0, squares = 0;
    for (double value : y) mean += value;
    mean /= static_cast<double>(y.size());
    for (double value : y) squares += (value - mean) * (value - mean);
    const double sd = std::sqrt(squares / static_cast<double>(y.size()));
    const IdentifyResult clean = identify(model_file("duffing.mom"), record.source(), {});
    CHECK(!mentions(doubts(clean), "sensor offset"));
    for (double& value : y) value += 0.3 * sd;
    const IdentifyResult r = identify(model_file("duffing.mom"), record.source(), {});
    CHECK(momentid::to_string(status(r)) == "doubtful");
    CHECK(mentions(doubts(r), "'y' has the mean"));
    CHECK(mentions(doubts(r), "--center y"));
    // The response to the record's zero-mean force, simulated for the check, follows the
    // record but for the offset.
    REQUIRE(r.response_means.size() == 2);
    const IdentifyResult::ResponseMean& response = r.response_means[0];
    CHECK(response.recorded - response.simulated == doctest::Approx(0.3 * sd).epsilon(0.01));
    CHECK(std::abs(response.simulated) < 0.01 * sd);
    // Removing the mean restores the estimates the offset spoiled.
    const IdentifyResult centered =
        identify(model_file("duffing.mom"), record.source(), {.center = {"y"}});
    CHECK(momentid::to_string(status(centered)) == "ok");
    REQUIRE(centered.centered.count("y") == 1);
    CHECK(centered.centered.at("y") == doctest::Approx(mean + 0.3 * sd));
    const auto k = [](const IdentifyResult& result) { return result.parameters()[1]; };
    MESSAGE("k: clean " << k(clean).estimate << ", offset " << k(r).estimate << ", centered "
                        << k(centered).estimate << " +- " << k(centered).std_error);
    // On this noise-free record the offset moves k by 6%; without it the estimate is the clean
    // one to 0.3% (the mean removed is the record's, not the offset alone).
    CHECK(std::abs(k(r).estimate / k(clean).estimate - 1) > 0.05);
    CHECK(std::abs(k(centered).estimate / k(clean).estimate - 1) < 0.005);
    CHECK(format_text(centered).find("means removed (--center): y ") != std::string::npos);
    // A model with an even term may have a mean: no doubt about it.
    const Model quadratic = parse_model(
        "model quadratic\nstate y, v\ninput x\nparam c, k, q\ny' = v\n"
        "v' = -c*v - k*y - q*y^2 + x\n",
        "quadratic.mom");
    CHECK(!mentions(doubts(identify(quadratic, record.source(), {})), "sensor offset"));
  }

  TEST_CASE(
      "a mean of the response's own is no offset; an offset beside it is named with the amount "
      "to subtract") {
    // A periodic force gives a nonlinear model's states a mean of their own (an independent
    // generator's multisine records: tests/independent/offsets.py multisine). Here the
    // simulated response's means are set as such a record would give them.
    const Record record(50000);
    IdentifyResult r = identify(model_file("duffing.mom"), record.source(), {});
    REQUIRE(r.means.front().name == "y");
    CHECK(r.response_means.empty());  // nothing in doubt, nothing simulated
    ChannelMean& y = r.means.front();
    y.mean = 20 * y.std_error;
    CHECK(mentions(doubts(r), "(20 standard errors from zero)"));
    CHECK(!mentions(doubts(r), "A periodic input"));
    r.response_failure = "the simulation does not follow the record";
    CHECK(mentions(doubts(r),
                   "remove it with --center y. A periodic input can give a state a "
                   "mean of its own, which the identified model's response to the "
                   "recorded inputs would show, but the simulation does not follow"));
    r.response_failure.clear();
    r.response_means = {{.name = "y", .recorded = y.mean, .simulated = y.mean, .std_error = 0}};
    CHECK(momentid::to_string(status(r)) == "ok");
    r.response_means[0].simulated = y.mean - 10 * y.std_error;
    const std::string offset = number(10 * y.std_error, "%.3g");
    CHECK(mentions(doubts(r), "'y' has the mean " + number(y.mean, "%.3g") + ", " + offset +
                                  " from the " + number(10 * y.std_error, "%.3g") +
                                  " of its response to the recorded inputs"));
    CHECK(mentions(doubts(r), "10 standard errors)"));
    CHECK(mentions(doubts(r), "subtract about " + offset + " from 'y'"));
    CHECK(!mentions(doubts(r), "--center y"));
    // A response that follows the record loosely widens the error of the difference.
    r.response_means[0].std_error = 5 * y.std_error;
    CHECK_FALSE(mentions(doubts(r), "'y' has the mean"));
    CHECK(momentid::to_string(status(r)) == "ok");
  }

  TEST_CASE("a short record's weakly determined parameters are named") {
    // The zero-lag equations by least squares: the optimal weighting, and the lagged equations,
    // determine these parameters well at this length.
    const Record record(3000);
    const IdentifyResult r =
        identify(model_file("duffing.mom"), record.source(),
                 {.method = Method::kZeroLag, .weighting = Weighting::kLeastSquares});
    const std::vector<std::string> all = warnings(r);
    bool weak = false;
    for (const ParameterEstimate& p : r.parameters()) {
      if (p.std_error > 0.1 * std::abs(p.estimate)) {
        weak = true;
        CHECK(mentions(all, "'" + p.name + "' is weakly determined"));
      }
    }
    CHECK(weak);
    CHECK(status(r) == Status::kUntested);  // a weak estimate is honest: its interval says so
  }

  TEST_CASE("strongly correlated estimates are named, from a symmetric correlation matrix") {
    const Record record(20000, 5);
    const IdentifyResult r = identify(model_file("duffing.mom"), record.source(),
                                      {.degree = 3, .weighting = Weighting::kGmm});
    REQUIRE(r.estimate.optimal.has_value());
    const auto& rho = r.estimate.optimal->correlation;
    REQUIRE(rho.size() == 3);
    for (std::size_t i = 0; i < 3; ++i) {
      CHECK(rho[i][i] == doctest::Approx(1));
      for (std::size_t j = 0; j < 3; ++j) CHECK(rho[i][j] == rho[j][i]);
    }
    MESSAGE("rho(k, eps) = " << rho[1][2]);
    CHECK(mentions(warnings(r), "'k' and 'eps' are strongly correlated") ==
          (std::abs(rho[1][2]) > 0.95));
  }
}

}  // namespace
}  // namespace momentid
