// The array formats: .npy, .mat (levels 5 and 7.3) and HDF5, written by convert() and read back
// through DataReader, value for value; the names and choices they share. Files written by other
// programs (numpy, scipy, h5py) are tested in tests/formats/test_formats.py.

#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "data/array_writers.hpp"
#include "momentid/convert.hpp"
#include "momentid/writer.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using momentid::FileFormat;

// A directory of its own, removed at the end.
struct Directory : momentid::testing::Directory {
  Directory() : momentid::testing::Directory("momentid_test_formats") {}
};

// Every column of a file, by name, with its metadata.
struct Table {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
  momentid::DataMetadata metadata;
};

Table read_all(const std::string& path, const momentid::FileLayout& layout = {}) {
  Table out;
  const auto probe =
      momentid::DataReader::open(path, {.names = {}, .min_rows = 0, .layout = layout});
  out.names = probe->columns();
  const auto reader =
      momentid::DataReader::open(path, {.names = out.names, .min_rows = 1, .layout = layout});
  out.columns.resize(out.names.size());
  momentid::DataBlock block;
  while (reader->next(block, 1000)) {
    for (std::size_t r = 0; r < block.rows; ++r) {
      for (std::size_t c = 0; c < out.names.size(); ++c) {
        out.columns[c].push_back(block.values[r * out.names.size() + c]);
      }
    }
  }
  out.metadata = reader->metadata();
  return out;
}

const std::vector<double>& column(const Table& t, const std::string& name) {
  const auto at = std::find(t.names.begin(), t.names.end(), name);
  REQUIRE(at != t.names.end());
  return t.columns[static_cast<std::size_t>(at - t.names.begin())];
}

// A small record with awkward values: subnormal, huge, negative zero, many digits.
std::string write_record(const Directory& dir) {
  momentid::DataMetadata metadata;
  metadata.add_line({{"dt", "0.25"}, {"input-hold", "zoh"}});
  const std::string path = dir / "record.csv";
  momentid::DataWriter out(path, momentid::DataWriter::Format::kCsv, metadata, {"t", "y", "x"});
  const double rows[][3] = {{0, 1.0 / 3, 4.9e-324}, {0.25, -0.0, 1e300},     {0.5, 2.5, -7.125},
                            {0.75, 0.1, 0.2},       {1.0, 123456789.123, 0}, {1.25, -1e-300, 3}};
  for (const auto& row : rows) out.row(row);
  out.commit();
  return path;
}

}  // namespace

