#pragma once

#include <string>
#include <vector>

#include "momentid/model.hpp"
#include "momentid/reader.hpp"
#include "momentid/record_options.hpp"

namespace momentid {

// The column names of `source`, as a reader with the record's column map and layout sees them (a
// 2-D .npy array is named by FileLayout::column_names, a .npy file named in `columns` is a
// column). Reads the header only.
std::vector<std::string> data_columns(const DataSource& source, const RecordOptions& record);

// Per model variable (states, then inputs): whether `source` has its column, under the name
// RecordOptions::columns maps it to (model name -> data column) or its own. Reads the header only.
std::vector<bool> variables_present(const Model& model, const DataSource& source,
                                    const RecordOptions& record);

// What identify needs to know of a record before its pass, from its header and metadata.
struct RecordSurvey {
  std::vector<bool> present;  // per model variable, as variables_present
  // The metadata say that `momentid simulate` wrote the record and added no measurement noise.
  bool noise_free = false;
  // The record carries metadata (a file's `# momentid:` lines, a Python Record's).
  bool described = false;
  // The record gives a sample interval: RecordOptions::dt, the metadata or a time column.
  bool timed = false;
};
RecordSurvey survey_record(const Model& model, const DataSource& source,
                           const RecordOptions& record);

}  // namespace momentid
