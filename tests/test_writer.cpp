// DataWriter: files read back through DataReader hold exactly the values written; a file is
// written whole or not at all; a symbolic link keeps pointing at the file it names.

#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "momentid/reader.hpp"
#include "momentid/writer.hpp"

namespace {

using momentid::DataReader;
using momentid::DataWriter;

namespace fs = std::filesystem;

// An empty directory of its own in the temporary directory, removed with what it holds. The
// name is unique per process and per directory, as CTest runs test cases in parallel.
class TempDirectory {
 public:
  TempDirectory() {
    static int count = 0;
    path_ = fs::temp_directory_path() /
            ("momentid_test_writer_" + std::to_string(::getpid()) + "_" + std::to_string(count++));
    fs::remove_all(path_);
    fs::create_directory(path_);
  }
  TempDirectory(const TempDirectory&) = delete;
  TempDirectory& operator=(const TempDirectory&) = delete;
  ~TempDirectory() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  fs::path operator/(const std::string& name) const { return path_ / name; }
  std::vector<std::string> entries() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(path_)) out.push_back(e.path().filename());
    std::sort(out.begin(), out.end());
    return out;
  }

 private:
  fs::path path_;
};

// Values whose text or bits are easy to get wrong: shortest round trips, extremes, subnormals,
// a negative zero.
const std::vector<double> kValues = {0.1,
                                     1.0 / 3,
                                     -2.5e-7,
                                     1e300,
                                     -std::numeric_limits<double>::max(),
                                     std::numeric_limits<double>::denorm_min(),
                                     -0.0,
                                     123456789.125,
                                     std::numeric_limits<double>::min()};
const std::vector<std::string> kColumns = {"y", "v", "x"};

void write(const fs::path& path, DataWriter::Format format) {
  momentid::DataMetadata metadata;
  metadata.add_line({{"dt", "0.25"}, {"input-hold", "zoh"}});
  DataWriter out(path.string(), format, metadata, kColumns);
  for (std::size_t r = 0; r < kValues.size() / kColumns.size(); ++r) {
    out.row(kValues.data() + r * kColumns.size());
  }
  out.commit();
}

// The file's values, as DataReader delivers them, and its metadata.
std::vector<double> read_back(const fs::path& path, std::string* dt = nullptr) {
  momentid::ColumnRequest request;
  request.names = kColumns;
  const auto reader = DataReader::open(path.string(), request);
  if (dt) *dt = reader->metadata().get("dt").value_or("");
  std::vector<double> values;
  momentid::DataBlock block;
  while (reader->next(block, 2)) {
    values.insert(values.end(), block.values.begin(), block.values.end());
  }
  return values;
}

// Equal bit for bit (so that -0.0 differs from 0.0).
bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::bit_cast<std::uint64_t>(a[i]) != std::bit_cast<std::uint64_t>(b[i])) return false;
  }
  return true;
}

std::string contents(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST_SUITE("writer") {
  TEST_CASE("a CSV file reads back with every value exact and its metadata") {
    const TempDirectory dir;
    write(dir / "d.csv", DataWriter::Format::kCsv);
    std::string dt;
    CHECK(same_bits(read_back(dir / "d.csv", &dt), kValues));
    CHECK(dt == "0.25");
    CHECK(dir.entries() == std::vector<std::string>{"d.csv"});
  }

  TEST_CASE("a binary file reads back with every value exact and its metadata") {
    const TempDirectory dir;
    write(dir / "d.bin", DataWriter::Format::kBinary);
    std::string dt;
    CHECK(same_bits(read_back(dir / "d.bin", &dt), kValues));
    CHECK(dt == "0.25");
    CHECK(contents(dir / "d.bin").substr(0, 8) == "MOMNTID1");
  }

  TEST_CASE("a writer destroyed without commit leaves no file, and an old file untouched") {
    const TempDirectory dir;
    {
      DataWriter out((dir / "d.csv").string(), DataWriter::Format::kCsv, {}, kColumns);
      out.row(kValues.data());
    }
    CHECK(dir.entries().empty());
    std::ofstream(dir / "old.csv") << "old\n";
    {
      DataWriter out((dir / "old.csv").string(), DataWriter::Format::kBinary, {}, kColumns);
      out.row(kValues.data());
    }
    CHECK(dir.entries() == std::vector<std::string>{"old.csv"});
    CHECK(contents(dir / "old.csv") == "old\n");
  }

  TEST_CASE("writing through a symbolic link replaces the file it points to, not the link") {
    const TempDirectory dir;
    fs::create_directory(dir / "data");
    std::ofstream(dir / "data" / "target.csv") << "old\n";
    fs::create_symlink(fs::path("data") / "target.csv", dir / "link.csv");
    write(dir / "link.csv", DataWriter::Format::kCsv);
    CHECK(fs::is_symlink(fs::symlink_status(dir / "link.csv")));
    CHECK(fs::read_symlink(dir / "link.csv") == fs::path("data") / "target.csv");
    CHECK(same_bits(read_back(dir / "data" / "target.csv"), kValues));
    CHECK(dir.entries() == std::vector<std::string>{"data", "link.csv"});
    CHECK(std::distance(fs::directory_iterator(dir / "data"), fs::directory_iterator()) == 1);
    // A link to a file not there yet: the file is created where the link points.
    fs::create_symlink(fs::path("data") / "new.csv", dir / "dangling.csv");
    write(dir / "dangling.csv", DataWriter::Format::kBinary);
    CHECK(fs::is_symlink(fs::symlink_status(dir / "dangling.csv")));
    CHECK(same_bits(read_back(dir / "data" / "new.csv"), kValues));
    CHECK(std::distance(fs::directory_iterator(dir / "data"), fs::directory_iterator()) == 2);
  }

  TEST_CASE("a device is written to directly, not replaced") {
    DataWriter out("/dev/null", DataWriter::Format::kCsv, {}, kColumns);
    out.row(kValues.data());
    out.commit();
    CHECK(fs::is_character_file("/dev/null"));
  }
}
