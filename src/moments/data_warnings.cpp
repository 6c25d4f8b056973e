// Warnings about a pass's data for the moment method (data_pass.hpp).

#include <cmath>
#include <cstdio>

#include "momentid/data_pass.hpp"

namespace momentid {

std::string missing_warning(const MissingSummary& missing) {
  const SourceLocation& at = *missing.first;
  std::string text = "dropped " + std::to_string(missing.rows) +
                     (missing.rows == 1 ? " row" : " rows") +
                     " with missing values (the first at " + at.file + ":" +
                     std::to_string(at.line) + ":" + std::to_string(at.column) + ")";
  if (missing.splits > 0) {
    text += " and began a new run at " + std::to_string(missing.splits) +
            (missing.splits == 1 ? " place" : " places");
  }
  if (missing.joins > 0) {
    text += " and joined their neighbours at " + std::to_string(missing.joins) +
            (missing.joins == 1 ? " place" : " places") +
            " as consecutive samples, which is right only for gaps short against the dynamics "
            "(--missing split-run starts a new run instead)";
  }
  return text;
}

std::optional<std::string> outlier_warning(const DataMoments& data) {
  if (data.rows < kOutlierRows) return std::nullopt;
  for (const ChannelStatistics& c : data.channels) {
    const double squares = static_cast<double>(data.rows) * (c.variance + c.mean * c.mean);
    const bool overflows = !std::isfinite(squares);
    if (!overflows && !(c.largest * c.largest > 0.5 * squares)) continue;
    char value[32], share[32];
    std::snprintf(value, sizeof value, "%.6g", c.largest);
    std::snprintf(share, sizeof share, "%.3g%%",
                  overflows ? 100.0 : 100 * c.largest * c.largest / squares);
    return "'" + c.name + "' has a value of magnitude " + value + " at row " +
           std::to_string(c.largest_row + 1) + " of the record that " +
           (overflows ? "has a square beyond the range of doubles"
                      : std::string("carries ") + share + " of the channel's sum of squares") +
           ": one sample decides every moment of it (a spike, a dropout marker, a unit error?). "
           "Correct or remove that row";
  }
  return std::nullopt;
}

std::vector<std::string> data_warnings(const DataMoments& data) {
  std::vector<std::string> out;
  if (data.missing.rows > 0) out.push_back(missing_warning(data.missing));
  for (const ChannelStatistics& c : data.channels) {
    if (c.autocorrelation.empty() || std::isnan(c.autocorrelation[0])) continue;
    const double rho = c.autocorrelation[0];
    char text[32];
    std::snprintf(text, sizeof text, "%.3f", rho);
    if (c.is_input && rho < 0.5) {
      out.push_back("input '" + c.name + "' is nearly white (lag-1 autocorrelation " + text +
                    "): the method needs a smooth input, and the estimates will be biased");
    } else if (!c.is_input && rho < 0.9) {
      out.push_back("sampling is coarse for the dynamics: the lag-1 autocorrelation of '" + c.name +
                    "' is " + text + "; the time averages are biased, sample faster if you can");
    }
  }
  return out;
}

}  // namespace momentid
