// MATLAB .mat files, version 5 (compressed or not) and 7.3 (HDF5 underneath), through matio.
// Each real double or single vector is a channel named as the variable; a matrix is one channel
// per column, `NAME[:, k]` (k from 0), with the samples along its longer dimension (a matrix
// wider than tall holds its channels in rows: `NAME[k, :]`). Scalars serve --dt-from, and
// `fs`, `Fs`, `sample_rate` and `wf_increment` (of any numeric class) state the sampling. A
// requested variable is read whole when the reading starts.

#include <matio.h>
#ifdef MOMENTID_WITH_HDF5
#include <hdf5.h>
#endif

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>

#include "data/column_store.hpp"
#include "data/format.hpp"
#include "data/formats.hpp"

namespace momentid::data {
namespace {

// The text variable in which momentid's writer keeps the metadata lines.
constexpr const char* kMetadataVariable = "momentid_metadata";

// matio reports through a log function; its first message of a call becomes part of ours
// instead of going to standard error. Calls into matio take turns, as its logging is global.
std::mutex matio_lock;
std::string matio_message;

void log_to_message(int, char* message) {
  if (!matio_message.empty() || message == nullptr) return;
  matio_message = message;
  matio_message.resize(std::min(matio_message.find('\n'), matio_message.size()));
}

struct MatioCall {
  std::lock_guard<std::mutex> lock{matio_lock};
  MatioCall() {
    matio_message.clear();
    Mat_LogInitFunc("momentid", log_to_message);
#ifdef MOMENTID_WITH_HDF5
    // Level 7.3 files are HDF5: its own error printing would go to standard error.
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
#endif
  }
};

const char* class_name(matio_classes type) {
  switch (type) {
    case MAT_C_DOUBLE:
      return "double";
    case MAT_C_SINGLE:
      return "single";
    case MAT_C_CHAR:
      return "char (text)";
    case MAT_C_CELL:
      return "cell";
    case MAT_C_STRUCT:
      return "struct";
    case MAT_C_INT8:
      return "int8";
    case MAT_C_UINT8:
      return "uint8";
    case MAT_C_INT16:
      return "int16";
    case MAT_C_UINT16:
      return "uint16";
    case MAT_C_INT32:
      return "int32";
    case MAT_C_UINT32:
      return "uint32";
    case MAT_C_INT64:
      return "int64";
    case MAT_C_UINT64:
      return "uint64";
    case MAT_C_SPARSE:
      return "sparse";
    default:
      return "another kind of";
  }
}

// Closed also when a constructor that opened it throws.
struct MatClose {
  void operator()(mat_t* file) const {
    const MatioCall call;
    Mat_Close(file);
  }
};
using MatFile = std::unique_ptr<mat_t, MatClose>;

struct VariableFree {
  void operator()(matvar_t* v) const { Mat_VarFree(v); }
};
using Variable = std::unique_ptr<matvar_t, VariableFree>;

class MatStore final : public ColumnStore {
 public:
  explicit MatStore(const std::string& path) : path_(path) {
    list_variables();
    if (metadata_text_) read_metadata();
  }

