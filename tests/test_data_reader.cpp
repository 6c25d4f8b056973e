#include <doctest/doctest.h>
#include <unistd.h>

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <typeinfo>
#include <utility>
#include <vector>

#include "common/decimal.hpp"
#include "momentid/reader.hpp"
#include "test_support.hpp"

namespace {

using momentid::testing::error_from;

using momentid::ColumnRequest;
using momentid::DataBlock;
using momentid::DataError;
using momentid::DataReader;

// A file in the temporary directory holding `contents`, removed when this goes out of scope.
// The name is unique per process and per file, as CTest runs test cases in parallel.
class TempFile {
 public:
  explicit TempFile(std::string_view contents) {
    static int count = 0;
    path_ = std::filesystem::temp_directory_path() /
            ("momentid_test_reader_" + std::to_string(::getpid()) + "_" + std::to_string(count++) +
             ".dat");
    std::ofstream out(path_, std::ios::binary);
    out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    REQUIRE(out.good());
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile() {
    std::error_code ignored;
    std::filesystem::remove(path_, ignored);
  }
  std::string path() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

// Everything a reader delivers for one file.
struct Contents {
  std::vector<DataBlock> blocks;
  std::vector<double> values;  // all rows, row-major, as requested
  std::size_t rows = 0;
  momentid::DataMetadata metadata;
  std::optional<double> time_step;
  momentid::MissingSummary missing;
};

Contents read_file(const std::string& path, const ColumnRequest& request,
                   std::size_t max_rows = 65536) {
  Contents contents;
  const auto reader = DataReader::open(path, request);
  DataBlock block;
  while (reader->next(block, max_rows)) {
    REQUIRE(block.rows <= max_rows);
    REQUIRE(block.values.size() == block.rows * request.names.size());
    contents.values.insert(contents.values.end(), block.values.begin(), block.values.end());
    contents.blocks.push_back(block);
  }
  CHECK(block.rows == 0);
  CHECK_FALSE(reader->next(block, max_rows));
  contents.rows = reader->rows_read();
  contents.metadata = reader->metadata();
  contents.time_step = reader->time_step();
  contents.missing = reader->missing();
  return contents;
}

Contents read_text(std::string_view text, const ColumnRequest& request,
                   std::size_t max_rows = 65536) {
  const TempFile file(text);
  return read_file(file.path(), request, max_rows);
}

// Reads a file holding `text` to its end and checks the DataError this throws: its message,
// where it points, the source line it carries, and that what() is "file:line:col: message".
void check_read_error(std::string_view text, const ColumnRequest& request,
                      const std::string& message, int line, int column,
                      const std::string& source_line) {
  const TempFile file(text);
  const DataError e = error_from<DataError>([&] { read_file(file.path(), request); });
  // The message as a library user reads it, an options field named by its name.
  CHECK(e.text([](const std::string& field) { return field; }) ==
        file.path() + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " + message);
  CHECK(e.location().file == file.path());
  CHECK(e.location().line == line);
  CHECK(e.location().column == column);
  CHECK(e.location().text == source_line);
  CHECK(std::string(e.what()) ==
        file.path() + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " + message);
}

// The binary layout: magic, header length, header text, rows of little-endian float64 values.
std::string binary_file(std::string_view header_text, const std::vector<double>& values) {
  std::string out = "MOMNTID1";
  const auto length = static_cast<std::uint32_t>(header_text.size());
  for (int i = 0; i < 4; ++i) out += static_cast<char>((length >> (8 * i)) & 0xFF);
  out += header_text;
  for (const double value : values) {
    const auto bits = std::bit_cast<std::uint64_t>(value);
    for (int i = 0; i < 8; ++i) out += static_cast<char>((bits >> (8 * i)) & 0xFF);
  }
  return out;
}

// The shortest decimal that reads back as `value`, so that a written file reads back exactly.
std::string decimal(double value) {
  char buffer[32];
  return std::string(buffer, std::to_chars(buffer, buffer + sizeof buffer, value).ptr);
}

// What to read: `names`, with `rename` and `min_rows`.
ColumnRequest columns(std::vector<std::string> names,
                      std::map<std::string, std::string> rename = {}, std::size_t min_rows = 2) {
  ColumnRequest request;
  request.names = std::move(names);
  request.rename = std::move(rename);
  request.min_rows = min_rows;
  return request;
}

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

}  // namespace

TEST_SUITE("data reader") {
  // --- Values and columns ---------------------------------------------------------------------

  TEST_CASE("delivers the requested columns in the requested order") {
    const Contents c = read_text("t,y,v,x\n0,1,2,3\n0.5,4,5,6\n1,7,8,9\n", columns({"x", "y"}));
    CHECK(c.values == std::vector<double>{3, 1, 6, 4, 9, 7});
    CHECK(c.rows == 3);
    REQUIRE(c.blocks.size() == 1);
    CHECK(c.blocks[0].rows == 3);
    CHECK(c.blocks[0].run == 0);
    CHECK(c.blocks[0].run_starts);
  }

  TEST_CASE("takes a semicolon separator from the header") {
    const Contents c = read_text("y;v\n1;2\n3;4\n", columns({"v", "y"}));
    CHECK(c.values == std::vector<double>{2, 1, 4, 3});
  }

  TEST_CASE("takes a comma separator when the header holds both comma and semicolon") {
    const Contents c = read_text("y,v;w\n1,2\n3,4\n", columns({"v;w"}));
    CHECK(c.values == std::vector<double>{2, 4});
  }

  TEST_CASE("separates columns by runs of blanks and tabs when the header has neither") {
    const Contents c =
        read_text("  t \t y   v\n0 1\t\t2\n  0.1   3 4  \n\t0.2\t5\t6\t\n", columns({"y", "v"}));
    CHECK(c.values == std::vector<double>{1, 2, 3, 4, 5, 6});
    CHECK(c.time_step == doctest::Approx(0.1).epsilon(1e-12));
  }

  TEST_CASE("reads a header with a single column and a file shorter than the binary magic") {
    const Contents c = read_text("y\n1\n2", columns({"y"}));
    CHECK(c.values == std::vector<double>{1, 2});
  }

  TEST_CASE("accepts blanks around fields, a leading plus sign and exponents") {
    const Contents c =
        read_text("y, v ,x\n +1.5 ,\t-2e-3, 3E2\n+.5,-0,1e+1 \n", columns({"y", "v", "x"}));
    CHECK(c.values == std::vector<double>{1.5, -2e-3, 300, 0.5, -0.0, 10});
  }

  TEST_CASE("strips a UTF-8 byte order mark and accepts CR LF line ends") {
    const Contents c = read_text("\xEF\xBB\xBFt,y\r\n0,1\r\n0.25,2\r\n", columns({"t", "y"}));
    CHECK(c.values == std::vector<double>{0, 1, 0.25, 2});
    CHECK(c.time_step == 0.25);
  }

  TEST_CASE("strips blanks and double quotes from column names") {
    const Contents c = read_text("\"t\", \"y\" , v\n0,1,2\n1,3,4\n", columns({"y", "v"}));
    CHECK(c.values == std::vector<double>{1, 2, 3, 4});
    CHECK(c.time_step == 1.0);
  }

  TEST_CASE("reads a model name from another column with rename") {
    const Contents c =
        read_text("y,velocity\n1,2\n3,4\n", columns({"y", "v"}, {{"v", "velocity"}}));
    CHECK(c.values == std::vector<double>{1, 2, 3, 4});
  }

  TEST_CASE("delivers one column for two requested names that read it") {
    const Contents c = read_text("y,x\n1,2\n3,4\n", columns({"y", "u", "x"}, {{"u", "y"}}));
    CHECK(c.values == std::vector<double>{1, 1, 2, 3, 3, 4});
  }

  TEST_CASE("ignores columns that are not requested, whatever they hold") {
    const Contents c = read_text(",label,y,note\n0,first,1,\n1,second,2,nan\n", columns({"y"}));
    CHECK(c.values == std::vector<double>{1, 2});
  }

  TEST_CASE("reads a line longer than a chunk") {
    const std::string long_field(3 << 20, 'a');
    const Contents c = read_text("y,note\n1," + long_field + "\n2,b\n", columns({"y"}));
    CHECK(c.values == std::vector<double>{1, 2});
  }

  TEST_CASE("ignores blank lines before the header, among the rows and at the end") {
    const Contents c =
        read_text("\n  \n# comment\n\nt,y\n0,1\n\n \t\n0.5,2\n1,3\n\n\n", columns({"y"}));
    CHECK(c.values == std::vector<double>{1, 2, 3});
    CHECK(c.time_step == 0.5);
  }

  TEST_CASE("reads a header without rows when min_rows is 0") {
    const Contents c = read_text("y,v\n", columns({"y"}, {}, 0));
    CHECK(c.rows == 0);
    CHECK(c.blocks.empty());
  }

  // --- Metadata and time step -----------------------------------------------------------------

  TEST_CASE("reads metadata pairs, later keys overwriting earlier ones, and skips other comments") {
    const Contents c = read_text(
        "# written by hand\n"
        "# momentid: dt=0.01 model=duffing seed=1\n"
        "  #momentid: seed=7 input.x=ma:K=10,w=0.1  empty=\n"
        "# not momentid: k=v\n"
        "y\n1\n2\n",
        columns({"y"}));
    CHECK(c.metadata.size() == 5);
    CHECK(c.metadata.get("dt") == "0.01");
    CHECK(c.metadata.get("model") == "duffing");
    CHECK(c.metadata.get("seed") == "7");
    CHECK(c.metadata.get("input.x") == "ma:K=10,w=0.1");
    CHECK(c.metadata.get("empty") == "");
    CHECK(c.metadata.get("k") == std::nullopt);
    CHECK(c.time_step == 0.01);
  }

  TEST_CASE("takes the time step from the t column, else from the metadata dt, else has none") {
    CHECK(read_text("t,y\n10,1\n10.02,2\n10.04,3\n", columns({"y"})).time_step ==
          doctest::Approx(0.02).epsilon(1e-12));
    CHECK(read_text("# momentid: dt=0.02\nt,y\n1,1\n1.02,2\n", columns({"y"})).time_step ==
          doctest::Approx(0.02).epsilon(1e-12));
    CHECK(read_text("# momentid: dt=0.5\ny\n1\n2\n", columns({"y"})).time_step == 0.5);
    CHECK(read_text("y\n1\n2\n", columns({"y"})).time_step == std::nullopt);
  }

  TEST_CASE("knows the time step once the first two rows of the first run are read") {
    const TempFile file("t,y\n0,1\n0.5,2\n1,3\n");
    const auto reader = DataReader::open(file.path(), columns({"y"}));
    CHECK(reader->time_step() == std::nullopt);
    DataBlock block;
    REQUIRE(reader->next(block, 1));
    CHECK(reader->time_step() == std::nullopt);
    REQUIRE(reader->next(block, 1));
    CHECK(reader->time_step() == 0.5);
    CHECK(reader->rows_read() == 2);
  }

  TEST_CASE("accepts times with rounding in their last digits") {
    // Near t = 1e6 a double's rounding changes a 0.1 step by about 1e-9 of it.
    std::string text = "t,y\n";
    for (int n = 0; n < 100; ++n) text += decimal(1e6 + n * 0.1) + ",1\n";
    CHECK(read_text(text, columns({"y"})).rows == 100);
  }

  TEST_CASE("accepts float32 time stamps and takes their mean step as the interval") {
    // t = 1000 + n * 0.01 stored as float32: each stamp off by up to 3e-5, a step by up to 0.6%.
    std::string text = "t,y\n";
    const int rows = 2000;
    for (int n = 0; n < rows; ++n) {
      text += decimal(static_cast<double>(static_cast<float>(1000.0 + n * 0.01))) + ",1\n";
    }
    const Contents contents = read_text(text, columns({"y"}));
    CHECK(contents.rows == rows);
    const double span = static_cast<double>(static_cast<float>(1000.0 + (rows - 1) * 0.01)) -
                        static_cast<double>(static_cast<float>(1000.0));
    CHECK(*contents.time_step == doctest::Approx(span / (rows - 1)).epsilon(1e-12));
    CHECK(std::abs(*contents.time_step / 0.01 - 1) < 1e-5);
    // A missing sample is still a gap.
    std::string gap = "t,y\n";
    for (int n = 0; n < 20; ++n) {
      if (n != 12)
        gap += decimal(static_cast<double>(static_cast<float>(1000.0 + n * 0.01))) + ",1\n";
    }
    const TempFile file(gap);
    const DataError e = error_from<DataError>([&] { read_file(file.path(), columns({"y"})); });
    CHECK(e.message().find("non-uniform time step") == 0);
    CHECK(e.location().line == 14);
  }

  // Time stamps printed to 6 decimals at 1024 Hz, as acquisition software writes them: steps of
  // 0.000976 and 0.000977.
  std::string printed_times(int rows, int decimals, double rate, int jitter_row = -1) {
    std::string text = "t,y\n";
    char field[64];
    for (int n = 0; n < rows; ++n) {
      const double jitter = n == jitter_row ? 3 * std::pow(10.0, -decimals) : 0;
      std::snprintf(field, sizeof field, "%.*f,1\n", decimals, n / rate + jitter);
      text += field;
    }
    return text;
  }

  TEST_CASE("accepts times printed to a few decimals and takes their mean step as the interval") {
    const Contents six = read_text(printed_times(5000, 6, 1024), columns({"y"}));
    CHECK(six.rows == 5000);
    // The mean of rounded steps: off by at most one unit of the last decimal over the span.
    CHECK(std::abs(*six.time_step - 1.0 / 1024) < 1e-6 / 4999);
    // Four decimals at 2048 Hz: steps of 0.0005 and 0.0004, a fifth apart.
    const Contents four = read_text(printed_times(3000, 4, 2048), columns({"y"}));
    CHECK(std::abs(*four.time_step - 1.0 / 2048) < 1e-4 / 2999);
  }

  TEST_CASE("refuses printed times whose steps differ by more than their last decimal") {
    const std::string text = printed_times(40, 6, 1024, 20);
    const TempFile file(text);
    const DataError e = error_from<DataError>([&] { read_file(file.path(), columns({"y"})); });
    CHECK(e.location().line == 22);
    CHECK(e.message().find(
              "non-uniform time step: 0.000979 after 0.000977 at t = 0.019534 (the "
              "steps before it average 0.000976579): give the sample interval with ") == 0);
    // The command line names the option, Python the keyword.
    const auto flag = [](const std::string& field) { return "--" + field; };
    CHECK(e.text(flag).find("give the sample interval with --dt 0.000976579 if the samples are "
                            "equally spaced") != std::string::npos);
    CHECK(std::string(e.what()).find("with dt 0.000976579 if") != std::string::npos);
  }

  TEST_CASE("a missing sample is refused however coarsely the times are printed") {
    // Whole seconds: a unit of 1, but never more than half a step is allowed.
    check_read_error("t,y\n0,1\n1,2\n3,3\n", columns({"y"}),
                     "non-uniform time step: 2 after 1 at t = 3 (the steps before it average 1): "
                     "give the sample interval with dt 1 if the samples are equally spaced",
                     4, 1, "3,3");
  }

  TEST_CASE("reads printed times from columns in memory as from a file") {
    std::vector<double> t, y;
    for (int n = 0; n < 3000; ++n) {
      t.push_back(std::round(n / 1024.0 * 1e6) / 1e6);
      y.push_back(1);
    }
    momentid::MemoryData data;
    data.columns = {{"t", t.data()}, {"y", y.data()}};
    data.rows = t.size();
    const momentid::DataSource source = momentid::DataSource::memory(data);
    const auto reader = source.open(columns({"y"}));
    DataBlock block;
    while (reader->next(block, 1000)) {
    }
    CHECK(reader->rows_read() == 3000);
    CHECK(std::abs(*reader->time_step() - 1.0 / 1024) < 1e-6 / 2999);
  }

  TEST_CASE("recognises a time column named time or t with a unit, or mapped to t") {
    for (const char* header : {"time", "Time", "TIME", "t [s]", "Time (s)", "time[ms]"}) {
      const Contents contents =
          read_text(std::string(header) + ",y\n0,1\n0.5,2\n1,3\n", columns({"y"}));
      CHECK(contents.time_step == 0.5);
    }
    // Not times: the column is not read, and its steps are not checked.
    for (const char* header : {"timestamp", "temperature", "t_end"}) {
      CHECK(read_text(std::string(header) + ",y\n0,1\n7,2\n8,3\n", columns({"y"})).time_step ==
            std::nullopt);
    }
    CHECK(read_text("clock,y\n0,1\n0.25,2\n0.5,3\n", columns({"y"}, {{"t", "clock"}})).time_step ==
          0.25);
    check_read_error("clock,y\n0,1\n0.25,2\n", columns({"y"}, {{"t", "tick"}}),
                     "missing column 'tick' for 't' (the header has: clock, y)", 1, 1, "clock,y");
  }

  TEST_CASE("the hints of a bad field name the options fields, which a front end spells") {
    const auto flag = [](const std::string& field) {
      std::string out = "--" + field;
      std::replace(out.begin(), out.end(), '_', '-');
      return out;
    };
    const auto text_of = [&](std::string_view text, const ColumnRequest& request) {
      const TempFile file(text);
      const DataError e = error_from<DataError>([&] { read_file(file.path(), request); });
      const std::string place = file.path() + ":";
      std::string out = e.text(flag);
      return out.starts_with(place) ? out.substr(place.size()) : out;
    };
    // A units row is skipped (below): a second row without a number draws the hint.
    CHECK(text_of("t;y\ns;m\nclock;laser\n0;1\n", columns({"y"})) ==
          "3:1: column 't': expected a number (a units row? give --skip-rows 1), found 'clock'");
    // A first row with a number in it is data with a bad field.
    CHECK(text_of("t,a\n0,m/s^2\n", columns({"a"})) ==
          "2:3: column 'a': expected a number, found 'm/s^2'");
    CHECK(text_of("t;y\n0;1,5\n", columns({"y"})) ==
          "2:3: column 'y': expected a number (with a decimal comma? give --decimal ,), found "
          "'1,5'");
    CHECK(text_of("t,y\n0,nan\n", columns({"y"})) ==
          "2:3: column 'y': expected a number (a missing value? --missing drop-row or split-run "
          "passes over it), found 'nan'");
  }

  TEST_CASE("skips a units row, reads decimal commas when told to, and suggests them") {
    ColumnRequest request = columns({"y", "x"});
    check_read_error("t;y;x\ns;m;N\n0;1,5;2\n0,5;1,25;1\n", request,
                     "column 'y': expected a number (with a decimal comma? give decimal ,), "
                     "found '1,5'",
                     3, 3, "0;1,5;2");
    request.layout.decimal = ',';
    const Contents contents = read_text("t;y;x\ns;m;N\n0;1,5;2\n0,5;1,25;-1e-1\n", request);
    CHECK(contents.values == std::vector<double>{1.5, 2, 1.25, -0.1});
    CHECK(contents.time_step == 0.5);
    // skip_rows 1 says the same; a units row and a row of descriptions need it.
    request.layout.skip_rows = 1;
    CHECK(read_text("t;y;x\ns;m;N\n0;1,5;2\n0,5;1,25;-1e-1\n", request).values == contents.values);
    CHECK(read_text("t;y;x\ns;m;N\ntime;laser;load cell\n\n0;1,5;2\n0,5;1,25;-1e-1\n", request)
              .values == contents.values);
    check_read_error("t,y,x\n0,1,2\n", request,
                     "a decimal comma needs fields separated by ';' or blanks, but the header "
                     "separates them by ','",
                     1, 1, "t,y,x");
  }

  TEST_CASE("a units row is told from a first row of data by its fields, not its digits") {
    // Units with digits: skipped, as in every part of a file read in shards.
    const TempFile file("t,a,b\ns,m/s^2,m s-2\n\n0,1,2\n1,3,4\n2,5,6\n3,7,8\n");
    CHECK(read_file(file.path(), columns({"a"})).values == std::vector<double>{1, 3, 5, 7});
    const auto source = momentid::DataSource::file(file.path());
    std::vector<double> values;
    for (const auto& shard : source.shards(10)) {
      const auto reader = source.open(shard, columns({"a"}, {}, 0));
      DataBlock block;
      while (reader->next(block, 10)) {
        if (block.zone == momentid::RowZone::kOwned) {
          values.insert(values.end(), block.values.begin(), block.values.end());
        }
      }
    }
    CHECK(values == std::vector<double>{1, 3, 5, 7});
    // Missing values alone are a row of data (an error by default), not units.
    check_read_error("t,a\nnan,NA\n0,1\n", columns({"a"}),
                     "column 't': expected a number (a missing value? missing drop-row or "
                     "split-run passes over it), found 'nan'",
                     2, 1, "nan,NA");
    // A first row that is data is read as such, after blank lines.
    CHECK(read_text("t,a\n\n0,1\n1,2\n", columns({"a"})).values == std::vector<double>{1, 2});
  }

  TEST_CASE("a given sample interval overrides the time column, which is then not checked") {
    ColumnRequest request = columns({"y"});
    request.dt = 0.125;
    const Contents contents = read_text("t,y\n0,1\n0.1,2\n0.7,3\n", request);
    CHECK(contents.rows == 3);
    CHECK(contents.time_step == 0.125);
  }

  // --- Several files -------------------------------------------------------------------------

  TEST_CASE("several files are one record whose files are never joined") {
    const TempFile a("t,y,run\n0,1,1\n1,2,1\n0,3,2\n1,4,2\n");
    const TempFile b("# momentid: dt=1\ny\n5\n6\n7\n");
    const auto reader = momentid::DataSource::files({a.path(), b.path()}).open(columns({"y"}));
    std::vector<double> values;
    std::vector<bool> starts;
    DataBlock block;
    while (reader->next(block, 100)) {
      starts.push_back(block.run_starts);
      values.insert(values.end(), block.values.begin(), block.values.end());
    }
    CHECK(values == std::vector<double>{1, 2, 3, 4, 5, 6, 7});
    CHECK(starts == std::vector<bool>{true, true, true});  // two runs in a, one in b
    CHECK(reader->rows_read() == 7);
    CHECK(reader->time_step() == 1);
    CHECK(momentid::DataSource::files({a.path(), b.path()}).name() ==
          a.path() + " and 1 more file");
  }

  TEST_CASE("files of several sample intervals, or too few rows in all, are refused") {
    const TempFile a("t,y\n0,1\n1,2\n");
    const TempFile b("t,y\n0,1\n0.5,2\n");
    const auto read = [](const momentid::DataSource& source, const ColumnRequest& request) {
      const auto reader = source.open(request);
      DataBlock block;
      while (reader->next(block, 100)) {
      }
    };
    const DataError e = error_from<DataError>([&] {
      read(momentid::DataSource::files({a.path(), b.path()}), columns({"y"}));
    });
    CHECK(std::string(e.what()) == b.path() + ":1:1: this file has dt = 0.5, but " + a.path() +
                                       " has dt = 1: the files of one identification need one "
                                       "interval");
    ColumnRequest request = columns({"y"});
    request.min_rows = 5;
    const DataError few = error_from<DataError>([&] {
      read(momentid::DataSource::files({a.path(), a.path()}), request);
    });
    CHECK(few.message() == "the data have 4 rows in 2 files; at least 5 are needed");
  }

  // --- Sums of columns -------------------------------------------------------------------------

  // Every value `source` delivers for `request`.
  std::vector<double> read_all(const momentid::DataSource& source, const ColumnRequest& request) {
    const auto reader = source.open(request);
    std::vector<double> values;
    DataBlock block;
    while (reader->next(block, 2)) {
      REQUIRE(block.values.size() == block.rows * request.names.size());
      values.insert(values.end(), block.values.begin(), block.values.end());
    }
    return values;
  }

  TEST_CASE("a name mapped to a sum of columns is delivered as the sum, with its factors") {
    const TempFile f("t,acc_mass,acc_table,Acc 3\n0,5,1,10\n1,7,2,20\n2,4,8,30\n");
    const auto source = momentid::DataSource::file(f.path());
    CHECK(
        read_all(source, columns({"z", "a"}, {{"z", "acc_mass-acc_table"}, {"a", "acc_table"}})) ==
        std::vector<double>{4, 1, 5, 2, -4, 8});
    // Factors before or after the column, blanks, a leading sign, a quoted name.
    CHECK(read_all(source, columns({"z"}, {{"z", " -0.5 * acc_mass + acc_table*2 - 'Acc 3'"}})) ==
          std::vector<double>{-0.5 - 10, 0.5 - 20, 14 - 30});
    // One column in two terms, and requested alone too: read once.
    CHECK(read_all(source, columns({"acc_table", "z"}, {{"z", "acc_table + acc_table"}})) ==
          std::vector<double>{1, 2, 2, 4, 8, 16});
  }

  TEST_CASE("a column whose name reads as a sum is that column") {
    const TempFile f("t,a-b,a,b\n0,100,5,1\n1,200,7,2\n");
    CHECK(read_all(momentid::DataSource::file(f.path()), columns({"y"}, {{"y", "a-b"}})) ==
          std::vector<double>{100, 200});
  }

  TEST_CASE("sums of columns in memory, and in shards of a file") {
    const std::vector<double> mass{3, 4, 5, 6}, table{1, 1, 2, 2};
    momentid::MemoryData data;
    data.columns = {{"m", mass.data(), 1}, {"b", table.data(), 1}};
    data.rows = 4;
    data.metadata.add_line({{"dt", "0.5"}});
    CHECK(read_all(momentid::DataSource::memory(data), columns({"y"}, {{"y", "m - b"}})) ==
          std::vector<double>{2, 3, 3, 4});
    const TempFile f("t,m,b\n0,3,1\n1,4,1\n2,5,2\n3,6,2\n");
    const auto source = momentid::DataSource::file(f.path());
    const auto shards = source.shards(12);
    CHECK(shards.size() > 1);
    std::vector<double> values;
    for (const auto& shard : shards) {
      const auto reader = source.open(shard, columns({"y"}, {{"y", "m-b"}}, 0));
      DataBlock block;
      while (reader->next(block, 10)) {
        if (block.zone != momentid::RowZone::kOwned) continue;
        values.insert(values.end(), block.values.begin(), block.values.end());
      }
    }
    CHECK(values == std::vector<double>{2, 3, 3, 4});
  }

  TEST_CASE("a sum that does not parse, or names a column the record lacks, is refused") {
    const TempFile f("t,m,b\n0,3,1\n1,4,1\n");
    const auto source = momentid::DataSource::file(f.path());
    const auto message = [&](const std::string& sum) {
      const auto e = error_from<momentid::UsageError>([&] {
        read_all(source, columns({"y"}, {{"y", sum}}));
      });
      return e.text([](const std::string& field) { return "--" + field; });
    };
    const std::string as_sum = "', and as a sum of columns, expected ";
    CHECK(message("m - c") == "--columns: y=m - c: " + f.path() + " has no column 'c'");
    CHECK(message("m - - b") == "--columns: y=m - - b: " + f.path() + " has no column 'm - - b" +
                                    as_sum +
                                    "a column name (in quotes when it holds blanks or operators) "
                                    "at character 5, found '-'");
    CHECK(message("2 m") == "--columns: y=2 m: " + f.path() + " has no column '2 m" + as_sum +
                                "'*' after the factor 2 at character 3, found 'm'");
    CHECK(message("m*") == "--columns: y=m*: " + f.path() + " has no column 'm*" + as_sum +
                               "a number after '*' at character 3, found the end");
    CHECK(message("m + 'b") == "--columns: y=m + 'b: " + f.path() + " has no column 'm + 'b" +
                                   as_sum +
                                   "a column name and a closing ' at character 5, found '''");
    // The time is always a column.
    const DataError time = error_from<DataError>([&] {
      read_all(source, columns({"m"}, {{"t", "m-b"}}));
    });
    CHECK(time.message().starts_with("missing column 'm-b' for 't'"));
  }

  TEST_CASE("a sum beyond the range of doubles is refused, not delivered as inf") {
    const TempFile f("t,m,b\n0,1e308,-1e308\n");
    const auto e = error_from<momentid::Error>([&] {
      read_all(momentid::DataSource::file(f.path()), columns({"y"}, {{"y", "m - b"}}, 1));
    });
    CHECK(std::string(e.what()) == f.path() +
                                       ": the sum m - b reaches inf, beyond the range of doubles, "
                                       "in a row whose columns are finite");
  }

  // --- Blocks and runs ------------------------------------------------------------------------

  TEST_CASE("splits blocks at max_rows and where the run changes") {
    const Contents c =
        read_text("t,y,run\n0,1,1\n1,2,1\n2,3,1\n0,4,2\n1,5,2\n5,6,3\n", columns({"y"}), 2);
    REQUIRE(c.blocks.size() == 4);
    CHECK(c.blocks[0].values == std::vector<double>{1, 2});
    CHECK(c.blocks[0].run == 1);
    CHECK(c.blocks[0].run_starts);
    CHECK(c.blocks[1].values == std::vector<double>{3});
    CHECK(c.blocks[1].run == 1);
    CHECK_FALSE(c.blocks[1].run_starts);
    CHECK(c.blocks[2].values == std::vector<double>{4, 5});
    CHECK(c.blocks[2].run == 2);
    CHECK(c.blocks[2].run_starts);
    CHECK(c.blocks[3].values == std::vector<double>{6});
    CHECK(c.blocks[3].run == 3);
    CHECK(c.blocks[3].run_starts);
    CHECK(c.rows == 6);
    CHECK(c.time_step == 1.0);
  }

  TEST_CASE("treats a file without a run column as one run numbered 0") {
    const Contents c = read_text("y\n1\n2\n3\n4\n5\n", columns({"y"}), 2);
    REQUIRE(c.blocks.size() == 3);
    CHECK(c.blocks[0].run_starts);
    CHECK_FALSE(c.blocks[1].run_starts);
    CHECK_FALSE(c.blocks[2].run_starts);
    for (const DataBlock& block : c.blocks) CHECK(block.run == 0);
  }

  TEST_CASE("accepts run numbers written with a zero fraction") {
    const Contents c = read_text("run,y\n3.0,1\n3,2\n-1.0,3\n", columns({"y"}));
    REQUIRE(c.blocks.size() == 2);
    CHECK(c.blocks[0].run == 3);
    CHECK(c.blocks[0].rows == 2);
    CHECK(c.blocks[1].run == -1);
  }

  TEST_CASE("lets the time restart in a new run") {
    const Contents c =
        read_text("t,y,run\n0,1,1\n0.1,2,1\n5,3,2\n5.1,4,2\n", columns({"y", "t", "run"}));
    CHECK(c.values == std::vector<double>{1, 0, 1, 2, 0.1, 1, 3, 5, 2, 4, 5.1, 2});
    CHECK(c.blocks.size() == 2);
  }

  // --- Large files ----------------------------------------------------------------------------

  TEST_CASE("streams a large file across chunk boundaries") {
    // About 15 MB: many 1 MiB chunks, so many rows span two of them.
    constexpr int kRows = 300000;
    std::mt19937_64 random(12345);
    std::normal_distribution<double> normal;
    std::string text = "# momentid: dt=0.001\nt,y,v,run\n";
    double y_sum = 0, v_sum = 0;
    for (int n = 0; n < kRows; ++n) {
      const double y = normal(random), v = normal(random) * 1e-3;
      y_sum += y;
      v_sum += v;
      text += decimal(n * 0.001) + "," + decimal(y) + "," + decimal(v) + "," +
              (n < kRows / 2 ? "1" : "2") + "\n";
    }
    const TempFile file(text);
    const auto reader = DataReader::open(file.path(), columns({"v", "y"}));
    DataBlock block;
    double y_read = 0, v_read = 0;
    std::vector<std::size_t> block_rows;
    std::vector<long> runs;
    while (reader->next(block, 65536)) {
      for (std::size_t r = 0; r < block.rows; ++r) {
        v_read += block.values[2 * r];
        y_read += block.values[2 * r + 1];
      }
      block_rows.push_back(block.rows);
      if (block.run_starts) runs.push_back(block.run);
    }
    // Same values added in the same order: the sums agree exactly.
    CHECK(y_read == y_sum);
    CHECK(v_read == v_sum);
    CHECK(reader->rows_read() == kRows);
    CHECK(block_rows == std::vector<std::size_t>{65536, 65536, 18928, 65536, 65536, 18928});
    CHECK(runs == std::vector<long>{1, 2});
    CHECK(reader->time_step() == doctest::Approx(0.001).epsilon(1e-9));
  }

  // --- Binary files ---------------------------------------------------------------------------

  TEST_CASE("reads a binary file: metadata, values, runs and time step") {
    const std::string bytes = binary_file("# momentid: dt=0.1 model=m\r\nt,y,v,run\n",
                                          {0, 1, -1, 1,  //
                                           0.1, 2, -2, 1, 0, 3, -3, 2, 0.1, 4, -4, 2});
    const Contents c = read_text(bytes, columns({"v", "y"}));
    CHECK(c.values == std::vector<double>{-1, 1, -2, 2, -3, 3, -4, 4});
    REQUIRE(c.blocks.size() == 2);
    CHECK(c.blocks[0].run == 1);
    CHECK(c.blocks[0].run_starts);
    CHECK(c.blocks[1].run == 2);
    CHECK(c.blocks[1].run_starts);
    CHECK(c.metadata.get("model") == "m");
    CHECK(c.time_step == 0.1);
    CHECK(c.rows == 4);
  }

  TEST_CASE("streams a large binary file across chunk boundaries") {
    // 3-value rows (24 bytes) do not divide a 1 MiB chunk.
    constexpr int kRows = 300000;
    std::vector<double> values;
    double sum = 0;
    for (int n = 0; n < kRows; ++n) {
      const double y = std::sin(n * 0.37) * 1e3;
      sum += y;
      values.insert(values.end(), {n * 0.01, y, static_cast<double>(n % 7)});
    }
    const Contents c = read_text(binary_file("t,y,x\n", values), columns({"y"}));
    double read_sum = 0;
    for (const double y : c.values) read_sum += y;
    CHECK(read_sum == sum);
    CHECK(c.rows == kRows);
    CHECK(c.blocks.size() == 5);
  }

  // --- Errors: the file and its header --------------------------------------------------------

  TEST_CASE("a file that cannot be opened is an Error naming the path and the reason") {
    const std::string path = "/nonexistent-momentid-dir/data.csv";
    const momentid::Error e =
        error_from<momentid::Error>([&] { DataReader::open(path, columns({"y"})); });
    CHECK(std::string(e.what()) == path + ": cannot open the data file: No such file or directory");
  }

  TEST_CASE("an empty file asks for a header row") {
    check_read_error("", columns({"y"}),
                     "the file is empty: expected a header row naming the columns", 1, 1, "");
  }

  TEST_CASE("a file of comments and blank lines asks for a header row") {
    check_read_error("# momentid: dt=0.1\n\n# more\n", columns({"y"}),
                     "expected a header row naming the columns", 1, 1, "# momentid: dt=0.1");
  }

  TEST_CASE("a header row of numbers is reported as a missing header") {
    check_read_error("\n1,2.5,3\n4,5,6\n", columns({"y"}),
                     "expected a header row naming the columns, found a row of numbers", 2, 1,
                     "1,2.5,3");
  }

  TEST_CASE("a missing column is reported with the names the header has") {
    check_read_error("# c\nt,y,x\n0,1,2\n0.1,1,2\n", columns({"y", "v", "x"}),
                     "missing column 'v' (the header has: t, y, x)", 2, 1, "t,y,x");
  }

  TEST_CASE("a missing renamed column is named with the name it stands for") {
    check_read_error("t,y,x\n0,1,2\n", columns({"y", "v"}, {{"v", "velocity"}}),
                     "missing column 'velocity' for 'v' (the header has: t, y, x)", 1, 1, "t,y,x");
  }

  TEST_CASE("a duplicate requested, t or run column is reported with where the first one is") {
    check_read_error("t,y,v,y\n0,1,2,3\n", columns({"y", "v"}),
                     "column 'y' appears twice in the header (first at column 3)", 1, 7, "t,y,v,y");
    check_read_error("t, y, t\n0,1,2\n", columns({"y"}),
                     "column 't' appears twice in the header (first at column 1)", 1, 7, "t, y, t");
    check_read_error("run y run\n1 2 3\n", columns({"y"}),
                     "column 'run' appears twice in the header (first at column 1)", 1, 7,
                     "run y run");
  }

  TEST_CASE("a duplicate column that is not used is accepted") {
    CHECK(read_text("y,x,x\n1,2,3\n4,5,6\n", columns({"y"})).values == std::vector<double>{1, 4});
  }

  TEST_CASE("a metadata dt that is not a positive number is reported at its value") {
    check_read_error("# momentid: model=m dt=abc\ny\n1\n2\n", columns({"y"}),
                     "metadata dt: expected a positive number, found 'abc'", 1, 24,
                     "# momentid: model=m dt=abc");
    check_read_error("# momentid: dt=-0.1\ny\n1\n2\n", columns({"y"}),
                     "metadata dt: expected a positive number, found '-0.1'", 1, 16,
                     "# momentid: dt=-0.1");
    check_read_error("# momentid: dt=0\ny\n1\n2\n", columns({"y"}),
                     "metadata dt: expected a positive number, found '0'", 1, 16,
                     "# momentid: dt=0");
    check_read_error("#momentid: dt=\ny\n1\n2\n", columns({"y"}),
                     "metadata dt: expected a positive number, found nothing", 1, 15,
                     "#momentid: dt=");
  }

  TEST_CASE("a metadata entry without '=' is reported") {
    check_read_error("# momentid: dt=0.1 oops\ny\n1\n2\n", columns({"y"}),
                     "metadata: expected key=value, found 'oops'", 1, 20,
                     "# momentid: dt=0.1 oops");
    check_read_error("# momentid: =1\ny\n1\n2\n", columns({"y"}),
                     "metadata: expected key=value, found '=1'", 1, 13, "# momentid: =1");
  }

  // --- Errors: fields and rows ----------------------------------------------------------------

  TEST_CASE("a field that is not a number is reported at its column") {
    check_read_error("t,y,v\n0,1,2\n0.1,abc,3\n", columns({"y", "v"}),
                     "column 'y': expected a number, found 'abc'", 3, 5, "0.1,abc,3");
    check_read_error("t,y,v\n0,1,2\n0.1, 1.5x ,3\n", columns({"y", "v"}),
                     "column 'y': expected a number, found '1.5x'", 3, 6, "0.1, 1.5x ,3");
    check_read_error("y v\n+-1 2\n", columns({"y", "v"}),
                     "column 'y': expected a number, found '+-1'", 2, 1, "+-1 2");
  }

  TEST_CASE("a field of a renamed column is reported with the column's name in the file") {
    check_read_error("y;velocity\n1;fast\n", columns({"v"}, {{"v", "velocity"}}),
                     "column 'velocity': expected a number, found 'fast'", 2, 3, "1;fast");
  }

  TEST_CASE("a long bad field is shown cut after 40 bytes") {
    const std::string field =
        "x123456789"
        "0123456789"
        "0123456789"
        "0123456789"
        "tail";
    check_read_error("y\n1\n" + field + "\n", columns({"y"}),
                     "column 'y': expected a number, found "
                     "'x123456789012345678901234567890123456789...'",
                     3, 1, field);
  }

  TEST_CASE("inf and numbers too large for a double are reported as not finite") {
    check_read_error("t,y,v\n0,1,-inf\n", columns({"y", "v"}),
                     "column 'v': expected a finite number, found '-inf'", 2, 5, "0,1,-inf");
    check_read_error("y\n1e999\n", columns({"y"}),
                     "column 'y': expected a finite number, found '1e999'", 2, 1, "1e999");
    check_read_error("t,y\nInfinity,1\n", columns({"y"}),
                     "column 't': expected a finite number, found 'Infinity'", 2, 1, "Infinity,1");
  }

  TEST_CASE("a missing value (empty, nan, NA, N/A) is an error that names the --missing rules") {
    const std::string hint =
        "expected a number (a missing value? missing drop-row or split-run passes over it)";
    check_read_error("t,y,v\n0.1,,3\n", columns({"y", "v"}),
                     "column 'y': " + hint + ", found an empty field", 2, 5, "0.1,,3");
    check_read_error("t,y,v\n0.1,2, \t\n", columns({"y", "v"}),
                     "column 'v': " + hint + ", found an empty field", 2, 7, "0.1,2, \t");
    check_read_error("t,y,v\n0,1,2\n0.1,nan,3\n", columns({"y", "v"}),
                     "column 'y': " + hint + ", found 'nan'", 3, 5, "0.1,nan,3");
    check_read_error("t y v\n0 1 2\n0.1 3 N/A\n", columns({"y", "v"}),
                     "column 'v': " + hint + ", found 'N/A'", 3, 7, "0.1 3 N/A");
    check_read_error("t;y\n0;1\nNA;3\n", columns({"y"}), "column 't': " + hint + ", found 'NA'", 3,
                     1, "NA;3");
  }

  TEST_CASE("drop-row drops rows with a missing value and joins their neighbours") {
    ColumnRequest request = columns({"y", "v"});
    request.layout.missing = momentid::MissingValues::kDropRow;
    // The time column's step across a dropped row is not checked and not in the mean step.
    const std::string text = "t,y,v\n0,1,2\n0.5,,3\n1,4,nan\n1.5,5,6\n2,7,8\n2.5,NA,1\n";
    const Contents c = read_text(text, request);
    REQUIRE(c.blocks.size() == 1);
    CHECK(c.values == std::vector<double>{1, 2, 5, 6, 7, 8});
    CHECK(c.time_step == 0.5);
    const momentid::MissingSummary& missing = c.missing;
    CHECK(missing.rows == 3);
    CHECK(missing.joins == 1);
    CHECK(missing.splits == 0);
    REQUIRE(missing.first);
    CHECK(missing.first->line == 3);
    CHECK(missing.first->column == 5);
    // Times must still increase across a dropped row.
    check_read_error(
        "t,y\n1,1\n1.5,\n0.25,2\n",
        [] {
          ColumnRequest r = columns({"y"});
          r.layout.missing = momentid::MissingValues::kDropRow;
          return r;
        }(),
        "non-increasing time: t = 0.25 after t = 1 (samples must be in increasing time order)", 4,
        1, "0.25,2");
  }

  TEST_CASE("split-run drops rows with a missing value and starts a new run after them") {
    ColumnRequest request = columns({"y"});
    request.layout.missing = momentid::MissingValues::kSplitRun;
    // A gap in time after the dropped rows is then no error.
    const std::string text =
        "y,t,run\n,0,1\n1,1,1\n2,2,1\n,3,1\nnan,4,1\n5,5,1\n6,6,1\n,7,1\n7,0,2\n";
    const Contents c = read_text(text, request);
    REQUIRE(c.blocks.size() == 3);
    CHECK(c.blocks[0].values == std::vector<double>{1, 2});
    CHECK(c.blocks[1].values == std::vector<double>{5, 6});
    CHECK(c.blocks[1].run == 1);
    CHECK(c.blocks[1].run_starts);
    CHECK(c.blocks[2].values == std::vector<double>{7});
    CHECK(c.blocks[2].run == 2);
    CHECK(c.time_step == 1);
    CHECK(c.missing.rows == 4);
    CHECK(c.missing.splits == 1);  // the first row and the last of run 1 split nothing
  }

  TEST_CASE("a row with too few fields is reported at column 1") {
    check_read_error("t,y,v,x\n0,1,2,3\n0.1,1,2\n", columns({"x"}),
                     "expected 4 fields as in the header, found 3", 3, 1, "0.1,1,2");
    check_read_error("t y v\n0 1\n", columns({"y"}), "expected 3 fields as in the header, found 2",
                     2, 1, "0 1");
  }

  TEST_CASE("a row with too many fields is reported at the first extra field") {
    check_read_error("t,y,v,x\n0.1,1,2,3,4,5\n", columns({"y"}),
                     "expected 4 fields as in the header, found 6", 2, 11, "0.1,1,2,3,4,5");
    check_read_error("y,x\n1,2,\n", columns({"y"}), "expected 2 fields as in the header, found 3",
                     2, 5, "1,2,");
    check_read_error("t y v\n0 1 2  3 4\n", columns({"y"}),
                     "expected 3 fields as in the header, found 5", 2, 8, "0 1 2  3 4");
  }

  TEST_CASE("a run number that is not an integer is reported") {
    check_read_error("t,y,run\n0,1,1\n0.1,2,1.5\n", columns({"y"}),
                     "column 'run': expected an integer, found '1.5'", 3, 7, "0.1,2,1.5");
  }

  TEST_CASE("a non-uniform time step is reported at the t field") {
    check_read_error("y,t\n1,5.00\n2,5.01\n3,5.03\n", columns({"y"}),
                     "non-uniform time step: 0.02 after 0.01 at t = 5.03 (the steps before it "
                     "average 0.01): give the sample interval with dt 0.01 if the samples are "
                     "equally spaced",
                     4, 3, "3,5.03");
    // Shown with the digits that tell the two steps apart: three units of the fifth decimal,
    // more than the one that rounding to five decimals explains.
    check_read_error("t,y\n0,1\n1,2\n2.00003,3\n", columns({"y"}),
                     "non-uniform time step: 1.00003 after 1 at t = 2.00003 (the steps before it "
                     "average 1): give the sample interval with dt 1 if the samples are equally "
                     "spaced",
                     4, 1, "2.00003,3");
  }

  TEST_CASE("a step in a later run must agree with the file's time step") {
    check_read_error("t,y,run\n0,1,1\n0.1,2,1\n0,3,2\n0.2,4,2\n", columns({"y"}),
                     "non-uniform time step: 0.2 after 0.1 at t = 0.2 (the steps before it "
                     "average 0.1): give the sample interval with dt 0.1 if the samples are "
                     "equally spaced",
                     5, 1, "0.2,4,2");
  }

  TEST_CASE("a time that does not increase is reported") {
    check_read_error("t,y\n0,1\n0.1,2\n0.05,3\n", columns({"y"}),
                     "non-increasing time: t = 0.05 after t = 0.1 (samples must be in increasing "
                     "time order)",
                     4, 1, "0.05,3");
    check_read_error("t,y\n0,1\n0,2\n", columns({"y"}),
                     "non-increasing time: t = 0 after t = 0 (samples must be in increasing time "
                     "order)",
                     3, 1, "0,2");
  }

  TEST_CASE("a t column that disagrees with the metadata dt is reported at the second row") {
    check_read_error("# momentid: dt=0.01\nt,y\n0,1\n0.02,2\n0.04,3\n", columns({"y"}),
                     "time step 0.02 of column 't' disagrees with dt=0.01 in the metadata", 4, 1,
                     "0.02,2");
  }

  TEST_CASE("too few rows are reported at the last row, or at the header when there are none") {
    check_read_error("t,y\n0,1\n\n\n", columns({"y"}), "the data have 1 row; at least 2 are needed",
                     2, 1, "0,1");
    check_read_error("# c\nt,y\n", columns({"y"}), "the data have 0 rows; at least 2 are needed", 2,
                     1, "t,y");
    check_read_error("y\n1\n2\n", columns({"y"}, {}, 3),
                     "the data have 2 rows; at least 3 are needed", 3, 1, "2");
    check_read_error("y\n", columns({"y"}, {}, 1), "the data have 0 rows; at least 1 is needed", 1,
                     1, "y");
  }

  TEST_CASE("a very long line is cut in the error's text, with the caret still under the field") {
    std::string header = "y", row = "1";
    for (int i = 0; i < 100; ++i) {
      header += ",c" + std::to_string(i);
      row += ",1.2345";
    }
    // Early in the line: the first 200 bytes.
    const std::string early = "nan" + row.substr(1);
    check_read_error(header + "\n" + early + "\n", columns({"y"}),
                     "column 'y': expected a number (a missing value? missing drop-row or "
                     "split-run passes over it), found 'nan'",
                     2, 1, early.substr(0, 200) + "...");
    // Far into the line: up to 40 bytes after the field, so that a caret can point at it.
    const std::string late = row + ",oops," + row;
    const int column = static_cast<int>(row.size()) + 2;
    check_read_error(header + ",z," + header + "\n" + late + "\n", columns({"z"}),
                     "column 'z': expected a number, found 'oops'", 2, column,
                     late.substr(0, column - 1 + 40) + "...");
  }

  TEST_CASE("the caret of a data error falls under the field") {
    const TempFile file("t,y\n0,1\n0.1,x1\n");
    const DataError e = error_from<DataError>([&] { read_file(file.path(), columns({"y"})); });
    CHECK(momentid::render_with_caret(e) == file.path() +
                                                ":3:5: column 'y': expected a number, found "
                                                "'x1'\n 3 | 0.1,x1\n   |     ^");
  }

  // --- Errors: binary files -------------------------------------------------------------------

  TEST_CASE("a binary file that ends inside its header is reported") {
    check_read_error(std::string("MOMNTID1\x05\x00", 10), columns({"y"}),
                     "the file ends inside its header: expected a 4-byte header length after "
                     "'MOMNTID1', found 2 bytes",
                     1, 1, "");
    check_read_error(std::string("MOMNTID1\x14\x00\x00\x00y,v\n", 16), columns({"y"}),
                     "the file ends inside its header: expected 20 bytes of header text, found 4",
                     1, 1, "");
    check_read_error(std::string("MOMNTID1\xff\xff\xff\xff", 12), columns({"y"}),
                     "the header length 4294967295 is too large (at most 16777216 bytes of "
                     "header text)",
                     1, 1, "");
  }

  TEST_CASE("a binary file without a header row asks for one") {
    check_read_error(binary_file("# momentid: dt=1\n", {}), columns({"y"}),
                     "expected a header row naming the columns", 1, 1, "# momentid: dt=1");
  }

  TEST_CASE("a binary file that ends inside a row is reported with the row") {
    std::string bytes = binary_file("t,y,v,x\n", {0, 1, 2, 3, 0.1, 1, 2, 3, 0.2, 1});
    bytes += "abcd";
    check_read_error(bytes, columns({"y"}), "the file ends inside row 3: 20 bytes of a 32-byte row",
                     3, 3, "");
  }

  TEST_CASE("a missing column of a binary file is reported at the line of its header text") {
    check_read_error(binary_file("# momentid: dt=0.1\nt,y\n", {0, 1, 0.1, 2}), columns({"y", "v"}),
                     "missing column 'v' (the header has: t, y)", 2, 1, "t,y");
  }

  TEST_CASE("a non-finite value of a binary file is reported by row and column number") {
    check_read_error(binary_file("t,y,v\n", {0, 1, 2, 0.1, kNaN, 2}), columns({"y"}),
                     "column 'y': expected a number (a missing value? missing drop-row or "
                     "split-run passes over it), found 'nan'",
                     2, 2, "");
    check_read_error(binary_file("t,y,v\n", {0, 1, -kInf}), columns({"y", "v"}),
                     "column 'v': expected a finite number, found '-inf'", 1, 3, "");
  }

  TEST_CASE("a non-finite value of a binary file in a column not read is accepted") {
    CHECK(read_text(binary_file("y,x\n", {1, kNaN, 2, kInf}), columns({"y"})).values ==
          std::vector<double>{1, 2});
  }

  TEST_CASE("a run number of a binary file that is not an integer is reported") {
    check_read_error(binary_file("y,run\n", {1, 1, 2, 1.5}), columns({"y"}),
                     "column 'run': expected an integer, found '1.5'", 2, 2, "");
  }

  TEST_CASE("a non-uniform time step of a binary file is reported by row and column number") {
    check_read_error(binary_file("y,t\n", {1, 0, 2, 0.1, 3, 0.3}), columns({"y"}),
                     "non-uniform time step: 0.2 after 0.1 at t = 0.3 (the steps before it "
                     "average 0.1): give the sample interval with dt 0.1 if the samples are "
                     "equally spaced",
                     3, 2, "");
  }

  TEST_CASE("rows of a binary file taken many at a time keep every check of one row") {
    // 5000 rows of t, y, v, x; each problem at row 3001 (from 1), deep inside a block.
    constexpr int kRows = 5000, kBad = 3000;
    const auto record = [&](int row, int field, double value) {
      std::vector<double> values;
      for (int n = 0; n < kRows; ++n) {
        const double x = n;
        values.insert(values.end(), {x * 0.25, x + 0.5, -x, 2 * x});
      }
      values[static_cast<std::size_t>(4 * row + field)] = value;
      return binary_file("t,y,v,x\n", values);
    };
    check_read_error(record(kBad, 1, kNaN), columns({"x", "y"}),
                     "column 'y': expected a number (a missing value? missing drop-row or "
                     "split-run passes over it), found 'nan'",
                     kBad + 1, 2, "");
    check_read_error(record(kBad, 3, kInf), columns({"x", "y"}),
                     "column 'x': expected a finite number, found 'inf'", kBad + 1, 4, "");
    // The time steps are checked four rows at a time: the row in each place of a four.
    for (const int bad : {kBad, kBad + 1, kBad + 2, kBad + 3}) {
      CAPTURE(bad);
      const double t = bad * 0.25;
      check_read_error(record(bad, 0, t + 0.125), columns({"y"}),
                       "non-uniform time step: 0.375 after 0.25 at t = " +
                           momentid::shortest_decimal(t + 0.125) +
                           " (the steps before it average 0.25): give the sample interval with "
                           "dt 0.25 if the samples are equally spaced",
                       bad + 1, 1, "");
      check_read_error(
          record(bad, 0, 0), columns({"y"}),
          "non-increasing time: t = 0 after t = " + momentid::shortest_decimal(t - 0.25) +
              " (samples must be in increasing time order)",
          bad + 1, 1, "");
    }
    // A value that is not finite in a column not read: every row delivered.
    const Contents unread = read_text(record(kBad, 3, kNaN), columns({"y"}));
    CHECK(unread.rows == kRows);
    CHECK(unread.values[kBad] == kBad + 0.5);
    // A missing value dropped: the rows around it are delivered, in blocks of any size.
    ColumnRequest request = columns({"v", "y", "y"});
    request.layout.missing = momentid::MissingValues::kDropRow;
    const std::string bytes = record(kBad, 2, kNaN);
    for (const std::size_t max_rows : {std::size_t{7}, std::size_t{4096}}) {
      const Contents c = read_text(bytes, request, max_rows);
      REQUIRE(c.values.size() == 3 * (kRows - 1));
      for (int n = 0, at = 0; n < kRows; ++n) {
        if (n == kBad) continue;
        const std::vector<double> row(c.values.begin() + at, c.values.begin() + at + 3);
        const double x = n;
        CHECK(row == std::vector<double>{-x, x + 0.5, x + 0.5});
        at += 3;
      }
      CHECK(c.rows == kRows - 1);
      CHECK(c.missing.rows == 1);
      CHECK(c.time_step == 0.25);
    }
  }

  TEST_CASE("too few rows of a binary file are reported at the last row or the header") {
    check_read_error(binary_file("y\n", {1}), columns({"y"}),
                     "the data have 1 row; at least 2 are needed", 1, 1, "");
    check_read_error(binary_file("# c\ny\n", {}), columns({"y"}),
                     "the data have 0 rows; at least 2 are needed", 2, 1, "y");
  }
}
