#include <doctest/doctest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "momentid/identify.hpp"
#include "momentid/latent.hpp"
#include "momentid/model.hpp"
#include "momentid/reader.hpp"
#include "momentid/simulate.hpp"
#include "test_support.hpp"

namespace {

using GiNaC::ex;
using momentid::EliminatedTerm;
using momentid::Elimination;
using momentid::Model;
using momentid::ModelError;
using momentid::testing::error_from;

Model model_text(const std::string& text) { return momentid::parse_model(text, "test.mom"); }

ex parameter(const Model& model, const std::string& name) {
  return model.parameter_symbol(model.parameter_index(name));
}

// The coefficient of d^order/dt^order of `signal` on the right side of equation 0.
ex right_side(const Model& model, const Elimination& e, const std::string& signal, int order) {
  for (const EliminatedTerm& t : e.equations.at(0).terms) {
    if (t.order == order && momentid::format_monomial(model, t.monomial) == signal) {
      return -t.coefficient;
    }
  }
  return 0;
}

void check_same(const ex& got, const ex& want) {
  INFO("got " << got << ", want " << want);
  CHECK((got - want).expand().normal().is_zero());
}

const char* const kFiltered = R"(model filtered "Duffing behind an input filter"
state y, v, z
input x
param c = 0.5, k = 4, eps = 1, a = 2, b = 1, g = 1
y' = v
v' = -c*v - k*y - eps*y^3 + g*z
z' = -a*z + b*x
)";

// `truth` simulated (2*10^5 samples, 2% noise on `state`) and `model` identified from that
// state's column and x's.
momentid::IdentifyResult identify_sensed(const Model& model, const Model& truth,
                                         const std::string& state) {
  momentid::SimulationOptions options;
  options.inputs = {momentid::InputSpec::parse("ma:K=10,w=0.1,sigma=20", "test")};
  options.samples = 200000;
  options.noise = {{state, 0.02}};
  momentid::testing::Recorder recorder(truth.channel_count());
  momentid::simulate(truth, options, recorder);
  // The recorder's columns: t, the states, the input.
  std::vector<double> y =
      recorder.column(1 + static_cast<std::size_t>(truth.variable_index(state)));
  std::vector<double> x = recorder.column(1 + truth.states().size());
  momentid::MemoryData data;
  data.rows = options.samples;
  data.columns = {{state, y.data()}, {"x", x.data()}};
  data.metadata.add_line({{"dt", "0.01"}, {"input-hold", "zoh"}});
  return momentid::identify(model, momentid::DataSource::memory(std::move(data)));
}

// The filtered oscillator from y and x.
momentid::IdentifyResult identify_filtered(const Model& model, const Model& truth) {
  return identify_sensed(model, truth, "y");
}

}  // namespace

