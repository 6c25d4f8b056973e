// The options of identify and select, described once (option_table.hpp): the table's entries,
// the setters that read an option's text, and the order apply_options sets them in.

#include <doctest/doctest.h>

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "momentid/option_table.hpp"
#include "momentid/reader.hpp"
#include "test_support.hpp"

namespace {

using momentid::find_option;
using momentid::GivenOption;
using momentid::SelectOptions;
using momentid::UsageError;
using momentid::testing::error_from;
using momentid::testing::model_file;

const momentid::DataSource kZeros =
    momentid::DataSource::file(std::string(MOMENTID_SOURCE_DIR) + "/tests/data/zeros.csv");

// The options given as (keyword, text) pairs, each named by its keyword, set into `options`.
momentid::Model apply(const std::vector<std::pair<std::string, std::string>>& texts,
                      SelectOptions& options, const std::string& model = "duffing.mom") {
  std::vector<GivenOption> given;
  for (const auto& [keyword, text] : texts) given.push_back({find_option(keyword), text, keyword});
  return momentid::apply_options(given, model_file(model), kZeros, options);
}

std::string refusal(const std::string& keyword, const std::string& text, const std::string& name) {
  const UsageError e = error_from<UsageError>([&] {
    SelectOptions into;
    find_option(keyword)->set(into, model_file("duffing.mom"), text, name);
  });
  return e.text([](const std::string& field) { return field; });
}

}  // namespace

TEST_SUITE("options") {
  TEST_CASE("every option has its flag, keyword, field, value name, help and setter, once") {
    std::set<std::string_view> flags, keywords, fields;
    for (const momentid::OptionDescription& option : momentid::option_table()) {
      CHECK(option.flag.starts_with("--"));
      // A switch without a value name is a flag (--refine).
      CHECK((!option.value_name.empty() || option.value == momentid::OptionValue::kSwitch));
      CHECK(!option.help.empty());
      CHECK((option.set != nullptr));
      CHECK(flags.insert(option.flag).second);
      CHECK(keywords.insert(option.keyword).second);
      CHECK(fields.insert(option.field).second);
      CHECK(find_option(option.keyword) == &option);
      CHECK(momentid::option_of_field(option.field) == &option);
    }
    CHECK(momentid::options_of("identify").size() == 26);
    CHECK(momentid::options_of("select").size() == 23);
  }

  TEST_CASE("a setter names the option as the caller does") {
    CHECK(refusal("batches", "ten", "--batches") ==
          "--batches: expected a whole number, 0 or more, found 'ten'");
    CHECK(refusal("batches", "ten", "batches") ==
          "batches: expected a whole number, 0 or more, found 'ten'");
    CHECK(refusal("input_hold", "held", "input_hold") ==
          "input_hold: expected sample or zoh, found 'held'");
    CHECK(refusal("lags", "3-40", "--lags") ==
          "--lags: expected FIRST..LAST in samples, e.g. 3..40, found '3-40'");
    CHECK(refusal("fix", "zz=1", "fix") ==
          "fix: 'zz' is not a parameter of model duffing (parameters: c, k, eps)");
    CHECK(refusal("shard_size", "4q", "--shard-size") ==
          "--shard-size: expected a size in bytes, with k, M or G for powers of 1024, found '4q'");
    CHECK(refusal("shard_size", "1000", "shard_size") ==
          "shard_size: expected at least 1k (1024 bytes), found 1000 bytes");
  }

  TEST_CASE("the texts become the options' values") {
    SelectOptions options;
    apply({{"lags", "3..40"},
           {"shard_size", "64k"},
           {"fix", "k=4.1,c=0.5"},
           {"noise", "none"},
           {"dt", "0.01"},
           {"names", "t,y,x"},
           {"extrapolate", "dt"},
           {"exhaustive", "4"}},
          options);
    CHECK(options.identify.lags == std::pair{3, 40});
    CHECK(options.identify.record.control.shard_bytes == 64 * 1024);
    CHECK(options.identify.fixed == std::map<std::string, double>{{"c", 0.5}, {"k", 4.1}});
    CHECK((options.identify.noise && options.identify.noise->empty()));
    CHECK(options.identify.record.dt == 0.01);
    CHECK(options.identify.record.layout.column_names == std::vector<std::string>{"t", "y", "x"});
    CHECK(options.identify.extrapolate);
    CHECK(options.exhaustive == 4);
  }

  TEST_CASE("the model's options are read against the model the derivative columns complete") {
    // center all names the column of v' that --columns declares; before the model is completed
    // there is no such channel.
    SelectOptions options;
    const momentid::Model completed = apply({{"center", "all"}, {"columns", "v'=a"}}, options);
    CHECK(completed.variable_index("a") >= 0);
    CHECK(options.identify.center == completed.channel_names());
    CHECK(std::find(options.identify.center.begin(), options.identify.center.end(), "a") !=
          options.identify.center.end());
  }

  TEST_CASE("two options that exclude each other are refused, named as given") {
    SelectOptions options;
    const UsageError e = error_from<UsageError>([&] {
      apply({{"multipliers", "y"}, {"lags", "3..40"}}, options);
    });
    CHECK(std::string(e.what()) == "lags excludes multipliers");
  }

  TEST_CASE("a double's text reads back as the same double") {
    for (const double x : {0.01, 1.706777165336792e-07, 2.522923758208279e-228, 1e300, -3.5}) {
      CHECK(momentid::parse_option_number(momentid::option_number_text(x), "dt") == x);
    }
    CHECK(momentid::option_number_text(0.01) == "0.01");
  }
}
