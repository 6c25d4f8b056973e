// HDF5 files, through the HDF5 C library. Each dataset of floating-point values is a channel
// named by its path without the leading '/' (`run1/disp`; `--columns y=/run1/disp` is the same);
// a 2-D dataset is one channel per column, `PATH[:, k]`, with the samples along its longer
// dimension (wider than tall: `PATH[k, :]`). Datasets are read in hyperslabs of a few thousand
// samples, so memory stays flat whatever their size. The root group's attributes are metadata:
// `dt` and text attributes such as `input-hold`; `fs`, `Fs`, `sample_rate` and `wf_increment`,
// of the file or of a channel's dataset, state the sampling (StatedInterval).

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>

#include "common/decimal.hpp"
#include "data/column_store.hpp"
#include "data/format.hpp"
#include "data/formats.hpp"

namespace momentid::data {
namespace {

// The text attribute in which momentid's writer keeps the metadata lines.
constexpr const char* kMetadataAttribute = "momentid_metadata";

// Closes an HDF5 identifier when it goes out of scope.
class Handle {
 public:
  Handle() = default;
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(Handle&& other) noexcept : id_(other.id_), close_(other.close_) { other.id_ = -1; }
  Handle& operator=(Handle&& other) noexcept {
    std::swap(id_, other.id_);
    std::swap(close_, other.close_);
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  hid_t get() const { return id_; }
  explicit operator bool() const { return id_ >= 0; }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

class Hdf5Store final : public ColumnStore {
 public:
  explicit Hdf5Store(const std::string& path) : path_(path) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are ours to report
    file_ = Handle(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
    if (!file_) fail(where(), "cannot read the HDF5 file (damaged or truncated?)");
    if (H5Lvisit(file_.get(), H5_INDEX_NAME, H5_ITER_INC, visit, this) < 0) {
      fail(where(), "cannot list the datasets of the HDF5 file (damaged or truncated?)");
    }
    read_attributes();
  }

  const char* kind() const override { return "dataset"; }
  std::vector<std::string> names() const override { return names_; }

  std::string column_name(const std::string& requested) const override {
    return requested.starts_with('/') ? requested.substr(1) : requested;
  }

  void prepare(std::size_t channel) override {
    Channel& c = channels_[channel];
    if (c.dataset) return;
    c.dataset = Handle(H5Dopen2(file_.get(), c.path.c_str(), H5P_DEFAULT), H5Dclose);
    if (!c.dataset) fail(where(channel), "cannot open dataset '" + c.path + "'");
    c.space = Handle(H5Dget_space(c.dataset.get()), H5Sclose);
  }

  std::size_t length(std::size_t channel) const override {
    const Channel& c = channels_[channel];
    return c.rank == 1 ? c.dims[0] : c.by_rows ? c.dims[1] : c.dims[0];
  }

  void read(std::size_t channel, std::size_t first, std::size_t count, double* out) override {
    Channel& c = channels_[channel];
    hsize_t start[2] = {first, 0}, counts[2] = {count, 1};
    if (c.rank == 2) {
      if (c.by_rows) {
        start[0] = c.index;
        start[1] = first;
        counts[0] = 1;
        counts[1] = count;
      } else {
        start[1] = c.index;
      }
    }
    const hsize_t memory_count = count;
    const Handle memory(H5Screate_simple(1, &memory_count, nullptr), H5Sclose);
    if (H5Sselect_hyperslab(c.space.get(), H5S_SELECT_SET, start, nullptr, counts, nullptr) < 0 ||
        H5Dread(c.dataset.get(), H5T_NATIVE_DOUBLE, memory.get(), c.space.get(), H5P_DEFAULT, out) <
            0) {
      fail({path_, clamp_to_int(static_cast<long long>(first) + 1), static_cast<int>(channel) + 1,
            ""},
           "cannot read dataset '" + c.path + "' from sample " + std::to_string(first + 1) +
               " (damaged or truncated?)");
    }
  }

  std::optional<double> scalar(const std::string& name) override {
    const std::string path = column_name(name);
    if (H5Aexists(file_.get(), path.c_str()) > 0) return number_attribute(file_.get(), path);
    // A dataset of one value.
    if (H5Lexists(file_.get(), path.c_str(), H5P_DEFAULT) <= 0) return std::nullopt;
    const Handle dataset(H5Dopen2(file_.get(), path.c_str(), H5P_DEFAULT), H5Dclose);
    if (!dataset) return std::nullopt;
    const Handle space(H5Dget_space(dataset.get()), H5Sclose);
    if (H5Sget_simple_extent_npoints(space.get()) != 1) return std::nullopt;
    double value = 0;
    if (H5Dread(dataset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, &value) < 0) {
      return std::nullopt;
    }
    return value;
  }

  DataMetadata metadata() const override { return metadata_; }

  std::vector<StatedInterval> stated_intervals(const std::vector<std::size_t>& channels) override {
    std::vector<StatedInterval> out;
    std::vector<std::string> datasets;
    for (const char* name : kStatedIntervalNames) stated(file_.get(), name, "the file", out);
    for (std::size_t channel : channels) {
      const Channel& c = channels_[channel];
      if (!c.dataset || std::find(datasets.begin(), datasets.end(), c.path) != datasets.end()) {
        continue;
      }
      datasets.push_back(c.path);
      for (const char* name : kStatedIntervalNames) {
        stated(c.dataset.get(), name, "dataset '" + c.path + "'", out);
      }
    }
    return out;
  }

 private:
  struct Channel {
    std::string path;
    int rank = 1;
    hsize_t dims[2] = {0, 0};
    std::size_t index = 0;
    bool by_rows = false;
    Handle dataset, space;
  };

  SourceLocation where(std::size_t channel = 0) const {
    return {path_, 1, static_cast<int>(channel) + 1, ""};
  }

  static herr_t visit(hid_t group, const char* name, const H5L_info_t*, void* data) {
    auto& self = *static_cast<Hdf5Store*>(data);
    const Handle object(H5Oopen(group, name, H5P_DEFAULT), H5Oclose);
    if (!object || H5Iget_type(object.get()) != H5I_DATASET) return 0;
    const std::string path = name;
    const Handle type(H5Dget_type(object.get()), H5Tclose);
    const H5T_class_t type_class = H5Tget_class(type.get());
    if (type_class != H5T_FLOAT) {
      self.unusable_[path] = "dataset '" + path + "' holds " +
                             (type_class == H5T_INTEGER    ? "integer"
                              : type_class == H5T_STRING   ? "text"
                              : type_class == H5T_COMPOUND ? "compound (complex?)"
                                                           : "non-numeric") +
                             " values: expected floating-point values";
      return 0;
    }
    const Handle space(H5Dget_space(object.get()), H5Sclose);
    hsize_t dims[H5S_MAX_RANK];
    const int rank = H5Sget_simple_extent_dims(space.get(), dims, nullptr);
    if (rank > 2) {
      self.unusable_[path] = "dataset '" + path + "' has " + std::to_string(rank) +
                             " dimensions: expected 1 (a channel) or 2 (samples x channels)";
      return 0;
    }
    // A dataset created but never (or only partly) written reads as its fill value: data
    // acquisition that stopped before writing leaves such datasets.
    if (const char* written = unwritten(object.get(), space.get(), rank, dims)) {
      self.unusable_[path] = "dataset '" + path + "' was " + written +
                             " written: its unwritten values would read as the fill value";
      return 0;
    }
    if (rank == 1 && dims[0] > 1) {
      self.add(path, path, 1, dims, 0, false);
    } else if (rank == 2 && dims[0] * dims[1] > 1) {
      const bool by_rows = dims[1] > dims[0];
      const std::size_t channels = by_rows ? dims[0] : dims[1];
      for (std::size_t k = 0; k < channels; ++k) {
        self.add(by_rows ? path + "[" + std::to_string(k) + ", :]"
                         : path + "[:, " + std::to_string(k) + "]",
                 path, 2, dims, k, by_rows);
      }
    }
    return 0;
  }

  void add(const std::string& name, const std::string& path, int rank, const hsize_t* dims,
           std::size_t index, bool by_rows) {
    names_.push_back(name);
    Channel c;
    c.path = path;
    c.rank = rank;
    c.dims[0] = dims[0];
    c.dims[1] = rank == 2 ? dims[1] : 1;
    c.index = index;
    c.by_rows = by_rows;
    channels_.push_back(std::move(c));
  }

  // "never" or "only partly" when storage for some of a dataset's values was never written, else
  // nullptr: a chunked dataset lacks chunks (edge chunks count whole), a contiguous one its
  // storage.
  static const char* unwritten(hid_t dataset, hid_t space, int rank, const hsize_t* dims) {
    if (H5Sget_simple_extent_npoints(space) <= 1) return nullptr;
    const Handle create(H5Dget_create_plist(dataset), H5Pclose);
    if (H5Pget_layout(create.get()) == H5D_CHUNKED) {
      hsize_t chunk[H5S_MAX_RANK];
      if (H5Pget_chunk(create.get(), rank, chunk) != rank) return nullptr;
      hsize_t expected = 1, present = 0;
      for (int d = 0; d < rank; ++d) expected *= (dims[d] + chunk[d] - 1) / chunk[d];
      if (H5Dget_num_chunks(dataset, space, &present) < 0) return nullptr;
      return present == 0 ? "never" : present < expected ? "only partly" : nullptr;
    }
    H5D_space_status_t status = H5D_SPACE_STATUS_ERROR;
    if (H5Pget_layout(create.get()) == H5D_CONTIGUOUS &&
        H5Dget_space_status(dataset, &status) >= 0 && status == H5D_SPACE_STATUS_NOT_ALLOCATED) {
      return "never";
    }
    return nullptr;
  }

  // Whether an attribute holds one value (an array of them is not metadata).
  static bool single(hid_t attribute) {
    const Handle space(H5Aget_space(attribute), H5Sclose);
    return space && H5Sget_simple_extent_npoints(space.get()) == 1;
  }

  std::optional<double> number_attribute(hid_t object, const std::string& name) const {
    const Handle attribute(H5Aopen(object, name.c_str(), H5P_DEFAULT), H5Aclose);
    if (!attribute || !single(attribute.get())) return std::nullopt;
    const Handle type(H5Aget_type(attribute.get()), H5Tclose);
    const H5T_class_t type_class = H5Tget_class(type.get());
    if (type_class != H5T_FLOAT && type_class != H5T_INTEGER) return std::nullopt;
    double value = 0;
    if (H5Aread(attribute.get(), H5T_NATIVE_DOUBLE, &value) < 0) return std::nullopt;
    return value;
  }

  // Attribute `name` of `object` (`owner` in messages), if it has one, as a stated interval.
  void stated(hid_t object, const std::string& name, const std::string& owner,
              std::vector<StatedInterval>& out) const {
    if (H5Aexists(object, name.c_str()) <= 0) return;
    StatedInterval s{name, "attribute '" + name + "' of " + owner, number_attribute(object, name),
                     ""};
    if (!s.value) {
      const auto text = text_attribute(object, name);
      s.why = text ? "holds the text '" + *text + "', not a number" : "does not hold one number";
    }
    out.push_back(std::move(s));
  }

  // A text attribute of one string, fixed-length or variable-length (as h5py writes a str).
  std::optional<std::string> text_attribute(hid_t object, const std::string& name) const {
    const Handle attribute(H5Aopen(object, name.c_str(), H5P_DEFAULT), H5Aclose);
    if (!attribute || !single(attribute.get())) return std::nullopt;
    const Handle type(H5Aget_type(attribute.get()), H5Tclose);
    if (H5Tget_class(type.get()) != H5T_STRING) return std::nullopt;
    if (H5Tis_variable_str(type.get()) > 0) {
      const Handle memory(H5Tcopy(H5T_C_S1), H5Tclose);
      H5Tset_size(memory.get(), H5T_VARIABLE);
      H5Tset_cset(memory.get(), H5Tget_cset(type.get()));
      char* value = nullptr;
      if (H5Aread(attribute.get(), memory.get(), &value) < 0 || value == nullptr) {
        return std::nullopt;
      }
      std::string text = value;
      H5free_memory(value);
      return text;
    }
    std::string text(H5Tget_size(type.get()), '\0');
    if (H5Aread(attribute.get(), type.get(), text.data()) < 0) return std::nullopt;
    text.resize(std::strlen(text.c_str()));
    return text;
  }

  // Root attributes: numbers and strings become metadata; the lines a momentid writer keeps
  // in `momentid_metadata` are taken as they are, the others after them.
  void read_attributes() {
    if (const auto text = text_attribute(file_.get(), kMetadataAttribute)) {
      long long number = 0;
      for (std::size_t begin = 0; begin < text->size();) {
        const std::size_t end = std::min(text->find('\n', begin), text->size());
        const std::string_view line = std::string_view(*text).substr(begin, end - begin);
        ++number;
        if (const std::size_t tag = line.find(kMetadataTag); tag != std::string_view::npos) {
          DataMetadata::Line pairs = read_metadata_line(path_ + ":" + kMetadataAttribute, number,
                                                        line, tag + kMetadataTag.size());
          if (!pairs.empty()) metadata_.add_line(std::move(pairs));
        }
        begin = end + 1;
      }
      return;
    }
    DataMetadata::Line line;
    std::pair<const Hdf5Store*, DataMetadata::Line*> context{this, &line};
    H5Aiterate2(
        file_.get(), H5_INDEX_NAME, H5_ITER_INC, nullptr,
        [](hid_t object, const char* name, const H5A_info_t*, void* data) -> herr_t {
          auto [self, into] = *static_cast<std::pair<const Hdf5Store*, DataMetadata::Line*>*>(data);
          if (const auto number = self->number_attribute(object, name)) {
            into->emplace_back(name, shortest_decimal(*number));
          } else if (const auto text = self->text_attribute(object, name)) {
            into->emplace_back(name, *text);
          }
          return 0;
        },
        &context);
    if (!line.empty()) metadata_.add_line(std::move(line));
  }

  std::string path_;
  Handle file_;
  std::vector<std::string> names_;
  std::vector<Channel> channels_;
  DataMetadata metadata_;
};

}  // namespace

std::unique_ptr<DataReader> open_hdf5(File file, const std::string& path,
                                      const ColumnRequest& request, std::string_view) {
  file.reset();  // the HDF5 library opens the file itself
  return open_column_store(std::make_unique<Hdf5Store>(path), path, request);
}

}  // namespace momentid::data