 private:
  void list_variables() {
    const MatioCall call;
    file_.reset(Mat_Open(path_.c_str(), MAT_ACC_RDONLY));
    if (!file_) fail({path_, 1, 1, ""}, "cannot read the MATLAB file" + detail());
    std::error_code error;
    const std::uintmax_t file_size = std::filesystem::file_size(path_, error);
    while (Variable info{Mat_VarReadNextInfo(file_.get())}) {
      if (info->name == nullptr) continue;
      const std::string name = info->name;
      if (name == kMetadataVariable && info->class_type == MAT_C_CHAR) {
        metadata_text_ = true;
        continue;
      }
      const std::size_t rows = info->rank >= 1 ? info->dims[0] : 0;
      const std::size_t columns = info->rank >= 2 ? info->dims[1] : 1;
      const bool numeric = (info->class_type == MAT_C_DOUBLE || info->class_type == MAT_C_SINGLE) &&
                           !info->isComplex;
      const bool number_class =
          info->class_type >= MAT_C_DOUBLE && info->class_type <= MAT_C_UINT64;
      if (stated_name(name)) {
        if (number_class && info->rank == 2 && rows * columns == 1 && !info->isComplex) {
          scalars_.push_back(name);  // a sample rate saved as an integer is one too
          continue;
        }
        stated_why_[name] = std::string("holds ") + (info->isComplex ? "complex " : "") +
                            class_name(info->class_type) + " values, not one real number";
      }
      if (!numeric || info->rank != 2) {
        unusable_[name] = "variable '" + name + "' holds " +
                          (info->rank != 2 ? std::to_string(info->rank) + "-dimensional "
                                           : std::string(info->isComplex ? "complex " : "")) +
                          class_name(info->class_type) +
                          " values: expected a real double or single vector or matrix";
        continue;
      }
      // matio reads what the header claims, whatever the file holds: a header claiming more
      // values than the file can store (one byte each, or zlib's best ratio, 1032, compressed)
      // would give values that were never written.
      const double capacity = static_cast<double>(file_size) *
                              (info->compression == MAT_COMPRESSION_NONE ? 1.0 : 1032.0);
      if (static_cast<double>(rows) * static_cast<double>(columns) > capacity) {
        unusable_[name] = "variable '" + name + "' claims " + std::to_string(rows) + " x " +
                          std::to_string(columns) + " values, more than a file of " +
                          std::to_string(file_size) + " bytes holds (a damaged header?)";
        continue;
      }
      if (rows * columns == 1) {
        scalars_.push_back(name);
        continue;
      }
      const bool by_rows = rows > 1 && columns > rows;  // channels in rows
      const std::size_t channels = rows == 1 || columns == 1 ? 1 : by_rows ? rows : columns;
      for (std::size_t k = 0; k < channels; ++k) {
        names_.push_back(channels == 1 ? name
                         : by_rows     ? name + "[" + std::to_string(k) + ", :]"
                                       : name + "[:, " + std::to_string(k) + "]");
        channels_.push_back({name, k, by_rows});
      }
    }
    if (!matio_message.empty()) {
      fail({path_, 1, 1, ""}, "cannot read the MATLAB file" + detail());
    }
    if (names_.empty() && scalars_.empty() && unusable_.empty()) {
      fail({path_, 1, 1, ""},
           "cannot read the MATLAB file: it holds no variables (damaged or "
           "truncated?)");
    }
  }

 public:
  const char* kind() const override { return "variable"; }
  std::vector<std::string> names() const override { return names_; }

  void prepare(std::size_t channel) override {
    const Channel& c = channels_[channel];
    if (loaded_.count(c.variable) != 0) return;
    const MatioCall call;
    Variable v{Mat_VarRead(file_.get(), c.variable.c_str())};
    if (!v || v->data == nullptr) {
      fail({path_, 1, static_cast<int>(channel) + 1, ""},
           "cannot read variable '" + c.variable + "'" + detail());
    }
    if (!holds_all(*v)) {
      fail({path_, 1, static_cast<int>(channel) + 1, ""}, damaged(*v));
    }
    loaded_.emplace(c.variable, std::move(v));
  }

  DataMetadata metadata() const override { return metadata_; }

  std::size_t length(std::size_t channel) const override {
    const Channel& c = channels_[channel];
    const matvar_t& v = *loaded_.at(c.variable);
    const std::size_t rows = v.dims[0], columns = v.dims[1];
    if (rows == 1 || columns == 1) return rows * columns;
    return c.by_rows ? columns : rows;
  }

  void read(std::size_t channel, std::size_t first, std::size_t count, double* out) override {
    const Channel& c = channels_[channel];
    const matvar_t& v = *loaded_.at(c.variable);
    const std::size_t rows = v.dims[0];
    const bool vector = rows == 1 || v.dims[1] == 1;
    // MATLAB stores by columns: element (r, k) at r + k * rows.
    const auto index = [&](std::size_t n) {
      return vector ? n : c.by_rows ? c.index + n * rows : n + c.index * rows;
    };
    for (std::size_t n = 0; n < count; ++n) {
      const std::size_t at = index(first + n);
      out[n] = v.class_type == MAT_C_DOUBLE
                   ? static_cast<const double*>(v.data)[at]
                   : static_cast<double>(static_cast<const float*>(v.data)[at]);
    }
  }

  std::optional<double> scalar(const std::string& name) override {
    if (std::find(scalars_.begin(), scalars_.end(), name) == scalars_.end()) return std::nullopt;
    const MatioCall call;
    Variable v{Mat_VarRead(file_.get(), name.c_str())};
    if (!v || v->data == nullptr) return std::nullopt;
    if (!holds_all(*v)) fail({path_, 1, 1, ""}, damaged(*v));
    return first_value(*v);
  }

  std::vector<StatedInterval> stated_intervals(const std::vector<std::size_t>&) override {
    std::vector<StatedInterval> out;
    for (const char* name : kStatedIntervalNames) {
      StatedInterval s{name, "variable '" + std::string(name) + "'", scalar(name), ""};
      if (const auto why = stated_why_.find(name); !s.value && why != stated_why_.end()) {
        s.why = why->second;
      }
      if (s.value || !s.why.empty()) out.push_back(std::move(s));
    }
    return out;
  }

