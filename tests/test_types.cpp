#include <doctest/doctest.h>

#include "momentid/error.hpp"
#include "momentid/types.hpp"

using momentid::FileFormat;
using momentid::InputHold;
using momentid::Interpolation;
using momentid::MissingValues;
using momentid::UsageError;
using momentid::Weighting;

namespace {

// Every name parses back to the value it names, and the names are distinct.
template <class Enum, class Parse>
void check_round_trip(const std::vector<Enum>& values, Parse parse) {
  const std::vector<std::string> names = momentid::names_of<Enum>();
  REQUIRE(names.size() == values.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    CAPTURE(names[i]);
    CHECK(momentid::to_string(values[i]) == names[i]);
    CHECK(parse(names[i], "option") == values[i]);
  }
}

}  // namespace

TEST_SUITE("types") {
  TEST_CASE("every enum round-trips through its name") {
    check_round_trip<InputHold>({InputHold::kSample, InputHold::kZeroOrderHold},
                                momentid::parse_input_hold);
    check_round_trip<MissingValues>(
        {MissingValues::kError, MissingValues::kDropRow, MissingValues::kSplitRun},
        momentid::parse_missing_values);
    check_round_trip<Interpolation>(
        {Interpolation::kHold, Interpolation::kLinear, Interpolation::kCubic, Interpolation::kSinc},
        momentid::parse_interpolation);
    check_round_trip<Weighting>({Weighting::kAuto, Weighting::kLeastSquares, Weighting::kGmm},
                                momentid::parse_weighting);
    check_round_trip<FileFormat>({FileFormat::kCsv, FileFormat::kBinary, FileFormat::kNpy,
                                  FileFormat::kMat5, FileFormat::kMat73, FileFormat::kHdf5},
                                 momentid::parse_file_format);
    check_round_trip<momentid::Status>(
        {momentid::Status::kOk, momentid::Status::kUntested, momentid::Status::kDoubtful,
         momentid::Status::kRankDeficient, momentid::Status::kNothingIdentifiable},
        momentid::parse_status);
    check_round_trip<momentid::Method>(
        {momentid::Method::kAuto, momentid::Method::kZeroLag, momentid::Method::kLagged},
        momentid::parse_method);
  }

  TEST_CASE("a bad name is a usage error of its option that lists the accepted names") {
    CHECK_THROWS_WITH_AS(momentid::parse_input_hold("held", "hold"),
                         "hold: expected sample or zoh, found 'held'", UsageError);
    CHECK_THROWS_WITH_AS(momentid::parse_missing_values("skip", "missing"),
                         "missing: expected error, drop-row or split-run, found 'skip'",
                         UsageError);
    CHECK_THROWS_WITH_AS(momentid::parse_interpolation("spline", "interpolation"),
                         "interpolation: expected zoh, foh, cubic or sinc, found 'spline'",
                         UsageError);
    CHECK_THROWS_WITH_AS(momentid::parse_weighting("GMM", "weighting"),
                         "weighting: expected auto, ls or gmm, found 'GMM'", UsageError);
    CHECK_THROWS_WITH_AS(momentid::parse_file_format("", "format"),
                         "format: expected csv, bin, npy, mat, mat73 or h5, found ''", UsageError);
    try {
      momentid::parse_input_hold("held", "hold");
    } catch (const UsageError& e) {
      CHECK(e.option() == "hold");
    }
  }

  TEST_CASE(
      "a usage error names its option and the options it mentions as a front end spells "
      "them") {
    const UsageError error(
        "noise", "channel 'v' is not observed (" + UsageError::mention("observe") + " y,x)");
    CHECK(std::string(error.what()) == "noise: channel 'v' is not observed (observe y,x)");
    const auto flag = [](const std::string& field) { return "--" + field; };
    CHECK(error.text(flag) == "--noise: channel 'v' is not observed (--observe y,x)");
    const UsageError plain("no file matches 'x'");
    CHECK(plain.option().empty());
    CHECK(plain.text(flag) == "no file matches 'x'");
  }
}
