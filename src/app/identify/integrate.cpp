// identify --integrate: the column each named state is formed from, and the corner of the
// high-pass filter the pass puts every channel through, chosen from the record's band when not
// given (docs/model-language.md, "Forming a state from its acceleration").

#include "app/identify/integrate.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <unsupported/Eigen/FFT>

#include "common/number.hpp"
#include "momentid/lagged.hpp"
#include "moments/integration.hpp"

namespace momentid {
namespace {

// The record's column of a model variable (IdentifyOptions' record columns rename it).
std::string column_of(const std::string& variable, const IdentifyOptions& options) {
  const auto renamed = options.record.columns.find(variable);
  return renamed == options.record.columns.end() ? variable : renamed->second;
}

// The band is read from the first rows of the record, in Welch segments of at most kSegment
// rows (0.25 Hz at 2048 Hz): its lower edge is where the power below it reaches kEdge of the
// whole, and the corner is half of that.
constexpr std::size_t kSpectrumRows = std::size_t{1} << 18;
constexpr std::size_t kSegment = 8192;
constexpr double kEdge = 0.01;

// The first rows of the record's column for variable `name`, and the sample interval.
std::pair<std::vector<double>, std::optional<double>> first_rows(const DataSource& source,
                                                                 const std::string& name,
                                                                 const RecordOptions& record) {
  const std::unique_ptr<DataReader> reader = source.open(
      {.names = {name}, .rename = record.columns, .min_rows = 2, .layout = record.layout});
  std::vector<double> out;
  DataBlock block;
  while (out.size() < kSpectrumRows && reader->next(block, kSpectrumRows - out.size())) {
    if (block.run_starts && !out.empty()) break;  // the first run
    out.insert(out.end(), block.values.begin(),
               block.values.begin() + static_cast<long>(block.rows));
  }
  return {out, record.dt ? record.dt : reader->time_step()};
}

// Welch's estimate of the power spectrum of `x` on the bins k = 0..n/2 of segments of n rows
// (Hann windows, half overlapping, the mean of each removed).
std::vector<double> power_spectrum(const std::vector<double>& x, std::size_t n) {
  Eigen::FFT<double> fft;
  std::vector<double> window(n), segment(n), power(n / 2 + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    window[i] = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * static_cast<double>(i) /
                                     static_cast<double>(n));
  }
  std::vector<std::complex<double>> spectrum;
  for (std::size_t start = 0; start + n <= x.size(); start += n / 2) {
    double mean = 0;
    for (std::size_t i = 0; i < n; ++i) mean += x[start + i];
    mean /= static_cast<double>(n);
    for (std::size_t i = 0; i < n; ++i) segment[i] = (x[start + i] - mean) * window[i];
    fft.fwd(spectrum, segment);
    for (std::size_t k = 0; k < power.size(); ++k) power[k] += std::norm(spectrum[k]);
  }
  return power;
}

// The default corner (Hz) from the first rows `x` of `column`, with how it was found.
std::pair<double, std::string> band_corner(const DataSource& source, const std::vector<double>& x,
                                           const std::string& column, double dt) {
  std::size_t n = kSegment;
  while (n > 256 && 4 * n > x.size()) n /= 2;
  if (x.size() < 2 * n) {
    throw DataError({source.name(), 1, 1, ""},
                    "the record's first run has " + std::to_string(x.size()) +
                        " rows, too few to find the band for " + UsageError::mention("integrate") +
                        ": give the corner with " + UsageError::mention("integrate_corner"));
  }
  const std::vector<double> power = power_spectrum(x, n);
  double total = 0;
  for (std::size_t k = 1; k < power.size(); ++k) total += power[k];
  double below = 0;
  std::size_t edge = 1;
  while (edge + 1 < power.size() && below + power[edge] < kEdge * total) below += power[edge++];
  // The corner lies at least two bins above 0, where the spectrum resolves it.
  const double bin = 1 / (static_cast<double>(n) * dt);
  const double lower = static_cast<double>(edge) * bin;
  const std::string share = number(100 * kEdge, "%.2g") + "% of its power";
  const std::string spectrum = "Welch spectrum of the first " + std::to_string(x.size()) + " rows";
  if (lower / 2 < 2 * bin) {
    return {2 * bin, "twice the " + number(bin, "%.3g") + " Hz resolution of the " + spectrum +
                         " of '" + column + "', which has " + share + " below " +
                         number(lower, "%.3g") + " Hz"};
  }
  return {lower / 2, "half of " + number(lower, "%.3g") + " Hz, below which '" + column + "' has " +
                         share + " (" + spectrum + ")"};
}

// The states IdentifyOptions::integrate names, each with the column it is formed from, which
// must show it only as its integral (with coefficient 1); marks them present.
std::vector<IdentifyResult::Integration::Formed> formed_states(const Model& model,
                                                               const IdentifyOptions& options,
                                                               std::vector<bool>& present) {
  std::vector<IdentifyResult::Integration::Formed> out;
  const std::vector<VariableReading> readings = variable_readings(model, present);
  for (const std::string& name : options.integrate) {
    const auto v = static_cast<std::size_t>(model.variable_index(name));
    const VariableReading& r = readings[v];
    if (present[v]) {
      throw UsageError("integrate", "the record has a column for '" + name + "'");
    }
    if (r.base < 0 || r.order >= 0) {
      throw UsageError("integrate",
                       "'" + name + "' is not the integral of a column of the record" +
                           (r.base >= 0 ? " (the equations read it as a derivative)" : ""));
    }
    if (r.scale != 1) {
      throw UsageError("integrate", "'" + name +
                                        "' is a multiple of the integral of a column: "
                                        "write its kinematic equation with coefficient 1");
    }
    const std::string& base = model.variables()[static_cast<std::size_t>(r.base)].name;
    out.push_back({name, base, column_of(base, options), -r.order});
  }
  for (const std::string& name : options.integrate) {
    present[static_cast<std::size_t>(model.variable_index(name))] = true;
  }
  return out;
}

// The instruments given: each holds at most one factor of the states formed and the columns they
// are formed from, whose noise the lagged equations share across lags and are corrected for to
// first order (lagged_rows).
void check_instruments(const Model& model, const IdentifyOptions& options,
                       const std::vector<IdentifyResult::Integration::Formed>& formed) {
  if (!options.instruments) return;
  for (const Monomial& instrument : *options.instruments) {
    int sharing = 0;
    for (const auto& f : formed) {
      for (const std::string& name : {f.state, f.variable}) {
        sharing += instrument[static_cast<std::size_t>(model.variable_index(name))];
      }
    }
    if (sharing > 1) {
      throw UsageError("instruments",
                       "instrument '" + format_monomial(model, instrument) +
                           "' holds more than one factor of the states formed (" +
                           UsageError::mention("integrate") +
                           ") and the columns they are formed from, whose noise the equations "
                           "share across lags: give such instruments to the first power, alone "
                           "or times other channels");
    }
  }
}

// The filter's corner (given, or from the band of `rows` of the guide column) and length, raised
// until the filter fills at most a quarter of a first run read to its end, and the formed
// states' noise gains; DataError when the filter would take half of that run.
void fit_filter(IdentifyResult::Integration& out, const DataSource& source,
                const std::vector<double>& rows, const std::string& column,
                const IdentifyOptions& options) {
  if (options.integrate_corner) {
    out.corner = *options.integrate_corner;
  } else {
    std::tie(out.corner, out.band) = band_corner(source, rows, column, out.dt);
    out.corner_chosen = true;
  }
  if (!(out.corner * out.dt < 0.25)) {
    throw UsageError("integrate_corner",
                     "expected a corner below a quarter of the sampling rate (" +
                         number(0.25 / out.dt, "%.6g") + " Hz), found " +
                         number(out.corner, "%.6g") + " Hz");
  }
  const auto length = [&](double corner) {
    try {
      return IntegrationFilter({.corner = corner, .dt = out.dt, .integrals = {0, 1, 2}}).warm_up();
    } catch (const std::invalid_argument&) {
      throw UsageError("integrate_corner", "a corner of " + number(corner, "%.3g") +
                                               " Hz is too low for a filter at this sample "
                                               "interval");
    }
  };
  out.settle = length(out.corner);
  // A chosen corner rises until the filter fills at most a quarter of a first run read to its
  // end: its length falls as the corner rises.
  const bool whole_run = rows.size() < kSpectrumRows;
  if (out.corner_chosen && whole_run && 4 * out.settle > rows.size()) {
    const double chosen = out.corner;
    while (4 * out.settle > rows.size() && (out.corner * 1.25) * out.dt < 0.25) {
      out.corner *= 1.25;
      out.settle = length(out.corner);
    }
    out.band += ", raised from " + number(chosen, "%.3g") +
                " Hz so that the filter fills at most a quarter of the first run";
  }
  const IntegrationFilter filter({.corner = out.corner, .dt = out.dt, .integrals = {0, 1, 2}});
  for (auto& formed : out.formed) {
    formed.noise_gain =
        filter.noise_gain(static_cast<std::size_t>(formed.integrals)) / filter.noise_gain(0);
  }
  // A first run read to its end that the filter's length would take half of.
  if (whole_run && 2 * out.settle > rows.size()) {
    throw DataError({source.name(), 1, 1, ""},
                    "forming " + out.formed.front().state + " (" +
                        UsageError::mention("integrate") + ") takes a high-pass at " +
                        number(out.corner, "%.3g") + " Hz whose length, " +
                        std::to_string(out.settle) +
                        " rows at the start of each run, is more "
                        "than half of the first run's " +
                        std::to_string(rows.size()) + " rows: give a longer record or a higher " +
                        UsageError::mention("integrate_corner"));
  }
}

}  // namespace

IdentifyResult::Integration plan_integration(const Model& model, const DataSource& source,
                                             const IdentifyOptions& options,
                                             std::vector<bool>& present) {
  IdentifyResult::Integration out;
  out.formed = formed_states(model, options, present);
  check_instruments(model, options, out.formed);
  // The corner from the band of the force, the first input with a column, else of the column
  // integrated.
  std::string guide = out.formed.front().variable;
  for (std::size_t i = 0; i < model.inputs().size(); ++i) {
    if (present[model.states().size() + i]) {
      guide = model.inputs()[i].name;
      break;
    }
  }
  const auto [rows, dt] = first_rows(source, guide, options.record);
  if (!dt) {
    throw DataError({source.name(), 1, 1, ""},
                    "forming a state (" + UsageError::mention("integrate") +
                        ") needs the sample interval: give the data a 't' column or a dt in the "
                        "metadata, or give " +
                        UsageError::mention("dt"));
  }
  out.dt = *dt;
  fit_filter(out, source, rows, column_of(guide, options), options);
  return out;
}

}  // namespace momentid
