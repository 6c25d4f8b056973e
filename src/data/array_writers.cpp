#include "data/array_writers.hpp"

#include <sys/resource.h>
#include <sys/statvfs.h>
#include <unistd.h>
#ifdef MOMENTID_WITH_HDF5
#include <hdf5.h>
#endif
#ifdef MOMENTID_WITH_MATIO
#include <matio.h>
#endif

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <set>

#include "common/decimal.hpp"
#include "data/format.hpp"
#include "data/temporary.hpp"
#include "data/text.hpp"
#include "momentid/error.hpp"
#include "momentid/writer.hpp"

namespace momentid::data {
namespace {

// A file name beside the target for a library that opens files itself; removed unless
// renamed into place, and by a signal that ends the program. A device or a pipe is not replaced:
// the finished file is copied into it.
class TemporaryPath {
 public:
  explicit TemporaryPath(const std::string& target) : target_(target) {
    path_ = target + ".partial-XXXXXX";
    const int fd = create_temporary(path_);
    if (fd < 0) throw Error(target + ": cannot write the output file: " + std::strerror(errno));
    ::close(fd);
    std::remove(path_.c_str());  // the library creates it afresh
  }
  TemporaryPath(const TemporaryPath&) = delete;
  TemporaryPath& operator=(const TemporaryPath&) = delete;
  ~TemporaryPath() {
    if (done_) return;
    std::remove(path_.c_str());
    forget_temporary();
  }
  const std::string& path() const { return path_; }
  // The error for a `kind` file (MATLAB, HDF5) that its library failed to write, with the cause
  // when it is seen (the libraries say no more than that they failed): a file within a write of
  // the size limit, or a device with less than a write's room left.
  Error failed(const std::string& kind) const {
    constexpr std::uintmax_t kSlack = 64 * 1024;  // a write of the libraries' own, or more
    std::string why;
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(path_, error);
    rlimit limit{};
    struct statvfs disk {};
    if (getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY && !error &&
        size + kSlack >= limit.rlim_cur) {
      why = ": the file reached the size limit (ulimit -f)";
    } else if (statvfs(std::filesystem::absolute(path_, error).parent_path().c_str(), &disk) == 0 &&
               std::uintmax_t{disk.f_bavail} * disk.f_frsize < kSlack) {
      why = ": no space left on the device";
    }
    return Error(target_ + ": cannot write the " + kind + " file" + why);
  }
  void commit() {
    std::error_code error;
    const auto status = std::filesystem::status(target_, error);
    if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status)) {
      copy_into_target();
    } else if (std::rename(path_.c_str(), target_.c_str()) != 0) {
      throw Error(target_ + ": cannot write the output file: " + std::strerror(errno));
    }
    done_ = true;
    forget_temporary();
  }

 private:
  void copy_into_target() const {
    const File in(std::fopen(path_.c_str(), "rb"));
    if (!in) throw Error(target_ + ": cannot write the output file: " + std::strerror(errno));
    OutputFile out(target_);
    std::vector<char> buffer(1 << 20);
    std::size_t got = 0;
    while ((got = std::fread(buffer.data(), 1, buffer.size(), in.get())) > 0) {
      out.write(buffer.data(), got);
    }
    if (std::ferror(in.get())) throw Error(target_ + ": cannot write the output file");
    out.commit();
    std::remove(path_.c_str());
  }

  std::string target_, path_;
  bool done_ = false;
};

// --- NumPy ----------------------------------------------------------------------------------

class NpyWriter final : public ArrayWriter {
 public:
  NpyWriter(const std::string& path, std::size_t columns, std::size_t rows)
      : width_(columns), file_(path) {
    std::string header = "{'descr': '<f8', 'fortran_order': False, 'shape': (" +
                         std::to_string(rows) + ", " + std::to_string(columns) + "), }";
    // Magic, version 1.0, the header length; the whole preamble a multiple of 64 bytes.
    const std::size_t total = (10 + header.size() + 1 + 63) / 64 * 64;
    header.append(total - 10 - header.size() - 1, ' ');
    header.push_back('\n');
    std::string preamble = "\x93NUMPY\x01";
    preamble.push_back('\0');
    preamble.push_back(static_cast<char>(header.size() & 0xff));
    preamble.push_back(static_cast<char>(header.size() >> 8));
    file_.write(preamble.data(), preamble.size());
    file_.write(header.data(), header.size());
  }
  void rows(const double* values, std::size_t count) override {
    bytes_.resize(count * width_ * sizeof(double));
    // Little-endian float64, whatever this machine's byte order.
    for (std::size_t i = 0; i < bytes_.size() / 8; ++i) {
      const auto bits = std::bit_cast<std::uint64_t>(values[i]);
      for (int b = 0; b < 8; ++b) bytes_[8 * i + b] = static_cast<char>(bits >> (8 * b));
    }
    file_.write(bytes_.data(), bytes_.size());
  }
  void commit() override { file_.commit(); }

