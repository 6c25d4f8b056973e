#pragma once
// The data file formats DataReader::open chooses from, by content. A new format is one source
// file that defines its detector and opener, and one entry in the table in reader.cpp.

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "data/text.hpp"
#include "momentid/reader.hpp"

namespace momentid::data {

// How many bytes at the start of a file the detectors see.
inline constexpr std::size_t kDetectBytes = 8;

// One format: whether a file that starts with `first_bytes` (kDetectBytes, fewer for a shorter
// file) is in it, and how to read it. `open` receives the file positioned just after those
// bytes.
struct DataFormat {
  const char* name;
  bool (*detect)(std::string_view first_bytes);
  std::unique_ptr<DataReader> (*open)(File file, const std::string& path,
                                      const ColumnRequest& request, std::string_view first_bytes);
};

bool is_binary(std::string_view first_bytes);
std::unique_ptr<DataReader> open_binary(File file, const std::string& path,
                                        const ColumnRequest& request, std::string_view first_bytes);

// NumPy .npy (column_store.hpp).
bool is_npy(std::string_view first_bytes);
std::unique_ptr<DataReader> open_npy(File file, const std::string& path,
                                     const ColumnRequest& request, std::string_view first_bytes);

// MATLAB .mat, levels 5 and 7.3 (column_store.hpp).
bool is_mat(std::string_view first_bytes);
std::unique_ptr<DataReader> open_mat(File file, const std::string& path,
                                     const ColumnRequest& request, std::string_view first_bytes);

// HDF5 (column_store.hpp).
bool is_hdf5(std::string_view first_bytes);
std::unique_ptr<DataReader> open_hdf5(File file, const std::string& path,
                                      const ColumnRequest& request, std::string_view first_bytes);

// CSV takes any file the other formats do not recognise.
std::unique_ptr<DataReader> open_csv(File file, const std::string& path,
                                     const ColumnRequest& request, std::string_view first_bytes);

}  // namespace momentid::data

namespace momentid::data {

// Fails (DataError at `file`) unless its sample interval is the first file's, to 1e-6: the
// files of one record need one interval.
void check_file_interval(const std::string& file, const std::optional<double>& step,
                         const std::string& first_file, const std::optional<double>& first_step);
// Reads several files one after the other (DataSource::files).
std::unique_ptr<DataReader> open_chain(const std::vector<std::string>& paths,
                                       const ColumnRequest& request);

// `open(request)`, or, when ColumnRequest::rename maps a name to a sum of columns (column_sum),
// a reader that delivers the sum: it opens the record once for its column names (`name` in
// messages), then with the columns the sums need.
std::unique_ptr<DataReader> open_sums(
    const ColumnRequest& request, const std::string& name,
    const std::function<std::unique_ptr<DataReader>(const ColumnRequest&)>& open);

// Reads columns in memory; `data` must outlive the reader.
std::unique_ptr<DataReader> open_memory(const MemoryData& data, const ColumnRequest& request);

}  // namespace momentid::data
