#pragma once
// The temporary file an output is being written to, which remove_partial_output_on_interrupt()
// deletes when a signal ends the program: one at a time, for every writer (OutputFile, and the
// .mat and HDF5 writers whose libraries open the file themselves).

#include <string>

namespace momentid::data {

void remember_temporary(const std::string& path);
// Once the file is moved into place or removed.
void forget_temporary();

}  // namespace momentid::data
