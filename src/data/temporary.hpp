#pragma once
// The temporary files that remove_partial_output_on_interrupt() deletes when a signal ends the
// program: the output being written, one at a time, for every writer (OutputFile, and the .mat
// and HDF5 writers whose libraries open the file themselves); and the file a stream (standard
// input, a pipe) is stored in (DataSource::stored).

#include <string>

namespace momentid::data {

enum class Temporary { kOutput, kStored };

void remember_temporary(const std::string& path, Temporary which = Temporary::kOutput);
// Once the file is moved into place or removed.
void forget_temporary(Temporary which = Temporary::kOutput);
// Creates a file named by the template `path` (ending in XXXXXX, which it fills in, as mkstemp)
// and remembers it, no interrupt arriving in between; its descriptor, or -1 with errno set.
int create_temporary(std::string& path, Temporary which = Temporary::kOutput);

}  // namespace momentid::data
