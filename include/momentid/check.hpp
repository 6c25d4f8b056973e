#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "momentid/accumulator.hpp"
#include "momentid/data_pass.hpp"
#include "momentid/estimate.hpp"
#include "momentid/model.hpp"
#include "momentid/reader.hpp"
#include "momentid/record_options.hpp"

namespace momentid {

// How to check data (docs/cli/check.md, "momentid check").
struct CheckOptions {
  // The record's columns, sample interval, layout and input hold, and the pass's threads,
  // shards and progress (every field is used).
  RecordOptions record;
  std::size_t lags = 9;  // autocorrelations per channel, 1..kMaxLags
  static constexpr std::size_t kMaxLags = 1000;

  // Throws UsageError for a number of lags out of range, or as RecordOptions::validate (with
  // `model`, when there is one).
  void validate(const Model* model) const;
};

// Whether a record suits the moment method: each channel's statistics and autocorrelations,
// warnings about smoothness, and with a model the sample violations of its stationarity
// identities.
struct CheckResult {
  std::string data_name;
  std::size_t lags = 0;
  DataMoments data;
  bool with_model = false;
  std::vector<std::string> missing_inputs;  // model inputs the data lack: states checked only
  // Model states the data lack but show as derivatives (v when y' = v): left out.
  std::vector<std::string> missing_states;
  std::vector<IdentityCheck> identities;  // with a model
  std::vector<std::string> warnings;
};

// Reads `source` once. Without a model every column but `t` and `run` is a channel; with one,
// its states and the inputs the data have. Throws as identify() does.
CheckResult check(const DataSource& source, const Model* model, const CheckOptions& options = {});

// The report `momentid check` prints.
std::string format_text(const CheckResult& result);
// The JSON layout (docs/json.md, "check").
std::string format_json(const CheckResult& result);

}  // namespace momentid
