// Small RAII helpers over the HDF5 C API for the solver's writers
// (result.h5, the mesh export's .h5): handles that close themselves, string
// attributes, and a file writer of 1-D and 2-D double / int64 datasets.
#pragma once

#include <hdf5.h>

#include <filesystem>
#include <string>
#include <type_traits>
#include <vector>

namespace pba {

// Closes an HDF5 handle on every path out of a scope.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

inline bool WriteStringAttribute(hid_t object, const char* name, const std::string& value) {
  Handle type(H5Tcopy(H5T_C_S1), H5Tclose);
  if (!type.ok() || H5Tset_size(type.get(), value.empty() ? 1 : value.size()) < 0) return false;
  Handle space(H5Screate(H5S_SCALAR), H5Sclose);
  Handle attribute(H5Acreate2(object, name, type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT),
                   H5Aclose);
  return attribute.ok() && H5Awrite(attribute.get(), type.get(), value.c_str()) >= 0;
}

class H5Writer {
 public:
  explicit H5Writer(const std::filesystem::path& path)
      : path_(path),
        file_(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose) {}

  bool ok() const { return file_.ok() && ok_; }
  hid_t file() const { return file_.get(); }

  // A string attribute on the existing object `object`.
  void Attribute(const char* object, const char* name, const std::string& value) {
    if (!ok()) return;
    Handle handle(H5Oopen(file_.get(), object, H5P_DEFAULT), H5Oclose);
    ok_ = handle.ok() && WriteStringAttribute(handle.get(), name, value);
  }

  void Group(const char* name) {
    Handle group(H5Gcreate2(file_.get(), name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    ok_ = ok_ && group.ok();
  }

  // A virtual dataset `name` (HDF5 1.10 VDS: a view, no copy) of rows
  // [first_row, first_row + rows) and columns [first_col, first_col + cols)
  // of the rows_total x cols_total double dataset `source` of this file
  // (written before): 1-D of `rows` values when cols is 1, else rows x cols.
  // For XDMF readers that take a plain DataItem but no HyperSlab (ParaView's
  // XDMF 3 reader, meshio).
  void View(const std::string& name, const std::string& source, hsize_t rows_total,
            hsize_t cols_total, hsize_t first_row, hsize_t rows, hsize_t first_col, hsize_t cols,
            const std::string& unit, const std::string& components = "") {
    if (!ok()) return;
    const hsize_t view_dims[2] = {rows, cols}, source_dims[2] = {rows_total, cols_total};
    const hsize_t start[2] = {first_row, first_col};
    Handle view_space(H5Screate_simple(cols == 1 ? 1 : 2, view_dims, nullptr), H5Sclose);
    Handle source_space(H5Screate_simple(2, source_dims, nullptr), H5Sclose);
    Handle properties(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
    ok_ = view_space.ok() && source_space.ok() && properties.ok() &&
          H5Sselect_hyperslab(source_space.get(), H5S_SELECT_SET, start, nullptr, view_dims,
                              nullptr) >= 0 &&
          // "." : the source is in this same file, wherever it is moved.
          H5Pset_virtual(properties.get(), view_space.get(), ".", source.c_str(),
                         source_space.get()) >= 0;
    if (!ok_) return;
    Handle dataset(H5Dcreate2(file_.get(), name.c_str(), H5T_IEEE_F64LE, view_space.get(),
                              H5P_DEFAULT, properties.get(), H5P_DEFAULT),
                   H5Dclose);
    ok_ = dataset.ok() && WriteStringAttribute(dataset.get(), "unit", unit) &&
          (components.empty() || WriteStringAttribute(dataset.get(), "components", components));
  }

  // Writes rows x cols (cols = 0: a 1-D dataset of `rows`) from `data`.
  template <typename T>
  void Dataset(const std::string& name, const std::vector<T>& data, hsize_t cols,
               const std::string& unit, const std::string& components = "") {
    if (!ok()) return;
    const hsize_t rows = cols == 0 ? data.size() : data.size() / cols;
    const hsize_t dims[2] = {rows, cols};
    Handle space(H5Screate_simple(cols == 0 ? 1 : 2, dims, nullptr), H5Sclose);
    const hid_t type = std::is_same_v<T, double> ? H5T_NATIVE_DOUBLE : H5T_NATIVE_INT64;
    const hid_t file_type = std::is_same_v<T, double> ? H5T_IEEE_F64LE : H5T_STD_I64LE;
    Handle dataset(H5Dcreate2(file_.get(), name.c_str(), file_type, space.get(), H5P_DEFAULT,
                              H5P_DEFAULT, H5P_DEFAULT),
                   H5Dclose);
    ok_ = dataset.ok() &&
          H5Dwrite(dataset.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data.data()) >= 0 &&
          WriteStringAttribute(dataset.get(), "unit", unit) &&
          (components.empty() || WriteStringAttribute(dataset.get(), "components", components));
  }

 private:
  std::filesystem::path path_;
  Handle file_;
  bool ok_ = true;
};

}  // namespace pba