TEST_SUITE("latent") {
  TEST_CASE("an input filter's output is eliminated into a third-order equation in y and x") {
    momentid::AlgebraLock lock;
    const Model model = model_text(kFiltered);
    const Elimination e = momentid::eliminate_latent(model, {true, false, false, true});
    REQUIRE(e.latent == std::vector<int>{2});
    REQUIRE(e.equations.size() == 1);
    CHECK(e.equations[0].sources == std::vector<int>{1, 2});
    const EliminatedTerm& lead = e.equations[0].terms.front();
    CHECK(momentid::derivative_text(model, lead.monomial, lead.order) == "y'''");
    check_same(lead.coefficient, 1);
    const ex a = parameter(model, "a"), c = parameter(model, "c"), k = parameter(model, "k"),
             eps = parameter(model, "eps"), b = parameter(model, "b"), g = parameter(model, "g");
    check_same(right_side(model, e, "y", 2), -(a + c));
    check_same(right_side(model, e, "y", 1), -(k + a * c));
    check_same(right_side(model, e, "y", 0), -a * k);
    check_same(right_side(model, e, "y^3", 1), -eps);
    check_same(right_side(model, e, "y^3", 0), -a * eps);
    check_same(right_side(model, e, "x", 0), b * g);
    CHECK(e.equations[0].terms.size() == 7);
    // Six coefficients, five combinations: b and g only as their product.
    CHECK(e.coefficients.size() == 6);
    CHECK(e.rank == 5);
    REQUIRE(e.undetermined.size() == 1);
    CHECK(e.undetermined[0].parameters ==
          std::vector<int>{model.parameter_index("b"), model.parameter_index("g")});
    CHECK(e.undetermined[0].to_fix == 1);
  }

  TEST_CASE("a fixed parameter makes the product's other factor determined") {
    std::string text = kFiltered;
    text.replace(text.find("b = 1"), 5, "b = 1 fixed");
    const Model model = model_text(text);
    const Elimination e = momentid::eliminate_latent(model, {true, false, false, true});
    CHECK(e.parameters.size() == 5);
    CHECK(e.rank == 5);
    CHECK(e.undetermined.empty());
  }

  TEST_CASE("an unmeasured mass of a chain is eliminated, its spring and damper determined") {
    momentid::AlgebraLock lock;
    const Model model = momentid::testing::model_file("chain_sensed.mom");
    const Elimination e = momentid::eliminate_latent(model, {false, false, true, false, true});
    CHECK(e.latent == std::vector<int>{0, 1});
    const EliminatedTerm& lead = e.equations.at(0).terms.front();
    CHECK(momentid::derivative_text(model, lead.monomial, lead.order) == "y2^(4)");
    const ex c1 = parameter(model, "c1"), c2 = parameter(model, "c2"), k1 = parameter(model, "k1"),
             k2 = parameter(model, "k2"), eps = parameter(model, "eps");
    check_same(right_side(model, e, "y2", 3), -(c1 + 2 * c2));
    check_same(right_side(model, e, "y2", 0), -k1 * k2);
    check_same(right_side(model, e, "y2^3", 2), -eps);
    check_same(right_side(model, e, "y2^3", 0), -eps * (k1 + k2));
    check_same(right_side(model, e, "x", 2), 1);
    check_same(right_side(model, e, "x", 1), c1 + c2);
    CHECK(e.rank == 5);
    CHECK(e.undetermined.empty());
  }

  TEST_CASE("a model whose states the record shows has nothing to eliminate") {
    const Model model = model_text(kFiltered);
    CHECK(momentid::eliminate_latent(model, {true, false, true, true}).latent.empty());
  }

  TEST_CASE("a latent state that enters nonlinearly or reaches no measured equation is refused") {
    std::string product = kFiltered;
    product.replace(product.find("g*z"), 3, "g*y*z");
    CHECK(std::string(error_from<ModelError>([&] {
                        momentid::eliminate_latent(model_text(product), {true, false, false, true});
                      }).what()) ==
          "test.mom:6:1: equation 2 holds the latent state z in a product or a power: a latent "
          "state can be eliminated only where it enters linearly");
    std::string absolute = kFiltered;
    absolute.replace(absolute.find("g*z"), 3, "g*abs(z)");
    CHECK(
        std::string(error_from<ModelError>([&] {
                      momentid::eliminate_latent(model_text(absolute), {true, false, false, true});
                    }).what()) ==
        "test.mom:6:1: equation 2 holds abs(z) of a latent state: a latent state can be "
        "eliminated only where it enters linearly");
    std::string apart = kFiltered;
    apart.replace(apart.find(" + g*z"), 6, " + g*x");
    CHECK(std::string(error_from<ModelError>([&] {
                        momentid::eliminate_latent(model_text(apart), {true, false, false, true});
                      }).what()) ==
          "test.mom:5:1: the latent states z enter no equation of the measured states: the record "
          "holds nothing of them (remove them from the model)");
  }

  TEST_CASE(
      "identify estimates a filter's pole that no channel shows, each parameter within 4 "
      "standard errors") {
    std::string text = kFiltered;
    text.replace(text.find("b = 1"), 5, "b = 2 fixed");
    const Model model = model_text(text);
    const momentid::IdentifyResult r = identify_filtered(model, model);
    REQUIRE(r.latent);
    CHECK(r.latent->states == std::vector<std::string>{"z"});
    CHECK(r.latent->coefficients.size() == 6);
    CHECK(r.latent->dof == 1);
    CHECK(r.latent->converged);
    REQUIRE(r.latent->pvalue);
    CHECK(*r.latent->pvalue > 0.01);
    CHECK(momentid::status(r) == momentid::Status::kOk);
    const std::map<std::string, double> truth{{"c", 0.5}, {"k", 4}, {"eps", 1}, {"a", 2}, {"g", 1}};
    for (const momentid::ParameterEstimate& p : r.parameters()) {
      INFO(p.name << " = " << p.estimate << " +- " << p.std_error);
      if (p.name == "b") {
        CHECK(p.fixed);
        continue;
      }
      CHECK(std::abs(p.estimate - truth.at(p.name)) < 4 * p.std_error);
    }
    // Without the filter the same record is not ok: the misfit shows.
    const Model plain = momentid::testing::model_file("duffing.mom");
    const momentid::IdentifyResult wrong = identify_filtered(plain, model);
    CHECK(wrong.latent == std::nullopt);
    CHECK(momentid::status(wrong) != momentid::Status::kOk);
  }

  TEST_CASE("identify stops before the pass at parameters the coefficients cannot separate") {
    const Model model = model_text(kFiltered);
    CHECK(std::string(error_from<ModelError>([&] { identify_filtered(model, model); }).what()) ==
          "test.mom:4:39: parameters b and g are not determined by the record's channels once "
          "the latent states z are eliminated: the coefficients of the equations without them "
          "hold them only in combinations (fix 1 of them, e.g. fix b=1, or `param b = 1 fixed`; "
          "docs/latent-states.md)");
  }

  TEST_CASE("a chain's unmeasured mass is identified from the other mass's displacement") {
    const Model model = momentid::testing::model_file("chain_sensed.mom");
    const momentid::IdentifyResult r = identify_sensed(model, model, "y2");
    REQUIRE(r.latent);
    CHECK(r.latent->states == std::vector<std::string>{"y1", "v1"});
    CHECK(r.latent->dof == 4);
    CHECK(momentid::status(r) == momentid::Status::kOk);
    const std::map<std::string, double> truth{
        {"c1", 0.3}, {"k1", 5}, {"c2", 0.2}, {"k2", 3}, {"eps", 1}};
    for (const momentid::ParameterEstimate& p : r.parameters()) {
      INFO(p.name << " = " << p.estimate << " +- " << p.std_error);
      CHECK(std::abs(p.estimate - truth.at(p.name)) < 4 * p.std_error);
    }
  }

  TEST_CASE(
      "a search from the nominal values that failed says it also ran from values around them") {
    const Model model = momentid::testing::model_file("chain_sensed.mom");
    momentid::IdentifyResult r = identify_sensed(model, model, "y2");
    REQUIRE(r.latent);
    CHECK(r.latent->starts == 0);  // accepted from the nominal values
    CHECK(!r.latent->nominal_distance);
    const auto said = [&](const std::string& text) {
      const std::vector<std::string> d = momentid::doubts(r);
      return std::any_of(d.begin(), d.end(),
                         [&](const std::string& s) { return s.find(text) != std::string::npos; });
    };
    CHECK(!said("the latent dynamics may be wrong"));
    // Rejected at the least Q of every search.
    r.latent->starts = 64;
    r.latent->nominal_distance = 452.3;
    r.latent->distance = 40.65;
    r.latent->pvalue = 1.1e-7;
    CHECK(
        said("(Q = 40.65 on 4 degrees of freedom, p = 1.1e-07, the least from the model's "
             "nominal values and 64 values around them): the latent dynamics may be wrong, or "
             "the nominal values too far from the truth for the search"));
    r.latent->converged = false;
    CHECK(
        said("did not converge from the model's nominal values and 64 values around them: give "
             "values nearer the truth"));
    CHECK(momentid::format_text(r).find("; searched from 64 values around the model's nominal "
                                        "ones too, from which it stopped at Q = 452.3") !=
          std::string::npos);
  }

  TEST_CASE("an elimination beyond the sixth derivative is an error at the equation") {
    const Model model = model_text(R"(model chain4 "four masses, a sensor on the first"
state y1, v1, y2, v2, y3, v3, y4, v4
input x
param c = 0.2, k = 3
y1' = v1
v1' = -c*(v1 - v2) - k*(y1 - y2)
y2' = v2
v2' = -c*(v2 - v1) - k*(y2 - y1) - c*(v2 - v3) - k*(y2 - y3)
y3' = v3
v3' = -c*(v3 - v2) - k*(y3 - y2) - c*(v3 - v4) - k*(y3 - y4)
y4' = v4
v4' = -c*(v4 - v3) - k*(y4 - y3) + x
)");
    const std::vector<bool> measured{true, false, false, false, false, false, false, false, true};
    const Model coefficients =
        momentid::coefficient_model(model, momentid::eliminate_latent(model, measured));
    momentid::LagOptions options;
    options.measured = measured;
    CHECK(std::string(error_from<ModelError>([&] {
                        momentid::derive_lagged(coefficients, options);
                      }).what()) ==
          "test.mom:6:1: term 'y1^(8)' of equation without y2, v2, y3, v3, y4, v4 needs the "
          "derivative of order 8 in the lag, above 6: the latent states' elimination raised the "
          "equation's order beyond what the lagged equations read (measure one of the latent "
          "states)");
  }
}