 private:
  std::size_t width_;
  OutputFile file_;
  std::vector<char> bytes_;
};

// --- MATLAB ---------------------------------------------------------------------------------
#ifdef MOMENTID_WITH_MATIO

class MatWriter final : public ArrayWriter {
 public:
  MatWriter(const std::string& path, const std::vector<std::string>& columns,
            const DataMetadata& metadata, std::size_t rows, bool level_73)
      : target_(path),
        temporary_(path),
        names_(columns),
        metadata_(metadata),
        rows_(rows),
        level_73_(level_73) {
    data_.resize(columns.size());
    for (auto& column : data_) column.reserve(rows);
    std::set<std::string> used;
    for (std::string& name : names_) {
      std::string base = matlab_name(name);
      std::string unique = base;
      for (int k = 2; used.count(unique) != 0 || unique == "momentid_metadata"; ++k) {
        unique = base.substr(0, 58) + "_" + std::to_string(k);
      }
      used.insert(unique);
      name = unique;
    }
  }

  void rows(const double* values, std::size_t count) override {
    for (std::size_t r = 0; r < count; ++r) {
      for (std::size_t c = 0; c < data_.size(); ++c) {
        data_[c].push_back(values[r * data_.size() + c]);
      }
    }
  }

  void commit() override {
#ifdef MOMENTID_WITH_HDF5
    if (level_73_) H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are ours to report
#endif
    mat_t* file =
        Mat_CreateVer(temporary_.path().c_str(), nullptr, level_73_ ? MAT_FT_MAT73 : MAT_FT_MAT5);
    if (file == nullptr) throw Error(target_ + ": cannot write the MATLAB file");
    bool ok = true;
    const auto write = [&](const char* name, matio_classes type, matio_types data_type,
                           std::size_t n, void* values) {
      std::size_t dims[2] = {n, 1};
      if (type == MAT_C_CHAR) std::swap(dims[0], dims[1]);
      matvar_t* v = Mat_VarCreate(name, type, data_type, 2, dims, values, MAT_F_DONT_COPY_DATA);
      ok = ok && v != nullptr &&
           Mat_VarWrite(file, v, level_73_ ? MAT_COMPRESSION_NONE : MAT_COMPRESSION_ZLIB) == 0;
      Mat_VarFree(v);
    };
    for (std::size_t c = 0; c < data_.size(); ++c) {
      write(names_[c].c_str(), MAT_C_DOUBLE, MAT_T_DOUBLE, rows_, data_[c].data());
    }
    double dt = 0;
    if (const auto text = metadata_.get("dt");
        text && std::find(names_.begin(), names_.end(), "dt") == names_.end() &&
        std::sscanf(text->c_str(), "%lf", &dt) == 1) {
      write("dt", MAT_C_DOUBLE, MAT_T_DOUBLE, 1, &dt);
    }
    std::string lines = header_text(metadata_, {});
    if (!lines.empty() && lines.back() == '\n') lines.pop_back();
    if (lines.size() > 1) {
      write("momentid_metadata", MAT_C_CHAR, MAT_T_UINT8, lines.size(), lines.data());
    }
    ok = Mat_Close(file) == 0 && ok;
    if (!ok || !reads_back()) throw temporary_.failed("MATLAB");
    temporary_.commit();
  }

 private:
  // Whether the file holds every column as written: matio's compressed writer reports success
  // when the disk is full, and leaves a file cut short.
  bool reads_back() const {
    mat_t* file = Mat_Open(temporary_.path().c_str(), MAT_ACC_RDONLY);
    if (file == nullptr) return false;
    bool ok = true;
    for (std::size_t c = 0; c < data_.size() && ok; ++c) {
      matvar_t* v = Mat_VarRead(file, names_[c].c_str());
      ok = v != nullptr && v->data_type == MAT_T_DOUBLE && v->rank == 2 &&
           v->dims[0] * v->dims[1] == rows_ &&
           (rows_ == 0 || (v->data != nullptr &&
                           std::memcmp(v->data, data_[c].data(), rows_ * sizeof(double)) == 0));
      Mat_VarFree(v);
    }
    return Mat_Close(file) == 0 && ok;
  }

  std::string target_;
  TemporaryPath temporary_;
  std::vector<std::string> names_;
  DataMetadata metadata_;
  std::size_t rows_;
  bool level_73_;
  std::vector<std::vector<double>> data_;
};

#endif