 private:
  struct Channel {
    std::string variable;
    std::size_t index = 0;  // the column (or row) of a matrix
    bool by_rows = false;
  };

  static bool stated_name(const std::string& name) {
    return std::find_if(std::begin(kStatedIntervalNames), std::end(kStatedIntervalNames),
                        [&](const char* n) { return name == n; }) != std::end(kStatedIntervalNames);
  }

  // Whether matio read as many values as the variable's dimensions claim (it may read fewer from a
  // damaged file, which are all that may be read).
  static bool holds_all(const matvar_t& v) {
    std::size_t count = 1;
    for (int d = 0; d < v.rank; ++d) {
      if (__builtin_mul_overflow(count, v.dims[d], &count)) return false;
    }
    // Numbers are read by their class, text by its stored width.
    const std::size_t stored = static_cast<std::size_t>(std::max(v.data_size, 0));
    const std::size_t size =
        v.class_type == MAT_C_CHAR ? stored : std::max(stored, Mat_SizeOfClass(v.class_type));
    return size > 0 && count <= v.nbytes / size;
  }
  std::string damaged(const matvar_t& v) const {
    return "variable '" + std::string(v.name ? v.name : "") + "' holds fewer values than its " +
           "dimensions claim: the file is damaged";
  }

  // The first value of a numeric variable, as a double.
  static std::optional<double> first_value(const matvar_t& v) {
    switch (v.class_type) {
      case MAT_C_DOUBLE:
        return *static_cast<const double*>(v.data);
      case MAT_C_SINGLE:
        return *static_cast<const float*>(v.data);
      case MAT_C_INT8:
        return *static_cast<const std::int8_t*>(v.data);
      case MAT_C_UINT8:
        return *static_cast<const std::uint8_t*>(v.data);
      case MAT_C_INT16:
        return *static_cast<const std::int16_t*>(v.data);
      case MAT_C_UINT16:
        return *static_cast<const std::uint16_t*>(v.data);
      case MAT_C_INT32:
        return *static_cast<const std::int32_t*>(v.data);
      case MAT_C_UINT32:
        return *static_cast<const std::uint32_t*>(v.data);
      case MAT_C_INT64:
        return static_cast<double>(*static_cast<const std::int64_t*>(v.data));
      case MAT_C_UINT64:
        return static_cast<double>(*static_cast<const std::uint64_t*>(v.data));
      default:
        return std::nullopt;
    }
  }

  std::string detail() const { return matio_message.empty() ? "" : ": " + matio_message; }

  // The metadata lines a momentid writer stores in a text variable (`# momentid: dt=0.01 ...`).
  void read_metadata() {
    const MatioCall call;
    Variable v{Mat_VarRead(file_.get(), kMetadataVariable)};
    if (!v || v->data == nullptr || v->rank != 2) return;
    if (!holds_all(*v)) fail({path_, 1, 1, ""}, damaged(*v));
    const std::size_t count = v->dims[0] * v->dims[1];
    std::string text;
    for (std::size_t i = 0; i < count; ++i) {
      const unsigned value = v->data_size == 2 ? static_cast<const std::uint16_t*>(v->data)[i]
                                               : static_cast<const unsigned char*>(v->data)[i];
      text.push_back(value < 128 ? static_cast<char>(value) : '?');
    }
    long long number = 0;
    std::size_t begin = 0;
    while (begin < text.size()) {
      const std::size_t end = std::min(text.find('\n', begin), text.size());
      const std::string_view line = std::string_view(text).substr(begin, end - begin);
      ++number;
      const std::size_t tag = line.find(kMetadataTag);
      if (tag != std::string_view::npos) {
        DataMetadata::Line pairs = read_metadata_line(path_ + ":" + kMetadataVariable, number, line,
                                                      tag + kMetadataTag.size());
        if (!pairs.empty()) metadata_.add_line(std::move(pairs));
      }
      begin = end + 1;
    }
  }

  std::string path_;
  MatFile file_;
  std::vector<std::string> names_, scalars_;
  std::map<std::string, std::string> stated_why_;  // why a kStatedIntervalNames variable is no rate
  std::vector<Channel> channels_;
  std::map<std::string, Variable> loaded_;
  bool metadata_text_ = false;
  DataMetadata metadata_;
};

}  // namespace

std::unique_ptr<DataReader> open_mat(File file, const std::string& path,
                                     const ColumnRequest& request, std::string_view) {
  file.reset();  // matio opens the file itself
  return open_column_store(std::make_unique<MatStore>(path), path, request);
}

}  // namespace momentid::data
