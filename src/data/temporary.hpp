#pragma once
// The temporary file an output is being written to, which remove_partial_output_on_interrupt()
// deletes when a signal ends the program: one at a time, for every writer (OutputFile, and the
// .mat and HDF5 writers whose libraries open the file themselves).

#include <string>

namespace momentid::data {

void remember_temporary(const std::string& path);
// Once the file is moved into place or removed.
void forget_temporary();
// Creates a file named by the template `path` (ending in XXXXXX, which it fills in, as mkstemp)
// and remembers it, no interrupt arriving in between; its descriptor, or -1 with errno set.
int create_temporary(std::string& path);

}  // namespace momentid::data
