// Reading a record in shards, on several threads: the result does not depend on the thread
// count, and the cut (shards of any size, in any format) changes the moments by rounding only.

#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "momentid/convert.hpp"
#include "momentid/data_pass.hpp"
#include "momentid/validate.hpp"
#include "test_support.hpp"

namespace {

namespace fs = std::filesystem;
using momentid::DataMoments;
using momentid::DataOptions;
using momentid::DataSource;
using momentid::Moment;

// A directory of its own, removed at the end.
struct Directory : momentid::testing::Directory {
  Directory() : momentid::testing::Directory("momentid_test_shards") {}
};

// Two runs of the Duffing oscillator, 3000 samples each, as CSV.
std::string duffing_csv(const Directory& dir) {
  const momentid::Model model = momentid::testing::model_file("duffing.mom");
  auto options = momentid::testing::options_for(model, 3000, 7);
  options.runs = 2;
  const std::string path = dir / "d.csv";
  momentid::simulate_to_file(model, options, path, momentid::DataWriter::Format::kCsv);
  return path;
}

// Plain, input and lagged moments over y, v (states) and x (input): lags reach 7 rows back.
std::vector<Moment> some_moments() {
  return {Moment({{0, 2, 0}}),
          Moment({{1, 2, 0}}),
          Moment({{0, 1, 0}, {2, 1, 0}}),
          Moment({{0, 3, 0}, {1, 1, 0}}),
          Moment({{0, 1, 0}, {0, 1, 7}}),
          Moment({{1, 1, 3}, {2, 1, 0}})};
}

DataMoments pass(const std::string& path, std::size_t shard_bytes, std::size_t threads,
                 const momentid::FileLayout& layout = {}) {
  DataOptions options;
  options.record.layout = layout;
  options.record.control.shard_bytes = shard_bytes;
  options.record.control.threads = threads;
  options.lags = 4;
  options.batches = 20;
  // As the simulation wrote (a .npy file keeps no metadata).
  options.record.hold = momentid::InputHold::kZeroOrderHold;
  return momentid::moments_from_data(DataSource::file(path), {"y", "v"}, {"x"}, some_moments(),
                                     options);
}

// Everything a pass yields, to the last bit.
void check_identical(const DataMoments& a, const DataMoments& b) {
  CHECK(a.rows == b.rows);
  CHECK(a.runs == b.runs);
  CHECK(a.time_step == b.time_step);
  CHECK(a.estimates.intervals == b.estimates.intervals);
  CHECK(a.estimates.mean == b.estimates.mean);
  CHECK(a.estimates.batch_means == b.estimates.batch_means);
  for (std::size_t c = 0; c < a.channels.size(); ++c) {
    CHECK(a.channels[c].mean == b.channels[c].mean);
    CHECK(a.channels[c].variance == b.channels[c].variance);
    CHECK(a.channels[c].autocorrelation == b.channels[c].autocorrelation);
  }
}

// The same record cut otherwise: the same sums, up to their rounding.
void check_same_sums(const DataMoments& a, const DataMoments& b) {
  CHECK(a.rows == b.rows);
  CHECK(a.runs == b.runs);
  REQUIRE(a.time_step.has_value() == b.time_step.has_value());
  if (a.time_step) CHECK(*a.time_step == doctest::Approx(*b.time_step).epsilon(1e-12));
  CHECK(a.estimates.intervals == b.estimates.intervals);
  for (std::size_t k = 0; k < a.estimates.mean.size(); ++k) {
    CHECK(a.estimates.mean[k] == doctest::Approx(b.estimates.mean[k]).epsilon(1e-12));
  }
  for (std::size_t c = 0; c < a.channels.size(); ++c) {
    CHECK(a.channels[c].mean == doctest::Approx(b.channels[c].mean).epsilon(1e-12));
    CHECK(a.channels[c].variance == doctest::Approx(b.channels[c].variance).epsilon(1e-12));
    for (std::size_t l = 0; l < a.channels[c].autocorrelation.size(); ++l) {
      CHECK(a.channels[c].autocorrelation[l] ==
            doctest::Approx(b.channels[c].autocorrelation[l]).epsilon(1e-12));
    }
  }
}

constexpr std::size_t kWhole = std::size_t{1} << 40;

}  // namespace

