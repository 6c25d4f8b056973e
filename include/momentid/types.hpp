#pragma once
// The enums that have a text form, and their names: one table per enum, read by the command
// line, the Python module, the data files' metadata and the reports alike (Ceres' types.h).
//
// For each enum E: `to_string(E)` is its name, `parse_e(text, option)` the value of a name,
// which throws UsageError for any other text, naming `option` (the options field the text is
// for, e.g. "hold") and the accepted names: "hold: expected sample or zoh, found 'x'".
// `names_of<E>()` lists the names in order, for a front end's list of choices.
//
// Example:
//   InputHold hold = parse_input_hold("zoh", "hold");  // InputHold::kZeroOrderHold
//   to_string(hold);                                    // "zoh"

#include <string>
#include <string_view>
#include <vector>

namespace momentid {

// How the input channels were sampled (docs/moments.md, "Sampled and held inputs").
//  kSample: every channel holds samples of a continuous signal at the same instants; a moment is
//           the trapezoidal time average of its product.
//  kZeroOrderHold: input row n is held over [t_n, t_{n+1}) (what simulators do); a product with
//           an input is averaged as u[n] * (g(y_n) + g(y_{n+1})) / 2.
// Names: sample, zoh.
enum class InputHold { kSample, kZeroOrderHold };

// What a missing value (an empty CSV field, `nan`, `NA`, `N/A`; NaN in a binary file) in a
// requested column does. Names: error, drop-row, split-run.
enum class MissingValues {
  kError,     // stops the reading with the value's location (the default)
  kDropRow,   // drops the row; its neighbours are joined as if consecutive
  kSplitRun,  // drops the row and ends the run: the next complete row starts a new one
};

// How a recorded input is taken between its samples, where the integrator needs it
// (docs/cli/validate.md, "Inputs between samples"):
//   kHold    the sample held over the interval that follows it (zero-order hold), which is how
//            `simulate` applies its random processes;
//   kLinear  a straight line between neighbouring samples (first-order hold);
//   kCubic   the cubic through the four nearest samples: at the midpoint, a sinusoid with
//            omega*dt = w comes out with the gain (9 cos(w/2) - cos(3w/2))/8, about
//            1 - 3 w^4/128 (0.35% low at ten samples per period, 5% at five);
//   kSinc    band-limited: a Kaiser-windowed sinc (beta 14) over the 48 nearest samples, whose
//            gain is within 3e-7 of 1 up to 0.8 times the Nyquist frequency.
// Intervals too near an end of the record for the stencil take the widest one that fits
// (cubic, then the quadratic through three samples, then linear).
// Names: zoh (kHold), foh (kLinear), cubic, sinc.
enum class Interpolation { kHold, kLinear, kCubic, kSinc };

// Which estimate identify reports as its main result (IdentifyOptions::weighting): kAuto, the
// optimally weighted one (GMM) with the J test whenever the equations outnumber the
// parameters, else least squares; kLeastSquares; kGmm, the optimally weighted one.
// Names: auto, ls, gmm.
enum class Weighting { kAuto, kLeastSquares, kGmm };

// Which moment equations identify takes (IdentifyOptions::method, docs/measured-data.md):
// kAuto, the lagged ones for measured records, which stay unbiased under white sensor noise,
// and the zero-lag ones for records known to be noise-free (simulate's without noise) or that
// the lagged ones cannot serve; kZeroLag; kLagged. Names: auto, zero-lag, lagged.
enum class Method { kAuto, kZeroLag, kLagged };

// The formats DataWriter writes, which `momentid convert` and `momentid simulate` take as
// --format (docs/cli/convert.md, "momentid convert"; format_for_path() tells them by name).
// Names: csv, bin, npy, mat (level 5), mat73 (level 7.3), h5.
enum class FileFormat { kCsv, kBinary, kNpy, kMat5, kMat73, kHdf5 };

// What an identification came to: kOk, estimates whose model a misfit test (the J test) did not
// reject and that nothing else in the data contradicts; kUntested, estimates that no test could
// check (as many equations as parameters, least squares asked for, or too few batches for the
// optimal weighting); kDoubtful, estimates with doubts (a J test that rejects the model, a
// violated stationarity identity, an offset: identify.hpp, doubts); kRankDeficient, some
// parameters determined only in combinations; kNothingIdentifiable, no estimate. The solver
// reports kOk, kRankDeficient and kNothingIdentifiable.
// Names: ok, untested, doubtful, rank-deficient, nothing-identifiable.
enum class Status { kOk, kUntested, kDoubtful, kRankDeficient, kNothingIdentifiable };

// The random processes and signals that simulate drives an input with (InputSpec, docs/cli/
// simulate.md): a moving average of white noise, an Ornstein-Uhlenbeck process, white noise, a
// multisine. Names: ma, ou, white, multisine.
enum class InputKind { kMovingAverage, kOrnsteinUhlenbeck, kWhite, kMultisine };

std::string to_string(InputHold hold);
std::string to_string(MissingValues missing);
std::string to_string(Interpolation method);
std::string to_string(Weighting weighting);
std::string to_string(Method method);
std::string to_string(FileFormat format);
std::string to_string(Status status);
std::string to_string(InputKind process);

InputHold parse_input_hold(std::string_view text, std::string_view option);
MissingValues parse_missing_values(std::string_view text, std::string_view option);
Interpolation parse_interpolation(std::string_view text, std::string_view option);
Weighting parse_weighting(std::string_view text, std::string_view option);
Method parse_method(std::string_view text, std::string_view option);
FileFormat parse_file_format(std::string_view text, std::string_view option);
Status parse_status(std::string_view text, std::string_view option);
InputKind parse_input_kind(std::string_view text, std::string_view option);

template <class Enum>
std::vector<std::string> names_of();
template <>
std::vector<std::string> names_of<InputHold>();
template <>
std::vector<std::string> names_of<MissingValues>();
template <>
std::vector<std::string> names_of<Interpolation>();
template <>
std::vector<std::string> names_of<Weighting>();
template <>
std::vector<std::string> names_of<Method>();
template <>
std::vector<std::string> names_of<FileFormat>();
template <>
std::vector<std::string> names_of<Status>();
template <>
std::vector<std::string> names_of<InputKind>();

}  // namespace momentid
