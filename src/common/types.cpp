#include "momentid/types.hpp"

#include <utility>

#include "momentid/error.hpp"

namespace momentid {
namespace {

template <class Enum>
using Names = std::initializer_list<std::pair<Enum, const char*>>;

// The one table per enum: its values and their names, in the order messages list them.
constexpr Names<InputHold> kInputHolds = {{InputHold::kSample, "sample"},
                                          {InputHold::kZeroOrderHold, "zoh"}};
constexpr Names<MissingValues> kMissingValues = {{MissingValues::kError, "error"},
                                                 {MissingValues::kDropRow, "drop-row"},
                                                 {MissingValues::kSplitRun, "split-run"}};
constexpr Names<Interpolation> kInterpolations = {{Interpolation::kHold, "zoh"},
                                                  {Interpolation::kLinear, "foh"},
                                                  {Interpolation::kCubic, "cubic"},
                                                  {Interpolation::kSinc, "sinc"}};
constexpr Names<Weighting> kWeightings = {
    {Weighting::kAuto, "auto"}, {Weighting::kLeastSquares, "ls"}, {Weighting::kGmm, "gmm"}};
constexpr Names<FileFormat> kFileFormats = {
    {FileFormat::kCsv, "csv"},  {FileFormat::kBinary, "bin"},  {FileFormat::kNpy, "npy"},
    {FileFormat::kMat5, "mat"}, {FileFormat::kMat73, "mat73"}, {FileFormat::kHdf5, "h5"}};
constexpr Names<Method> kMethods = {
    {Method::kAuto, "auto"}, {Method::kZeroLag, "zero-lag"}, {Method::kLagged, "lagged"}};
constexpr Names<Status> kStatuses = {{Status::kOk, "ok"},
                                     {Status::kUntested, "untested"},
                                     {Status::kDoubtful, "doubtful"},
                                     {Status::kRankDeficient, "rank-deficient"},
                                     {Status::kNothingIdentifiable, "nothing-identifiable"}};
constexpr Names<InputKind> kInputKindes = {{InputKind::kMovingAverage, "ma"},
                                           {InputKind::kOrnsteinUhlenbeck, "ou"},
                                           {InputKind::kWhite, "white"},
                                           {InputKind::kMultisine, "multisine"}};

template <class Enum>
std::string name_in(Names<Enum> names, Enum value) {
  for (const auto& [v, name] : names) {
    if (v == value) return name;
  }
  return "";  // not reached: every table names every value
}

template <class Enum>
std::vector<std::string> list(Names<Enum> names) {
  std::vector<std::string> out;
  for (const auto& entry : names) out.emplace_back(entry.second);
  return out;
}

// "a, b or c".
std::string choices(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    out += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  }
  return out;
}

template <class Enum>
Enum parse_in(Names<Enum> names, std::string_view text, std::string_view option) {
  for (const auto& [value, name] : names) {
    if (text == name) return value;
  }
  throw UsageError(std::string(option),
                   "expected " + choices(list(names)) + ", found '" + std::string(text) + "'");
}

}  // namespace

std::string to_string(InputHold hold) { return name_in(kInputHolds, hold); }
std::string to_string(MissingValues missing) { return name_in(kMissingValues, missing); }
std::string to_string(Interpolation method) { return name_in(kInterpolations, method); }
std::string to_string(Weighting weighting) { return name_in(kWeightings, weighting); }
std::string to_string(FileFormat format) { return name_in(kFileFormats, format); }
std::string to_string(Method method) { return name_in(kMethods, method); }
std::string to_string(Status status) { return name_in(kStatuses, status); }
std::string to_string(InputKind process) { return name_in(kInputKindes, process); }

InputHold parse_input_hold(std::string_view text, std::string_view option) {
  return parse_in(kInputHolds, text, option);
}
MissingValues parse_missing_values(std::string_view text, std::string_view option) {
  return parse_in(kMissingValues, text, option);
}
Interpolation parse_interpolation(std::string_view text, std::string_view option) {
  return parse_in(kInterpolations, text, option);
}
Weighting parse_weighting(std::string_view text, std::string_view option) {
  return parse_in(kWeightings, text, option);
}
FileFormat parse_file_format(std::string_view text, std::string_view option) {
  return parse_in(kFileFormats, text, option);
}
Method parse_method(std::string_view text, std::string_view option) {
  return parse_in(kMethods, text, option);
}
Status parse_status(std::string_view text, std::string_view option) {
  return parse_in(kStatuses, text, option);
}
InputKind parse_input_kind(std::string_view text, std::string_view option) {
  return parse_in(kInputKindes, text, option);
}

template <>
std::vector<std::string> names_of<InputHold>() {
  return list(kInputHolds);
}
template <>
std::vector<std::string> names_of<MissingValues>() {
  return list(kMissingValues);
}
template <>
std::vector<std::string> names_of<Interpolation>() {
  return list(kInterpolations);
}
template <>
std::vector<std::string> names_of<Weighting>() {
  return list(kWeightings);
}
template <>
std::vector<std::string> names_of<FileFormat>() {
  return list(kFileFormats);
}
template <>
std::vector<std::string> names_of<Method>() {
  return list(kMethods);
}
template <>
std::vector<std::string> names_of<Status>() {
  return list(kStatuses);
}
template <>
std::vector<std::string> names_of<InputKind>() {
  return list(kInputKindes);
}

}  // namespace momentid