TEST_SUITE("shards") {
  TEST_CASE("the thread count changes nothing, to the last bit") {
    const Directory dir;
    const std::string path = duffing_csv(dir);
    // About 75 shards, and 300: then each shard is one stretch.
    for (std::size_t bytes : {8192, 2048}) {
      const DataMoments one = pass(path, bytes, 1);
      for (std::size_t threads : {2, 3, 8}) {
        CAPTURE(bytes);
        CAPTURE(threads);
        check_identical(one, pass(path, bytes, threads));
      }
    }
  }

  TEST_CASE("any cut of the record into shards gives its sums, in every format") {
    const Directory dir;
    const std::string csv = duffing_csv(dir);
    const DataMoments whole = pass(csv, kWhole, 1);
    CHECK(whole.rows == 6000);
    CHECK(whole.runs == 2);
    std::vector<std::string> files{csv};
    for (const auto& [format, name] : std::vector<std::pair<momentid::FileFormat, std::string>>{
             {momentid::FileFormat::kBinary, "d.bin"},
             {momentid::FileFormat::kMat5, "d.mat"},
             {momentid::FileFormat::kMat73, "d73.mat"},
             {momentid::FileFormat::kHdf5, "d.h5"}}) {
      momentid::convert(DataSource::file(csv), dir / name, format);
      files.push_back(dir / name);
    }
    // A 2-D .npy array: its columns named as the CSV file's.
    momentid::convert(DataSource::file(csv), dir / "d.npy", momentid::FileFormat::kNpy);
    files.push_back(dir / "d.npy");
    momentid::FileLayout npy;
    npy.column_names = {"t", "y", "v", "x", "run"};
    for (const std::string& file : files) {
      const std::uintmax_t size = fs::file_size(file);
      const momentid::FileLayout layout = file.ends_with(".npy") ? npy : momentid::FileLayout{};
      // One shard, two, a few, many (100: each one stretch); cuts inside the header of a CSV
      // file too. (A .mat file is always one shard.)
      for (std::size_t shards : {1, 2, 7, 60, 100}) {
        CAPTURE(file);
        CAPTURE(shards);
        check_same_sums(whole, pass(file, static_cast<std::size_t>(size / shards + 1), 2, layout));
      }
    }
  }

  TEST_CASE("channels computed from the others are averaged like them, whatever the cut") {
    const Directory dir;
    const std::string path = duffing_csv(dir);
    // Channels 3 to 6: abs(v) and sign(v), continuous as v is, and abs(-2*x) and sign(x), held
    // as x is; their moments must equal those of the products they stand for.
    DataOptions options;
    options.batches = 20;
    options.record.hold = momentid::InputHold::kZeroOrderHold;
    options.record.control.threads = 2;
    options.computed = {
        {.kind = momentid::ComputedChannel::Kind::kAbs, .argument = {{1.0, {0, 1, 0}}}},
        {.kind = momentid::ComputedChannel::Kind::kSign, .argument = {{1.0, {0, 1, 0}}}},
        {.kind = momentid::ComputedChannel::Kind::kAbs, .argument = {{-2.0, {0, 0, 1}}}},
        {.kind = momentid::ComputedChannel::Kind::kSign, .argument = {{1.0, {0, 0, 1}}}}};
    const std::vector<Moment> moments{Moment({{1, 2, 0}}),
                                      Moment({{3, 2, 0}}),  // abs(v)^2 = v^2
                                      Moment({{3, 1, 0}}),
                                      Moment({{1, 1, 0}, {4, 1, 0}}),  // v*sign(v) = abs(v)
                                      Moment({{0, 1, 0}, {5, 1, 0}}),  // y*abs(-2x) = 2*y*abs(x)
                                      Moment({{0, 1, 0}, {2, 1, 0}, {6, 1, 0}}),  // y*x*sign(x)
                                      Moment({{3, 1, 0}, {0, 1, 4}})};  // abs(v) and y 4 rows back
    std::vector<DataMoments> cuts;
    for (std::size_t bytes : {kWhole, std::size_t{2048}}) {
      options.record.control.shard_bytes = bytes;
      cuts.push_back(
          momentid::moments_from_data(DataSource::file(path), {"y", "v"}, {"x"}, moments, options));
    }
    // Equal products, and 2*y*abs(x) against y*(-2x)... in another order: equal up to rounding.
    const std::vector<double>& mean = cuts[0].estimates.mean;
    REQUIRE(mean.size() == moments.size());
    CHECK(mean[1] == doctest::Approx(mean[0]).epsilon(1e-12));
    CHECK(mean[3] == doctest::Approx(mean[2]).epsilon(1e-12));
    CHECK(mean[2] > 0);
    CHECK(mean[4] == doctest::Approx(2 * mean[5]).epsilon(1e-12));
    check_same_sums(cuts[0], cuts[1]);
  }

  TEST_CASE("under the integration filter a product of channels filtered alone is filtered whole") {
    // y = 1 + sin(2 pi 5 t): the high-pass takes y to sin, whose square has the mean 1/2, and
    // y^2 = 1 + 2 sin + sin^2 to 2 sin - cos(4 pi 5 t)/2, whose mean is 0. The equations filtered
    // whole hold the second.
    const Directory dir;
    const std::string path = dir / "offset_sine.csv";
    {
      std::ofstream out(path);
      out << "t,y,x\n";
      for (int n = 0; n < 20000; ++n) {
        const double t = 0.01 * n;
        out << t << ',' << 1 + std::sin(2 * M_PI * 5 * t) << ',' << std::cos(2 * M_PI * 3 * t)
            << '\n';
      }
    }
    DataOptions options;
    options.batches = 20;
    options.integration = DataOptions::Integration{.corner = 0.5, .dt = 0.01, .integrals = {0, 0}};
    options.computed = {
        {.kind = momentid::ComputedChannel::Kind::kPolynomial, .argument = {{1.0, {2, 0}}}}};
    const std::vector<Moment> moments{Moment({{0, 2, 0}}), Moment({{2, 1, 0}}),
                                      Moment({{0, 1, 0}})};
    const DataMoments m =
        momentid::moments_from_data(DataSource::file(path), {"y"}, {"x"}, moments, options);
    REQUIRE(m.estimates.mean.size() == 3);
    CHECK(m.estimates.mean[0] == doctest::Approx(0.5).epsilon(0.01));
    CHECK(std::abs(m.estimates.mean[1]) < 0.01);
    CHECK(std::abs(m.estimates.mean[2]) < 0.01);
    // The channel statistics are those of the channels read.
    REQUIRE(m.channels.size() == 2);
    CHECK(m.channels[0].variance == doctest::Approx(0.5).epsilon(0.01));
    CHECK(m.channels[1].variance == doctest::Approx(0.5).epsilon(0.01));
  }

  TEST_CASE("blank lines, CR LF line ends and rows cut by a shard edge read alike") {
    const Directory dir;
    const std::string csv = duffing_csv(dir);
    // The same rows with a blank line after every tenth and Windows line ends.
    std::ifstream in(csv);
    std::ofstream out(dir / "crlf.csv", std::ios::binary);
    std::string line;
    for (int n = 0; std::getline(in, line); ++n) {
      out << line << "\r\n";
      if (n > 10 && n % 10 == 0) out << "  \r\n";
    }
    out.close();
    const DataMoments whole = pass(csv, kWhole, 1);
    for (std::size_t bytes : {1024, 1500, 4096}) {
      CAPTURE(bytes);
      check_same_sums(whole, pass(dir / "crlf.csv", bytes, 2));
    }
  }

  TEST_CASE("an error in a later shard is located as in one pass") {
    const Directory dir;
    const std::string csv = duffing_csv(dir);
    std::ifstream in(csv);
    std::ostringstream text;
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      // Line 5000 gets a field that is not a number.
      text << (n == 5000 ? line.substr(0, line.find(',')) + ",oops" +
                               line.substr(line.find(',', line.find(',') + 1))
                         : line)
           << "\n";
    }
    std::ofstream(dir / "bad.csv") << text.str();
    const auto whole = momentid::testing::error_from<momentid::DataError>(
        [&] { pass(dir / "bad.csv", kWhole, 1); });
    CHECK(whole.location().line == 5000);
    for (std::size_t bytes : {1024, 50000}) {
      const auto sharded = momentid::testing::error_from<momentid::DataError>(
          [&] { pass(dir / "bad.csv", bytes, 2); });
      CHECK(std::string(sharded.what()) == whole.what());
    }
    // A binary file: the row is the error's line.
    momentid::convert(DataSource::file(csv), dir / "d.bin", momentid::FileFormat::kBinary);
    const std::uintmax_t size = fs::file_size(dir / "d.bin");
    {
      std::fstream bin(dir / "d.bin", std::ios::in | std::ios::out | std::ios::binary);
      const double nan = std::nan("");
      bin.seekp(static_cast<std::streamoff>(size - 40 * 5 * sizeof(double) + sizeof(double)));
      bin.write(reinterpret_cast<const char*>(&nan), sizeof nan);
    }
    const auto one =
        momentid::testing::error_from<momentid::DataError>([&] { pass(dir / "d.bin", kWhole, 1); });
    const auto many =
        momentid::testing::error_from<momentid::DataError>([&] { pass(dir / "d.bin", 4096, 2); });
    CHECK(std::string(many.what()) == one.what());
    CHECK(one.location().line == 5961);
  }

  TEST_CASE("a file of few rows cut into shards is refused for them") {
    const Directory dir;
    std::ofstream(dir / "short.csv") << "# " << std::string(5000, 'x') << "\nt,y,v,x\n0,1,2,3\n"
                                     << "0.1,1,2,3\n0.2,1,2,3\n";
    DataOptions options;
    options.record.control.shard_bytes = 1024;
    options.min_rows = 10;
    const auto e = momentid::testing::error_from<momentid::DataError>([&] {
      momentid::moments_from_data(DataSource::file(dir / "short.csv"), {"y", "v"}, {"x"},
                                  some_moments(), options);
    });
    CHECK(std::string(e.what()) ==
          dir / "short.csv" + ":1:1: the data have 3 rows; at least 10 are needed");
  }
  TEST_CASE("a source's passes read the file as it was first opened, or say that it changed") {
    const Directory dir;
    const std::string path = duffing_csv(dir);
    const std::string copy = dir / "copy.csv";
    fs::copy_file(path, copy);
    const auto pass = [&](const DataSource& source) {
      return momentid::moments_from_data(source, {"y", "v"}, {"x"}, some_moments(), DataOptions{})
          .rows;
    };
    const DataSource source = DataSource::file(path);
    const std::size_t rows = pass(source);
    // The same bytes written again, between two passes of one source (and of its copies).
    fs::copy_file(copy, path, fs::copy_options::overwrite_existing);
    fs::last_write_time(path, fs::last_write_time(path) + std::chrono::seconds(1));
    const DataSource later = source;
    const std::string changed =
        path +
        ": the file changed while it was read (it was written to): read it when it is "
        "complete";
    for (const DataSource* s : {&source, &later}) {
      const auto e = momentid::testing::error_from<momentid::Error>([&] { pass(*s); });
      CHECK(std::string(e.what()) == changed);
    }
    // validate and convert, which read the record whole, say it too (and convert writes nothing).
    const momentid::Model model = momentid::testing::model_file("duffing.mom");
    CHECK(std::string(momentid::testing::error_from<momentid::Error>([&] {
                        momentid::validate(model, source, {});
                      }).what()) == changed);
    CHECK(std::string(momentid::testing::error_from<momentid::Error>([&] {
                        momentid::convert(source, dir / "out.csv", momentid::FileFormat::kCsv, {},
                                          std::nullopt);
                      }).what()) == changed);
    CHECK(!fs::exists(dir / "out.csv"));
    // A new source reads the file as it is now.
    CHECK(pass(DataSource::file(path)) == rows);
  }
  TEST_CASE("a file that changes while the pass reads it is an error naming it") {
    const Directory dir;
    const std::string path = duffing_csv(dir);
    const auto size = fs::file_size(path);
    const std::string copy = dir / "copy.csv";
    fs::copy_file(path, copy);
    // Each change is made once, as the pass reports that it has read everything.
    const auto changed_by = [&](const std::function<void()>& change) {
      fs::copy_file(copy, path, fs::copy_options::overwrite_existing);
      DataOptions options;
      options.record.control.threads = 2;
      options.record.control.shard_bytes = 4096;
      bool done = false;
      options.record.control.progress = [&](std::size_t, std::optional<double> fraction) {
        if (done || fraction != 1.0) return;
        done = true;
        change();
      };
      const auto e = momentid::testing::error_from<momentid::Error>([&] {
        momentid::moments_from_data(DataSource::file(path), {"y", "v"}, {"x"}, some_moments(),
                                    options);
      });
      CHECK(done);
      return std::string(e.what());
    };
    const auto cut = size * 2 / 5;
    CHECK(changed_by([&] { fs::resize_file(path, cut); }) ==
          path + ": the file changed while it was read (its size went from " +
              std::to_string(size) + " to " + std::to_string(cut) +
              " bytes): read it when it is complete");
    CHECK(changed_by([&] { std::ofstream(path, std::ios::app) << "600,0,0,0\n"; }) ==
          path + ": the file changed while it was read (its size went from " +
              std::to_string(size) + " to " + std::to_string(size + 10) +
              " bytes): read it when it is complete");
    // A new version moved into place, as a writer that renames its temporary file does.
    CHECK(changed_by([&] {
            fs::copy_file(copy, dir / "new.csv", fs::copy_options::overwrite_existing);
            fs::rename(dir / "new.csv", path);
          }) == path +
                    ": the file changed while it was read (it was replaced or removed): read "
                    "it when it is complete");
  }

  TEST_CASE(
      "a pass stops when its caller asks: no shard is started after, and Interrupted is thrown") {
    // 10^5 shards of two rows: read whole, the pass outlasts the first question by far.
    const std::size_t rows = 200000;
    std::vector<double> y(rows), v(rows), x(rows);
    for (std::size_t n = 0; n < rows; ++n) {
      y[n] = std::sin(0.01 * static_cast<double>(n));
      v[n] = std::cos(0.013 * static_cast<double>(n));
      x[n] = std::sin(0.7 * static_cast<double>(n));
    }
    momentid::MemoryData data;
    data.rows = rows;
    data.columns = {{"y", y.data()}, {"v", v.data()}, {"x", x.data()}};
    data.metadata.add_line({{"dt", "0.01"}});
    DataOptions options;
    options.record.control.threads = 2;
    options.record.control.shard_bytes = 48;
    int asked = 0;
    std::size_t rows_read = 0;
    options.record.control.interrupted = [&] { return ++asked >= 2; };
    options.record.control.progress = [&](std::size_t read, std::optional<double>) {
      rows_read = read;
    };
    CHECK_THROWS_AS(momentid::moments_from_data(DataSource::memory(std::move(data)), {"y", "v"},
                                                {"x"}, some_moments(), options),
                    momentid::Interrupted);
    CHECK(asked == 2);
    CHECK(rows_read < rows);
  }
}
