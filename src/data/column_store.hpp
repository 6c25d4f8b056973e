#pragma once
// Files whose channels are arrays read by name rather than rows of text: MATLAB .mat, HDF5 and
// NumPy .npy. Each format is a ColumnStore; one reader turns any store into rows, so that the
// checks of the other formats (time steps, runs, missing values, too few rows) apply alike.

#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "momentid/reader.hpp"

namespace momentid::data {

// A sample rate or interval that a file states under a name acquisition software uses
// (kStatedIntervalNames): an HDF5 attribute of the file or of a channel's dataset, or a .mat
// scalar.
struct StatedInterval {
  std::string name;   // `fs`, `wf_increment`, ...
  std::string where;  // as messages name it: "attribute 'fs' of the file", "variable 'Fs'"
  std::optional<double> value;  // as stored: a rate or an interval (is_rate); none: unusable
  std::string why;              // why it is unusable: "holds text, not a number"
};

// The names under which files state their sampling: rates, then `wf_increment`, an interval (the
// waveform attribute of National Instruments' files).
inline constexpr const char* kStatedIntervalNames[] = {"fs", "Fs", "sample_rate", "wf_increment"};
inline bool is_rate(const std::string& name) { return name != "wf_increment"; }

// The arrays of one file, as channels of equal length. A matrix of N samples and K columns is K
// channels, `NAME[:, k]` for k from 0.
class ColumnStore {
 public:
  virtual ~ColumnStore() = default;
  // What a channel is called in messages: "variable", "dataset", "column".
  virtual const char* kind() const = 0;
  // The channels' names, in file order.
  virtual std::vector<std::string> names() const = 0;
  // Why `name`, which is not a channel, cannot be one (a text, integer or complex variable, one
  // never written), or nullopt when the file has nothing of that name.
  std::optional<std::string> unusable(const std::string& name) const {
    const auto found = unusable_.find(name);
    if (found == unusable_.end()) return std::nullopt;
    return found->second;
  }
  // Every name unusable() explains, with its reason.
  const std::map<std::string, std::string>& unusable_names() const { return unusable_; }
  // A channel's name as a user may write it (`--columns y=/run1/disp`) in the form of names().
  virtual std::string column_name(const std::string& written) const { return written; }
  // Readies a channel that will be read; throws DataError when it cannot be read.
  virtual void prepare(std::size_t channel) = 0;
  // The number of samples of a prepared channel.
  virtual std::size_t length(std::size_t channel) const = 0;
  // Values [first, first + count) of a prepared channel, as doubles.
  virtual void read(std::size_t channel, std::size_t first, std::size_t count, double* out) = 0;
  // A scalar stored in the file under `name` (`--dt-from`), or nullopt when there is none.
  virtual std::optional<double> scalar(const std::string& name) { return std::nullopt; }
  // The rates and intervals the file states (StatedInterval), for the prepared channels among
  // `channels` and the file.
  virtual std::vector<StatedInterval> stated_intervals(const std::vector<std::size_t>& channels) {
    return {};
  }
  // Metadata the file carries (`dt` among them), as a CSV file's `# momentid:` lines.
  virtual DataMetadata metadata() const { return {}; }

 protected:
  std::map<std::string, std::string> unusable_;  // name -> why it is no channel
};

// Reads a store as rows: the requested channels, `t` (or a time-like name, or the channel `t`
// is renamed to) and `run`; with FileLayout::runs, run after run, each prefix in front of the
// names (the channels a user sees are those of the first run, without its prefix). The sample
// interval comes from ColumnRequest::dt, else from FileLayout::dt_from (a scalar in the file;
// `1/NAME` for a rate), else from the metadata's dt and the intervals the file states
// (StatedInterval), which must agree to 1e-6, else from the time channel, which must agree with
// them too. A stated interval that cannot be used fails when nothing else gives the interval.
// Errors are located at the file, the sample (from 1) as line and the channel's place in names()
// (from 1) as column.
std::unique_ptr<DataReader> open_column_store(std::unique_ptr<ColumnStore> store,
                                              const std::string& path,
                                              const ColumnRequest& request);

}  // namespace momentid::data
