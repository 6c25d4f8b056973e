// libFuzzer target: any bytes as a data file (in any format: CSV, binary, .npy, .mat, HDF5, as
// chosen by content), read to the end by the reader that `identify` uses, asking for the
// columns y, v and x. Only momentid::Error may escape.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "momentid/reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/tmp/momentid_fuzz_data_" + std::to_string(getpid());
  if (std::FILE* f = std::fopen(path.c_str(), "wb")) {
    std::fwrite(data, 1, size, f);
    std::fclose(f);
  }
  try {
    momentid::ColumnRequest request;
    request.names = {"y", "v", "x"};
    request.min_rows = 1;
    auto reader = momentid::DataReader::open(path, request);
    momentid::DataBlock block;
    while (reader->next(block, 7)) {
    }
    (void)reader->time_step();
  } catch (const momentid::Error&) {
  }
  return 0;
}

// CLN allocates a few bytes at start-up that it never frees; that is not momentid's leak.
extern "C" const char* __lsan_default_suppressions() { return "leak:libcln.so\n"; }
extern "C" const char* __lsan_default_options() { return "print_suppressions=0"; }