TEST_SUITE("formats") {
  TEST_CASE("the format follows the extension, and each name") {
    CHECK(momentid::format_for_path("a/b.CSV") == FileFormat::kCsv);
    CHECK(momentid::format_for_path("b.bin") == FileFormat::kBinary);
    CHECK(momentid::format_for_path("b.npy") == FileFormat::kNpy);
    CHECK(momentid::format_for_path("b.mat") == FileFormat::kMat5);
    CHECK(momentid::format_for_path("b.hdf5") == FileFormat::kHdf5);
    CHECK_FALSE(momentid::format_for_path("b.xlsx"));
    CHECK(momentid::parse_file_format("mat73", "format") == FileFormat::kMat73);
    CHECK_THROWS_WITH_AS(momentid::parse_file_format("xls", "format"),
                         "format: expected csv, bin, npy, mat, mat73 or h5, found 'xls'",
                         momentid::UsageError);
  }

  TEST_CASE("MATLAB names are letters, digits and underscores, from a letter") {
    CHECK(momentid::data::matlab_name("t [s]") == "t__s_");
    CHECK(momentid::data::matlab_name("2nd") == "c_2nd");
    CHECK(momentid::data::matlab_name(std::string(80, 'a')).size() == 63);
  }

  TEST_CASE("every array format keeps every value, bit for bit, and what it can of the rest") {
    const Directory dir;
    const std::string csv = write_record(dir);
    const Table original = read_all(csv);
    for (const auto& [format, file_name] :
         std::vector<std::pair<FileFormat, std::string>>{{FileFormat::kBinary, "r.bin"},
                                                         {FileFormat::kNpy, "r.npy"},
                                                         {FileFormat::kMat5, "r.mat"},
                                                         {FileFormat::kMat73, "r73.mat"},
                                                         {FileFormat::kHdf5, "r.h5"}}) {
      const std::string& name = file_name;  // for CAPTURE, which cannot capture a binding
      CAPTURE(name);
      const auto notes = momentid::convert(momentid::DataSource::file(csv), dir / name, format);
      momentid::FileLayout layout;
      if (format == FileFormat::kNpy) {
        REQUIRE(notes.size() == 1);
        CHECK(notes[0] == "a .npy file keeps neither column names nor metadata: read " +
                              (dir / name) + " with --names t,y,x --input-hold zoh");
        layout.column_names = {"t", "y", "x"};
      }
      const Table copy = read_all(dir / name, layout);
      for (const char* c : {"t", "y", "x"}) {
        const auto& a = column(original, c);
        const auto& b = column(copy, c);
        REQUIRE(a.size() == b.size());
        for (std::size_t i = 0; i < a.size(); ++i) {
          CHECK(std::signbit(a[i]) == std::signbit(b[i]));
          CHECK(a[i] == b[i]);
        }
      }
      if (format != FileFormat::kNpy) {
        CHECK(copy.metadata.get("dt") == "0.25");
        CHECK(copy.metadata.get("input-hold") == "zoh");
      }
    }
  }

  TEST_CASE("an HDF5 file is read back against the hashes of what was written") {
    const Directory dir;
    const std::string csv = write_record(dir);
    const Table original = read_all(csv);
    momentid::convert(momentid::DataSource::file(csv), dir / "r.h5", FileFormat::kHdf5);
    const std::vector<std::string> names{"t", "y", "x"};
    std::vector<std::uint64_t> hashes;
    for (const std::string& name : names) {
      momentid::data::ColumnHash hash;
      hash.add(column(original, name).data(), column(original, name).size());
      hashes.push_back(hash.value());
    }
    const std::size_t rows = column(original, "t").size();
    CHECK(momentid::data::hdf5_holds(dir / "r.h5", names, rows, hashes));
    std::vector<std::uint64_t> changed = hashes;
    ++changed[1];
    CHECK(!momentid::data::hdf5_holds(dir / "r.h5", names, rows, changed));
    CHECK(!momentid::data::hdf5_holds(dir / "r.h5", names, rows + 1, hashes));
    CHECK(!momentid::data::hdf5_holds(dir / "r.h5", {"t", "y", "z"}, rows, hashes));
    CHECK(!momentid::data::hdf5_holds(dir / "missing.h5", names, rows, hashes));
  }

  TEST_CASE("a file that cannot be written leaves nothing behind") {
    const Directory dir;
    const std::string csv = write_record(dir);
    for (const std::string name : {"missing/r.mat", "missing/r.h5", "missing/r.npy"}) {
      CAPTURE(name);
      const auto format = *momentid::format_for_path(name);
      CHECK_THROWS_AS(momentid::convert(momentid::DataSource::file(csv), dir / name, format),
                      momentid::Error);
    }
    CHECK(std::distance(fs::directory_iterator(dir.path), fs::directory_iterator()) == 1);
  }
  TEST_CASE("a .npy file cut short while it is read is a located error, not a crash") {
    const Directory dir;
    const momentid::Model model = momentid::testing::model_file("duffing.mom");
    const std::string csv = dir / "long.csv";
    momentid::simulate_to_file(model, momentid::testing::options_for(model, 200000, 3), csv,
                               momentid::DataWriter::Format::kCsv);
    const std::string npy = dir / "long.npy";
    momentid::convert(momentid::DataSource::file(csv), npy, momentid::FileFormat::kNpy);
    momentid::FileLayout layout;
    layout.column_names = {"t", "y", "v", "x"};
    const auto reader = momentid::DataReader::open(
        npy, {.names = {"y", "v", "x"}, .min_rows = 1, .layout = layout});
    momentid::DataBlock block;
    REQUIRE(reader->next(block, 1000));
    fs::resize_file(npy, fs::file_size(npy) / 2);
    const auto e = momentid::testing::error_from<momentid::DataError>([&] {
      while (reader->next(block, 1000)) {
      }
    });
    CHECK(std::string(e.what()) ==
          npy + ":1:1: the file ends inside the array: it was cut short while it was read");
  }
}
