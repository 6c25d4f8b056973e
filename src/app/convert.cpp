#include "momentid/convert.hpp"

#ifdef MOMENTID_WITH_HDF5
#include <hdf5.h>
#endif
#ifdef MOMENTID_WITH_MATIO
#include <matio.h>
#endif

#include <algorithm>
#include <filesystem>

#include "app/variables.hpp"
#include "common/decimal.hpp"
#include "data/header.hpp"
#include "momentid/writer.hpp"

namespace momentid {

std::string data_formats() {
  std::string out = "CSV, momentid binary, NumPy .npy";
#ifdef MOMENTID_WITH_MATIO
  int major = 0, minor = 0, release = 0;
  Mat_GetLibraryVersion(&major, &minor, &release);
  out += ", MATLAB .mat levels 5 and 7.3 (matio " + std::to_string(major) + "." +
         std::to_string(minor) + "." + std::to_string(release) + ")";
#endif
#ifdef MOMENTID_WITH_HDF5
  unsigned hdf5_major = 0, hdf5_minor = 0, hdf5_release = 0;
  H5get_libversion(&hdf5_major, &hdf5_minor, &hdf5_release);
  out += ", HDF5 (" + std::to_string(hdf5_major) + "." + std::to_string(hdf5_minor) + "." +
         std::to_string(hdf5_release) + ")";
#endif
  out += "; all read and written";
#ifndef MOMENTID_WITH_MATIO
  out += "; built without matio: no .mat";
#endif
#ifndef MOMENTID_WITH_HDF5
  out += "; built without HDF5: no HDF5";
#endif
  return out;
}

std::optional<FileFormat> format_for_path(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (extension == ".csv" || extension == ".txt") return FileFormat::kCsv;
  if (extension == ".bin") return FileFormat::kBinary;
  if (extension == ".npy") return FileFormat::kNpy;
  if (extension == ".mat") return FileFormat::kMat5;
  if (extension == ".h5" || extension == ".hdf5") return FileFormat::kHdf5;
  return std::nullopt;
}

FileFormat simulation_format(const std::string& path, std::optional<FileFormat> asked,
                             const std::string& format_option, const std::string& output_option) {
  const auto same = [](FileFormat a, FileFormat b) {
    const auto level = [](FileFormat f) { return f == FileFormat::kMat73 ? FileFormat::kMat5 : f; };
    return level(a) == level(b);
  };
  if (path == "-") {
    if (asked && *asked != FileFormat::kCsv && *asked != FileFormat::kBinary &&
        *asked != FileFormat::kNpy) {
      throw UsageError(format_option, "standard output takes csv, bin or npy, not " +
                                          to_string(*asked) + ": name a file with " +
                                          UsageError::mention(output_option));
    }
    return asked.value_or(FileFormat::kCsv);
  }
  const std::optional<FileFormat> named = format_for_path(path);
  if (asked && named && !same(*asked, *named)) {
    throw UsageError(format_option, to_string(*asked) + " contradicts the output file's name '" +
                                        path + "' (" + to_string(*named) + "): give one of them");
  }
  if (asked) return *asked;
  if (named) return *named;
  if (std::filesystem::path(path).extension().empty()) return FileFormat::kCsv;
  throw UsageError(output_option, "cannot tell the format of '" + path +
                                      "' from its name (.csv, .txt, .bin, .npy, .mat, .h5, "
                                      ".hdf5): give " +
                                      UsageError::mention(format_option));
}

namespace {

// Hands every block of `reader` to `take`. A file of `source` that changed meanwhile is said as
// such, also when the reader has met what a cut leaves (a malformed last row).
template <class Take>
void read_blocks(const DataSource& source, DataReader& reader, Take take) {
  DataBlock block;
  try {
    while (reader.next(block, 1 << 16)) take(block);
  } catch (const Error&) {
    source.check_unchanged();
    throw;
  }
  source.check_unchanged();
}

}  // namespace

std::vector<std::string> convert(const DataSource& source, const std::string& path,
                                 FileFormat format, const FileLayout& layout,
                                 std::optional<double> dt) {
  const std::vector<std::string> columns = data_columns(source, {.layout = layout});
  const ColumnRequest request{
      .names = columns, .rename = {}, .min_rows = 1, .dt = dt, .layout = layout};
  const bool has_time = std::any_of(columns.begin(), columns.end(), [&](const std::string& c) {
    return c == "t" || data::is_time_name(c);
  });
  if (dt && has_time) {
    throw UsageError("dt",
                     source.name() + " has a time column, which is copied and gives the interval");
  }
  // The array formats are given their length first: one pass counts the rows.
  std::optional<std::size_t> rows;
  if (format != FileFormat::kCsv && format != FileFormat::kBinary) {
    const auto counter = source.open(request);
    read_blocks(source, *counter, [](const DataBlock&) {});
    rows = counter->rows_read();
  }
  const auto reader = source.open(request);
  DataMetadata metadata = reader->metadata();
  const auto interval = reader->time_step();
  if (!has_time && interval && (dt || !metadata.get("dt"))) {
    metadata.add_line({{"dt", shortest_decimal(*interval)}});
  }
  DataWriter out(path, format, metadata, columns, rows);
  read_blocks(source, *reader,
              [&](const DataBlock& block) { out.rows(block.values.data(), block.rows); });
  out.commit();
  std::vector<std::string> notes;
  if (auto note = out.note()) notes.push_back(std::move(*note));
  return notes;
}

}  // namespace momentid
