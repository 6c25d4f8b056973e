#pragma once
// Writers of the array formats that `momentid convert` produces besides CSV and binary: NumPy
// .npy, MATLAB .mat (levels 5 and 7.3) and HDF5. Each writes whole or not at all: the file is
// filled under a temporary name beside the target and renamed into place by commit().

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "momentid/metadata.hpp"

namespace momentid::data {

class ArrayWriter {
 public:
  virtual ~ArrayWriter() = default;
  // `count` rows, row-major, one value per column.
  virtual void rows(const double* values, std::size_t count) = 0;
  // Throws Error when the file cannot be completed.
  virtual void commit() = 0;
};

// A 2-D float64 array, rows x columns, C order. The format keeps neither names nor metadata.
std::unique_ptr<ArrayWriter> open_npy_writer(const std::string& path, std::size_t columns,
                                             std::size_t rows);
// One double vector per column, named as the column where that is a MATLAB name (otherwise made
// one: `t [s]` becomes `t__s_`), `dt` as a scalar when the metadata give it, and the metadata
// lines in the text variable `momentid_metadata`. Level 7.3 is HDF5 underneath.
std::unique_ptr<ArrayWriter> open_mat_writer(const std::string& path,
                                             const std::vector<std::string>& columns,
                                             const DataMetadata& metadata, std::size_t rows,
                                             bool level_73);
// One float64 dataset per column at the root (a '/' in a name becomes '_'), written in chunks;
// the metadata as root attributes (`dt` a number, the rest text).
std::unique_ptr<ArrayWriter> open_hdf5_writer(const std::string& path,
                                              const std::vector<std::string>& columns,
                                              const DataMetadata& metadata, std::size_t rows);

// A fingerprint of a column's values (FNV-1a over their 64-bit patterns), taken as they are
// written and again as they are read back; or of a file's bytes, one at a time.
class ColumnHash {
 public:
  void add(const double* values, std::size_t count);
  void add_bytes(const unsigned char* bytes, std::size_t count);
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 14695981039346656037ULL;
};

// Whether the HDF5 file at `path` holds a float64 dataset of `rows` values under each of `names`
// whose values hash to `hashes` (one per name): what the HDF5 writer checks before its file
// takes the target's name.
bool hdf5_holds(const std::string& path, const std::vector<std::string>& names, std::size_t rows,
                const std::vector<std::uint64_t>& hashes);

// For a program (the command line) that reports every error itself, once at its start: HDF5
// (also under .mat level 7.3) prints no diagnostic stack of its own, and skips its clean-up at
// exit, which crashes after a file failed to close (a full disk).
void quiet_array_libraries();

// A MATLAB variable name for `name`: letters, digits and '_', beginning with a letter, at most
// 63 characters.
std::string matlab_name(const std::string& name);

}  // namespace momentid::data
