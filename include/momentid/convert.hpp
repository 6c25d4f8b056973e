#pragma once

#include <optional>
#include <string>
#include <vector>

#include "momentid/reader.hpp"
#include "momentid/types.hpp"

namespace momentid {

// By the name's extension: .csv and .txt, .bin, .npy, .mat (level 5), .h5 and .hdf5; nullopt for
// another. Level 7.3 .mat files are asked for by name: "mat73".
std::optional<FileFormat> format_for_path(const std::string& path);

// The format simulate writes `path` in (`-o`, also with `--input-file`): `asked` (--format), else
// the one the path's extension names (format_for_path: .csv and .txt, .bin, .npy, .mat, .h5 and
// .hdf5), and CSV for standard output "-" and for a name without an extension (a device, a pipe,
// `record`). Throws UsageError, under `output_option`, for a name whose extension no format has
// (`run.xyz`, `run.csv.gz`) unless `asked` says the format; and, under `format_option`, when
// `asked` contradicts the name (`bin` for `run.mat`; `mat` and `mat73` are both `.mat`) or is a
// .mat or HDF5 file on standard output, which DataWriter cannot stream: nothing is written as
// something else than its name says.
FileFormat simulation_format(const std::string& path, std::optional<FileFormat> asked,
                             const std::string& format_option = "format",
                             const std::string& output_option = "output");

// Copies every column of `source` (`t` and `run` included), read with `layout` and the sample
// interval `dt` when given, into `path` in `format`, whole or not at all, with the metadata
// (and `dt` when the interval came from elsewhere than a time column), as DataWriter writes it.
// Returns what the reader of the new file should know (DataWriter::note(): NumPy files keep
// neither column names nor metadata). Throws as DataReader does, and Error when the file cannot
// be written.
//
// Example:
//   convert(DataSource::file("run.mat"), "run.h5", FileFormat::kHdf5, {});
std::vector<std::string> convert(const DataSource& source, const std::string& path,
                                 FileFormat format, const FileLayout& layout = {},
                                 std::optional<double> dt = std::nullopt);

// The data formats of this build, with the versions of the libraries behind them, e.g. "CSV,
// momentid binary, NumPy .npy, MATLAB .mat levels 5 and 7.3 (matio 1.5.23), HDF5 (1.10.8); all
// read and written".
std::string data_formats();

}  // namespace momentid