// --- HDF5 -----------------------------------------------------------------------------------
#ifdef MOMENTID_WITH_HDF5

class Hdf5Writer final : public ArrayWriter {
 public:
  Hdf5Writer(const std::string& path, const std::vector<std::string>& columns,
             const DataMetadata& metadata, std::size_t rows)
      : target_(path), temporary_(path), rows_(rows) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    file_ = H5Fcreate(temporary_.path().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (file_ < 0) throw Error(target_ + ": cannot write the HDF5 file");
    const hsize_t dims = rows;
    space_ = H5Screate_simple(1, &dims, nullptr);
    const hid_t properties = H5Pcreate(H5P_DATASET_CREATE);
    const hsize_t chunk = std::clamp<hsize_t>(rows, 1, 1 << 16);
    if (rows > 0) H5Pset_chunk(properties, 1, &chunk);
    std::set<std::string> used;
    for (const std::string& column : columns) {
      std::string name = column;
      std::replace(name.begin(), name.end(), '/', '_');
      if (name.empty() || name == ".") name.assign(1, '_');
      for (int k = 2; used.count(name) != 0; ++k) name = column + "_" + std::to_string(k);
      used.insert(name);
      names_.push_back(name);
      datasets_.push_back(H5Dcreate2(file_, name.c_str(), H5T_IEEE_F64LE, space_, H5P_DEFAULT,
                                     properties, H5P_DEFAULT));
      ok_ = ok_ && datasets_.back() >= 0;
    }
    H5Pclose(properties);
    // Each pair as an attribute for other readers, and the lines as they are for momentid.
    for (const DataMetadata::Line& line : metadata.lines()) {
      for (const auto& [key, value] : line) {
        if (key != "momentid_metadata") attribute(key, value);
      }
    }
    std::string lines = header_text(metadata, {});
    if (!lines.empty() && lines.back() == '\n') lines.pop_back();
    if (lines.size() > 1) attribute("momentid_metadata", lines);
  }
  ~Hdf5Writer() override { close(); }

  void rows(const double* values, std::size_t count) override {
    const std::size_t width = datasets_.size();
    column_.resize(count);
    const hsize_t start = written_, length = count;
    const hid_t memory = H5Screate_simple(1, &length, nullptr);
    ok_ =
        ok_ && H5Sselect_hyperslab(space_, H5S_SELECT_SET, &start, nullptr, &length, nullptr) >= 0;
    hashes_.resize(width);
    for (std::size_t c = 0; c < width && ok_; ++c) {
      for (std::size_t r = 0; r < count; ++r) column_[r] = values[r * width + c];
      hashes_[c].add(column_.data(), count);
      ok_ = H5Dwrite(datasets_[c], H5T_NATIVE_DOUBLE, memory, space_, H5P_DEFAULT,
                     column_.data()) >= 0;
    }
    H5Sclose(memory);
    written_ += count;
  }

  // The file is read back before it takes the target's name: HDF5's return codes catch a full
  // disk, and the read-back whatever they might not.
  void commit() override {
    ok_ = close() && ok_ && written_ == rows_;
    std::vector<std::uint64_t> expected(names_.size(), ColumnHash().value());
    for (std::size_t c = 0; c < hashes_.size(); ++c) expected[c] = hashes_[c].value();
    if (!ok_ || !hdf5_holds(temporary_.path(), names_, rows_, expected)) {
      throw temporary_.failed("HDF5");
    }
    temporary_.commit();
  }

 private:
  void attribute(const std::string& key, const std::string& value) {
    const hid_t scalar = H5Screate(H5S_SCALAR);
    double number = 0;
    hid_t a = -1;
    if (key == "dt" && std::sscanf(value.c_str(), "%lf", &number) == 1) {
      a = H5Acreate2(file_, key.c_str(), H5T_IEEE_F64LE, scalar, H5P_DEFAULT, H5P_DEFAULT);
      ok_ = ok_ && a >= 0 && H5Awrite(a, H5T_NATIVE_DOUBLE, &number) >= 0;
    } else {
      const hid_t type = H5Tcopy(H5T_C_S1);
      H5Tset_size(type, std::max<std::size_t>(value.size(), 1));
      a = H5Acreate2(file_, key.c_str(), type, scalar, H5P_DEFAULT, H5P_DEFAULT);
      std::string padded = value;
      padded.resize(std::max<std::size_t>(value.size(), 1), '\0');
      ok_ = ok_ && a >= 0 && H5Awrite(a, type, padded.data()) >= 0;
      H5Tclose(type);
    }
    if (a >= 0) H5Aclose(a);
    H5Sclose(scalar);
  }

