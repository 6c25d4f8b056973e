#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "momentid/types.hpp"

namespace momentid {

// The key-value pairs a data file carries in `# momentid: key=value key=value ...` lines before
// its header row, e.g. `dt=0.01 input-hold=zoh model=duffing seed=1`. Keys and values hold no
// blanks; a key given twice means its last value. The lines are kept as they were read or
// added, so that metadata copied from one file to another reads the same.
//
// Known keys: `dt` (the sample interval, a positive number), `input-hold` (`zoh` or `sample`;
// `momentid simulate` writes `mixed` for held and sampled inputs together, with
// `input-hold.NAME` per input); `momentid simulate` also writes the model, the seed, the
// parameter values (`param.NAME`), the input processes (`input.NAME`) and, when asked for, the
// written channels (`observe`) and the measurement noise (`noise.NAME`, relative, and
// `noise-sd.NAME`, absolute).
//
// Example:
//   DataMetadata m;
//   m.add_line({{"dt", "0.01"}, {"input-hold", "zoh"}});
//   m.get("dt");  // "0.01"
//   m.text();     // "# momentid: dt=0.01 input-hold=zoh\n"
class DataMetadata {
 public:
  using Line = std::vector<std::pair<std::string, std::string>>;

  // The last value given for `key`, if any.
  std::optional<std::string> get(const std::string& key) const;
  // How input `input` was sampled: `input-hold`, or under `mixed` its `input-hold.NAME`; kSample
  // when the metadata do not say (or name a hold this version does not know). Without a name,
  // how every input was: kSample for `mixed`.
  InputHold input_hold(const std::string& input = "") const;
  void add_line(Line line);
  const std::vector<Line>& lines() const { return lines_; }
  // The number of distinct keys.
  std::size_t size() const;
  // The lines as a data file holds them, each `# momentid: ` and its pairs, ended by a newline.
  std::string text() const;

 private:
  std::vector<Line> lines_;
};

}  // namespace momentid
