#pragma once
// A record read whole for validate and simulate --input-file (and written back with its
// replay), and the facts about its runs that the replay and the comparison share.

#include <cstddef>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "momentid/error.hpp"
#include "momentid/validate.hpp"

namespace momentid {

// The start of a file, where errors about a record as a whole point.
SourceLocation file_start(const std::string& name);

// Reads the columns of the model's variables that `source` has, and every input (one the data
// lack is reported as a missing column), run by run, the first `most_rows` rows. Throws
// DataError when the data give no sample interval.
Record read_record(const Model& model, const DataSource& source, const ReplayOptions& options,
                   std::size_t most_rows = std::numeric_limits<std::size_t>::max());

// Removes from the column of each variable named in `center` its mean over every run, and
// returns the means removed, by name; a variable without a column is left alone.
std::map<std::string, double> center_record(const Model& model, Record& record,
                                            const std::vector<std::string>& center);

// Subtracts from the column of each variable named in `means` that value (the means a pass
// removed, IdentifyResult::centered); a variable without a column is left alone.
void remove_means(const Model& model, Record& record, const std::map<std::string, double>& means);

// The input columns of a run, in model order.
std::vector<std::vector<double>> run_inputs(const Model& model, const Record& record,
                                            const RecordRun& run);

// The time of a run's first row (0 without a `t` column).
double run_start(const RecordRun& run);

// The label of run `r` in messages: its `run` column's value, else its number from 1.
std::size_t run_label(const Record& record, std::size_t r);

}  // namespace momentid