  bool close() {
    bool ok = true;
    for (hid_t d : datasets_) ok = (d < 0 || H5Dclose(d) >= 0) && ok;
    datasets_.clear();
    if (space_ >= 0) H5Sclose(space_);
    space_ = -1;
    if (file_ >= 0) ok = H5Fclose(file_) >= 0 && ok;
    file_ = -1;
    return ok;
  }

  std::string target_;
  TemporaryPath temporary_;
  std::size_t rows_, written_ = 0;
  hid_t file_ = -1, space_ = -1;
  std::vector<std::string> names_;
  std::vector<hid_t> datasets_;
  std::vector<double> column_;
  std::vector<ColumnHash> hashes_;
  bool ok_ = true;
};

// Whether dataset `name` of `file` holds `rows` float64 values that hash to `hash`, read in
// chunks.
bool dataset_holds(hid_t file, const std::string& name, std::size_t rows, std::uint64_t hash) {
  const hid_t dataset = H5Dopen2(file, name.c_str(), H5P_DEFAULT);
  if (dataset < 0) return false;
  const hid_t space = H5Dget_space(dataset);
  hsize_t extent = 0;
  bool ok = space >= 0 && H5Sget_simple_extent_ndims(space) == 1 &&
            H5Sget_simple_extent_dims(space, &extent, nullptr) == 1 && extent == rows;
  constexpr hsize_t kChunk = 1 << 16;
  std::vector<double> values(std::min<hsize_t>(std::max<hsize_t>(rows, 1), kChunk));
  ColumnHash read;
  for (hsize_t start = 0; ok && start < rows; start += kChunk) {
    const hsize_t length = std::min<hsize_t>(kChunk, rows - start);
    const hid_t memory = H5Screate_simple(1, &length, nullptr);
    ok = H5Sselect_hyperslab(space, H5S_SELECT_SET, &start, nullptr, &length, nullptr) >= 0 &&
         H5Dread(dataset, H5T_NATIVE_DOUBLE, memory, space, H5P_DEFAULT, values.data()) >= 0;
    H5Sclose(memory);
    read.add(values.data(), length);
  }
  if (space >= 0) H5Sclose(space);
  H5Dclose(dataset);
  return ok && read.value() == hash;
}

#endif

}  // namespace

void ColumnHash::add(const double* values, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) {
    hash_ = (hash_ ^ std::bit_cast<std::uint64_t>(values[i])) * 1099511628211ULL;
  }
}

void ColumnHash::add_bytes(const unsigned char* bytes, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) hash_ = (hash_ ^ bytes[i]) * 1099511628211ULL;
}

#ifdef MOMENTID_WITH_HDF5
bool hdf5_holds(const std::string& path, const std::vector<std::string>& names, std::size_t rows,
                const std::vector<std::uint64_t>& hashes) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return false;
  bool ok = names.size() == hashes.size();
  for (std::size_t c = 0; c < names.size() && ok; ++c) {
    ok = dataset_holds(file, names[c], rows, hashes[c]);
  }
  return H5Fclose(file) >= 0 && ok;
}
#endif

std::string matlab_name(const std::string& name) {
  std::string out;
  for (char c : name) {
    const bool word = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
    out.push_back(word ? c : '_');
  }
  if (out.empty() || !((out[0] >= 'a' && out[0] <= 'z') || (out[0] >= 'A' && out[0] <= 'Z'))) {
    out = "c_" + out;
  }
  return out.substr(0, 63);
}

std::unique_ptr<ArrayWriter> open_npy_writer(const std::string& path, std::size_t columns,
                                             std::size_t rows) {
  return std::make_unique<NpyWriter>(path, columns, rows);
}

std::unique_ptr<ArrayWriter> open_mat_writer(const std::string& path,
                                             const std::vector<std::string>& columns,
                                             const DataMetadata& metadata, std::size_t rows,
                                             bool level_73) {
#ifdef MOMENTID_WITH_MATIO
  return std::make_unique<MatWriter>(path, columns, metadata, rows, level_73);
#else
  throw Error(path + ": this momentid was built without matio: it writes no .mat files");
#endif
}

std::unique_ptr<ArrayWriter> open_hdf5_writer(const std::string& path,
                                              const std::vector<std::string>& columns,
                                              const DataMetadata& metadata, std::size_t rows) {
#ifdef MOMENTID_WITH_HDF5
  return std::make_unique<Hdf5Writer>(path, columns, metadata, rows);
#else
  throw Error(path + ": this momentid was built without HDF5: it writes no HDF5 files");
#endif
}

void quiet_array_libraries() {
#ifdef MOMENTID_WITH_HDF5
  // Before any other HDF5 call, or it has no effect.
  H5dont_atexit();
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
#endif
}

}  // namespace momentid::data
