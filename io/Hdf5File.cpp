#include "io/Hdf5File.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>
#include <system_error>

#include <fmt/format.h>

#include "core/Error.hpp"

namespace fountain::io::hdf5 {

static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three packed doubles");

namespace {

herr_t collect_innermost(unsigned /*n*/, const H5E_error2_t* err, void* client) {
  // Walking downward, the last entry visited is the innermost (the root cause).
  auto* out = static_cast<std::string*>(client);
  if (err != nullptr && err->desc != nullptr && err->desc[0] != '\0') *out = err->desc;
  return 0;
}

// A link-creation property list that creates missing intermediate groups.
Id intermediate_groups_lcpl() {
  Id lcpl(H5Pcreate(H5P_LINK_CREATE), H5Pclose);
  if (lcpl.valid()) H5Pset_create_intermediate_group(lcpl.get(), 1);
  return lcpl;
}

// A fixed-length, null-terminated C string type able to hold `length` characters.
Id fixed_string_type(std::size_t length) {
  Id type(H5Tcopy(H5T_C_S1), H5Tclose);
  if (!type.valid()) return type;
  if (H5Tset_size(type.get(), length + 1) < 0 || H5Tset_strpad(type.get(), H5T_STR_NULLTERM) < 0)
    return Id();
  return type;
}

std::string describe_class(H5T_class_t c) {
  switch (c) {
    case H5T_INTEGER: return "integer";
    case H5T_FLOAT: return "floating-point";
    case H5T_STRING: return "string";
    case H5T_COMPOUND: return "compound";
    case H5T_ARRAY: return "array";
    case H5T_ENUM: return "enum";
    case H5T_VLEN: return "variable-length";
    case H5T_BITFIELD: return "bitfield";
    case H5T_OPAQUE: return "opaque";
    case H5T_REFERENCE: return "reference";
    default: return "unknown";
  }
}

// Reads one string from a dataset or attribute whose file type is `file_type`;
// `read(memory_type, buffer)` does the H5Dread/H5Aread.
template <class ReadFn>
bool read_single_string(hid_t file_type, ReadFn read, std::string& out) {
  if (H5Tis_variable_str(file_type) > 0) {
    Id memory_type(H5Tcopy(H5T_C_S1), H5Tclose);
    if (!memory_type.valid() || H5Tset_size(memory_type.get(), H5T_VARIABLE) < 0) return false;
    char* text = nullptr;
    if (read(memory_type.get(), static_cast<void*>(&text)) < 0) return false;
    out = text != nullptr ? std::string(text) : std::string();
    if (text != nullptr) H5free_memory(text);
    return true;
  }
  const std::size_t size = H5Tget_size(file_type);
  if (size == 0) return false;
  Id memory_type(H5Tcopy(H5T_C_S1), H5Tclose);
  if (!memory_type.valid() || H5Tset_size(memory_type.get(), size + 1) < 0 ||
      H5Tset_strpad(memory_type.get(), H5T_STR_NULLTERM) < 0)
    return false;
  std::vector<char> buffer(size + 1, '\0');
  if (read(memory_type.get(), static_cast<void*>(buffer.data())) < 0) return false;
  out.assign(buffer.data());  // up to the first null
  while (!out.empty() && out.back() == ' ') out.pop_back();  // Fortran-style space padding
  return true;
}

std::string join_path(const std::string& object, const std::string& name) {
  return object == "/" ? "/" + name : object + "/" + name;
}

}  // namespace

void silence_hdf5_errors() {
  static const bool done = [] {
    // HDF5 keeps a file whose last write failed (a full disk) half-open, and its clean-up at
    // exit then crashes on it. Every file here is closed by its owner, so that clean-up is
    // not needed: a full disk ends in the error message, not a crash. (Effective only before
    // the library's first use, which this is.)
    H5dont_atexit();
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)done;
}

std::string hdf5_error_detail() {
  std::string detail;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collect_innermost, &detail);
  H5Eclear2(H5E_DEFAULT);
  // The file drivers' messages span lines (time stamp, buffer address, byte counts): keep
  // their first words and the system's reason, e.g. "file write failed: File too large".
  const std::string key = "error message = '";
  const std::size_t at = detail.find(key);
  if (at != std::string::npos) {
    const std::size_t end = detail.find('\'', at + key.size());
    const std::size_t colon = detail.find(':');
    if (end != std::string::npos && colon != std::string::npos && colon < at)
      detail = detail.substr(0, colon) + ": " + detail.substr(at + key.size(), end - at - key.size());
  }
  return detail;
}

bool is_hdf5(const std::string& path) {
  silence_hdf5_errors();
  const htri_t r = H5Fis_hdf5(path.c_str());
  H5Eclear2(H5E_DEFAULT);
  return r > 0;
}

// ---------------------------------------------------------------------------------------

File::File(const std::string& path, Mode mode) : path_(path) {
  silence_hdf5_errors();
  H5Eclear2(H5E_DEFAULT);
  if (mode == Mode::read) {
    file_ = Id(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
    if (!file_.valid()) fail("", "cannot open as an HDF5 file (damaged or truncated?)");
  } else {
    file_ = Id(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    if (!file_.valid()) fail("", "cannot create the HDF5 file");
  }
}

void File::close() {
  if (!file_.valid()) return;
  const herr_t flushed = H5Fflush(file_.get(), H5F_SCOPE_GLOBAL);
  const herr_t closed = file_.close();
  if (flushed < 0 || closed < 0) fail("", "cannot write the file to disk (disk full?)");
}

void File::fail(const std::string& object, const std::string& what) const {
  std::string message = path_ + ": ";
  if (!object.empty()) message += object + ": ";
  message += what;
  const std::string detail = hdf5_error_detail();
  if (!detail.empty()) message += " (HDF5: " + detail + ")";
  throw InputError(message);
}

bool File::exists(const std::string& object) const {
  if (object.empty() || object == "/") return true;
  std::size_t pos = object[0] == '/' ? 1 : 0;
  while (true) {
    const std::size_t slash = object.find('/', pos);
    const std::string prefix = object.substr(0, slash);
    if (!prefix.empty() && prefix != "/") {
      const htri_t r = H5Lexists(file_.get(), prefix.c_str(), H5P_DEFAULT);
      if (r <= 0) {
        H5Eclear2(H5E_DEFAULT);
        return false;
      }
    }
    if (slash == std::string::npos) break;
    pos = slash + 1;
  }
  const htri_t r = H5Oexists_by_name(file_.get(), object.c_str(), H5P_DEFAULT);
  H5Eclear2(H5E_DEFAULT);
  return r > 0;
}

bool File::has_attribute(const std::string& object, const std::string& name) const {
  if (!exists(object)) return false;
  const htri_t r = H5Aexists_by_name(file_.get(), object.c_str(), name.c_str(), H5P_DEFAULT);
  H5Eclear2(H5E_DEFAULT);
  return r > 0;
}

Id File::open_object(const std::string& object) const {
  if (!exists(object)) fail(object, "not found");
  Id id(H5Oopen(file_.get(), object.c_str(), H5P_DEFAULT), H5Oclose);
  if (!id.valid()) fail(object, "cannot open");
  return id;
}

Id File::open_dataset(const std::string& dataset) const {
  if (!exists(dataset)) fail(dataset, "dataset not found");
  Id id(H5Dopen2(file_.get(), dataset.c_str(), H5P_DEFAULT), H5Dclose);
  if (!id.valid()) fail(dataset, "cannot open as a dataset");
  return id;
}

Id File::open_attribute(const std::string& object, const std::string& name) const {
  if (!exists(object)) fail(object, "not found (looking for attribute " + name + ")");
  if (!has_attribute(object, name)) fail(object, "attribute " + name + " not found");
  Id id(H5Aopen_by_name(file_.get(), object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  if (!id.valid()) fail(join_path(object, name), "cannot open attribute");
  return id;
}

DatasetInfo File::dataset_info(const std::string& dataset) const {
  Id ds = open_dataset(dataset);
  Id space(H5Dget_space(ds.get()), H5Sclose);
  Id type(H5Dget_type(ds.get()), H5Tclose);
  if (!space.valid() || !type.valid()) fail(dataset, "cannot read shape or type");
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) fail(dataset, "cannot read shape");
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  if (rank > 0 && H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr) < 0)
    fail(dataset, "cannot read shape");
  DatasetInfo info;
  info.dims.assign(dims.begin(), dims.end());
  info.type_class = H5Tget_class(type.get());
  info.type_size = H5Tget_size(type.get());
  info.is_signed = info.type_class == H5T_INTEGER && H5Tget_sign(type.get()) == H5T_SGN_2;
  return info;
}

// --- Reading datasets ------------------------------------------------------------------

File::Selection File::select_rows(const Id& ds, const std::string& dataset, const RowRange* rows) const {
  Selection out;
  out.file = Id(H5Dget_space(ds.get()), H5Sclose);
  if (!out.file.valid()) fail(dataset, "cannot read size");
  const hssize_t n = H5Sget_simple_extent_npoints(out.file.get());
  if (n < 0) fail(dataset, "cannot read size");
  if (rows == nullptr) {
    out.elements = static_cast<std::size_t>(n);
    return out;
  }
  const int rank = H5Sget_simple_extent_ndims(out.file.get());
  std::vector<hsize_t> dims(static_cast<std::size_t>(std::max(rank, 0)));
  if (rank < 1 || H5Sget_simple_extent_dims(out.file.get(), dims.data(), nullptr) < 0)
    fail(dataset, "cannot select rows of a scalar dataset");
  if (rows->first + rows->count > dims[0])
    fail(dataset, fmt::format("has {} rows, fewer than the {} to {} asked for", dims[0], rows->first,
                              rows->first + rows->count));
  std::vector<hsize_t> start(dims.size(), 0), size = dims;
  start[0] = rows->first;
  size[0] = rows->count;
  out.elements = 1;
  for (hsize_t d : size) out.elements *= d;
  const hsize_t elements = out.elements;
  out.memory = Id(H5Screate_simple(1, &elements, nullptr), H5Sclose);
  if (!out.memory.valid() ||
      H5Sselect_hyperslab(out.file.get(), H5S_SELECT_SET, start.data(), nullptr, size.data(), nullptr) < 0)
    fail(dataset, fmt::format("cannot select rows {} to {}", rows->first, rows->first + rows->count));
  return out;
}

std::vector<double> File::read_doubles(const std::string& dataset, const RowRange* rows) const {
  const DatasetInfo info = dataset_info(dataset);
  if (info.type_class != H5T_FLOAT && info.type_class != H5T_INTEGER)
    fail(dataset, "holds " + describe_class(info.type_class) + " data, expected numbers");
  Id ds = open_dataset(dataset);
  const Selection sel = select_rows(ds, dataset, rows);
  std::vector<double> values(sel.elements);
  if (sel.elements > 0 && H5Dread(ds.get(), H5T_NATIVE_DOUBLE, rows ? sel.memory.get() : H5S_ALL,
                                  rows ? sel.file.get() : H5S_ALL, H5P_DEFAULT, values.data()) < 0)
    fail(dataset, "cannot read data (damaged or truncated file?)");
  return values;
}

std::vector<Vec3> File::read_vec3(const std::string& dataset, const RowRange* rows) const {
  const DatasetInfo info = dataset_info(dataset);
  if (info.dims.size() != 2 || info.dims[1] != 3) {
    std::ostringstream shape;
    for (std::size_t d = 0; d < info.dims.size(); ++d) shape << (d ? " x " : "") << info.dims[d];
    fail(dataset, "has shape (" + shape.str() + "), expected N x 3");
  }
  const std::vector<double> flat = read_doubles(dataset, rows);
  std::vector<Vec3> out(flat.size() / 3);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = {flat[3 * i], flat[3 * i + 1], flat[3 * i + 2]};
  return out;
}

std::vector<std::uint64_t> File::read_uint64(const std::string& dataset, const RowRange* rows) const {
  const DatasetInfo info = dataset_info(dataset);
  if (info.type_class != H5T_INTEGER)
    fail(dataset, "holds " + describe_class(info.type_class) + " data, expected integers");
  Id ds = open_dataset(dataset);
  const Selection sel = select_rows(ds, dataset, rows);
  const hid_t memory = rows ? sel.memory.get() : H5S_ALL, file = rows ? sel.file.get() : H5S_ALL;
  const std::uint64_t first = rows ? rows->first : 0;
  std::vector<std::uint64_t> out(sel.elements);
  if (out.empty()) return out;
  if (info.is_signed) {
    std::vector<std::int64_t> tmp(out.size());
    if (H5Dread(ds.get(), H5T_NATIVE_INT64, memory, file, H5P_DEFAULT, tmp.data()) < 0)
      fail(dataset, "cannot read data (damaged or truncated file?)");
    for (std::size_t i = 0; i < tmp.size(); ++i) {
      if (tmp[i] < 0)
        fail(dataset, "entry " + std::to_string(first + i) + " is " + std::to_string(tmp[i]) + " (must be non-negative)");
      out[i] = static_cast<std::uint64_t>(tmp[i]);
    }
  } else if (H5Dread(ds.get(), H5T_NATIVE_UINT64, memory, file, H5P_DEFAULT, out.data()) < 0) {
    fail(dataset, "cannot read data (damaged or truncated file?)");
  }
  return out;
}

std::string File::read_string(const std::string& dataset) const {
  Id ds = open_dataset(dataset);
  Id type(H5Dget_type(ds.get()), H5Tclose);
  if (!type.valid() || H5Tget_class(type.get()) != H5T_STRING) fail(dataset, "is not a string dataset");
  std::string out;
  const bool ok = read_single_string(type.get(), [&](hid_t memory_type, void* buffer) {
    return H5Dread(ds.get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buffer);
  }, out);
  if (!ok) fail(dataset, "cannot read string");
  return out;
}

// --- Reading attributes ----------------------------------------------------------------

namespace {
struct AttributeShape {
  Id type;
  H5T_class_t type_class = H5T_NO_CLASS;
  bool is_signed = false;
  std::size_t count = 0;
};

AttributeShape attribute_shape(const File& file, hid_t attr, const std::string& where) {
  AttributeShape s;
  s.type = Id(H5Aget_type(attr), H5Tclose);
  Id space(H5Aget_space(attr), H5Sclose);
  if (!s.type.valid() || !space.valid()) file.fail(where, "cannot read type or shape");
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n < 0) file.fail(where, "cannot read shape");
  s.type_class = H5Tget_class(s.type.get());
  s.is_signed = s.type_class == H5T_INTEGER && H5Tget_sign(s.type.get()) == H5T_SGN_2;
  s.count = static_cast<std::size_t>(n);
  return s;
}
}  // namespace

std::vector<double> File::read_attribute_doubles(const std::string& object, const std::string& name) const {
  Id attr = open_attribute(object, name);
  const std::string where = join_path(object, name);
  const AttributeShape shape = attribute_shape(*this, attr.get(), where);
  if (shape.type_class != H5T_FLOAT && shape.type_class != H5T_INTEGER)
    fail(where, "holds " + describe_class(shape.type_class) + " data, expected numbers");
  std::vector<double> values(shape.count);
  if (shape.count > 0 && H5Aread(attr.get(), H5T_NATIVE_DOUBLE, values.data()) < 0) fail(where, "cannot read");
  return values;
}

double File::read_attribute_double(const std::string& object, const std::string& name) const {
  const std::vector<double> v = read_attribute_doubles(object, name);
  if (v.size() != 1)
    fail(join_path(object, name), "has " + std::to_string(v.size()) + " values, expected one");
  return v[0];
}

std::vector<std::uint64_t> File::read_attribute_uint64(const std::string& object, const std::string& name) const {
  Id attr = open_attribute(object, name);
  const std::string where = join_path(object, name);
  const AttributeShape shape = attribute_shape(*this, attr.get(), where);
  std::vector<std::uint64_t> out(shape.count);
  if (shape.count == 0) return out;
  if (shape.type_class == H5T_INTEGER && !shape.is_signed) {
    if (H5Aread(attr.get(), H5T_NATIVE_UINT64, out.data()) < 0) fail(where, "cannot read");
  } else if (shape.type_class == H5T_INTEGER) {
    std::vector<std::int64_t> tmp(shape.count);
    if (H5Aread(attr.get(), H5T_NATIVE_INT64, tmp.data()) < 0) fail(where, "cannot read");
    for (std::size_t i = 0; i < tmp.size(); ++i) {
      if (tmp[i] < 0)
        fail(where, "entry " + std::to_string(i) + " is " + std::to_string(tmp[i]) + " (must be non-negative)");
      out[i] = static_cast<std::uint64_t>(tmp[i]);
    }
  } else if (shape.type_class == H5T_FLOAT) {
    const std::vector<double> tmp = read_attribute_doubles(object, name);
    for (std::size_t i = 0; i < tmp.size(); ++i) {
      if (!(tmp[i] >= 0.0) || tmp[i] != std::floor(tmp[i]) || tmp[i] >= 18446744073709551616.0) {
        std::ostringstream s;
        s << "entry " << i << " is " << tmp[i] << " (must be a non-negative whole number)";
        fail(where, s.str());
      }
      out[i] = static_cast<std::uint64_t>(tmp[i]);
    }
  } else {
    fail(where, "holds " + describe_class(shape.type_class) + " data, expected integers");
  }
  return out;
}

std::vector<std::int64_t> File::read_attribute_int64(const std::string& object, const std::string& name) const {
  Id attr = open_attribute(object, name);
  const std::string where = join_path(object, name);
  const AttributeShape shape = attribute_shape(*this, attr.get(), where);
  std::vector<std::int64_t> out(shape.count);
  if (shape.count == 0) return out;
  if (shape.type_class == H5T_INTEGER && shape.is_signed) {
    if (H5Aread(attr.get(), H5T_NATIVE_INT64, out.data()) < 0) fail(where, "cannot read");
  } else if (shape.type_class == H5T_INTEGER) {
    std::vector<std::uint64_t> tmp(shape.count);
    if (H5Aread(attr.get(), H5T_NATIVE_UINT64, tmp.data()) < 0) fail(where, "cannot read");
    for (std::size_t i = 0; i < tmp.size(); ++i) {
      if (tmp[i] > static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()))
        fail(where, "entry " + std::to_string(i) + " is too large");
      out[i] = static_cast<std::int64_t>(tmp[i]);
    }
  } else if (shape.type_class == H5T_FLOAT) {
    const std::vector<double> tmp = read_attribute_doubles(object, name);
    for (std::size_t i = 0; i < tmp.size(); ++i) {
      if (!std::isfinite(tmp[i]) || tmp[i] != std::floor(tmp[i]) || std::fabs(tmp[i]) >= 9.2e18) {
        std::ostringstream s;
        s << "entry " << i << " is " << tmp[i] << " (must be a whole number)";
        fail(where, s.str());
      }
      out[i] = static_cast<std::int64_t>(tmp[i]);
    }
  } else {
    fail(where, "holds " + describe_class(shape.type_class) + " data, expected integers");
  }
  return out;
}

std::string File::read_attribute_string(const std::string& object, const std::string& name) const {
  Id attr = open_attribute(object, name);
  const std::string where = join_path(object, name);
  const AttributeShape shape = attribute_shape(*this, attr.get(), where);
  if (shape.type_class != H5T_STRING) fail(where, "is not a string");
  if (shape.count != 1) fail(where, "holds " + std::to_string(shape.count) + " strings, expected one");
  std::string out;
  const bool ok = read_single_string(shape.type.get(), [&](hid_t memory_type, void* buffer) {
    return H5Aread(attr.get(), memory_type, buffer);
  }, out);
  if (!ok) fail(where, "cannot read string");
  return out;
}

// --- Writing -----------------------------------------------------------------------------

void File::create_group(const std::string& group) {
  if (exists(group)) return;
  Id lcpl = intermediate_groups_lcpl();
  Id g(H5Gcreate2(file_.get(), group.c_str(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
  if (!g.valid()) fail(group, "cannot create group");
}

Id File::create_dataset(const std::string& dataset, hid_t file_type, const std::vector<hsize_t>& dims) {
  Id space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
  if (!space.valid()) fail(dataset, "cannot create dataspace");
  Id lcpl = intermediate_groups_lcpl();
  Id ds(H5Dcreate2(file_.get(), dataset.c_str(), file_type, space.get(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT),
        H5Dclose);
  if (!ds.valid()) fail(dataset, "cannot create dataset");
  return ds;
}

void File::write_numeric_dataset(const std::string& dataset, hid_t file_type, hid_t memory_type,
                                 const std::vector<hsize_t>& dims, const void* data,
                                 const StringAttributes& attributes) {
  {
    Id ds = create_dataset(dataset, file_type, dims);
    const bool empty = std::any_of(dims.begin(), dims.end(), [](hsize_t d) { return d == 0; });
    if (!empty && H5Dwrite(ds.get(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
      fail(dataset, "cannot write data (disk full?)");
    if (ds.close() < 0) fail(dataset, "cannot close dataset (disk full?)");
  }
  for (const auto& [name, value] : attributes) write_attribute(dataset, name, value);
}

void File::write_dataset(const std::string& dataset, std::span<const double> values,
                         const StringAttributes& attributes) {
  write_numeric_dataset(dataset, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {values.size()}, values.data(), attributes);
}

void File::write_dataset(const std::string& dataset, std::span<const Vec3> values,
                         const StringAttributes& attributes) {
  write_numeric_dataset(dataset, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {values.size(), 3}, values.data(), attributes);
}

void File::write_dataset(const std::string& dataset, std::span<const std::uint64_t> values,
                         const StringAttributes& attributes) {
  write_numeric_dataset(dataset, H5T_STD_U64LE, H5T_NATIVE_UINT64, {values.size()}, values.data(), attributes);
}

template <class T>
void File::write_pieces(const std::string& dataset, hid_t file_type, hid_t memory_type, std::size_t rows,
                        std::size_t columns, const std::function<void(std::size_t, std::span<T>)>& fill) {
  // 2^16 rows a piece: a few MB of buffer, and a write call per piece costs nothing beside it.
  constexpr std::size_t kPieceRows = std::size_t{1} << 16;
  const int rank = columns == 1 ? 1 : 2;
  Id ds = create_dataset(dataset, file_type, rank == 1 ? std::vector<hsize_t>{rows} : std::vector<hsize_t>{rows, columns});
  std::vector<T> buffer(std::min(rows, kPieceRows) * columns);
  for (std::size_t first = 0; first < rows; first += kPieceRows) {
    const std::size_t count = std::min(kPieceRows, rows - first);
    const std::span<T> out(buffer.data(), count * columns);
    fill(first, out);
    const hsize_t start[2] = {first, 0}, size[2] = {count, columns};
    const hsize_t elements = out.size();
    Id file_space(H5Dget_space(ds.get()), H5Sclose);
    Id memory_space(H5Screate_simple(1, &elements, nullptr), H5Sclose);
    if (!file_space.valid() || !memory_space.valid() ||
        H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start, nullptr, size, nullptr) < 0)
      fail(dataset, "cannot select rows to write");
    if (H5Dwrite(ds.get(), memory_type, memory_space.get(), file_space.get(), H5P_DEFAULT, buffer.data()) < 0)
      fail(dataset, "cannot write data (disk full?)");
  }
  if (ds.close() < 0) fail(dataset, "cannot close dataset (disk full?)");
}

void File::create_rows_dataset(const std::string& dataset, RowType type, std::size_t rows, std::size_t columns) {
  const hid_t file_type = type == RowType::float64 ? H5T_IEEE_F64LE
                          : type == RowType::uint64 ? H5T_STD_U64LE
                                                    : H5T_STD_I32LE;
  Id ds = create_dataset(dataset, file_type, columns == 1 ? std::vector<hsize_t>{rows} : std::vector<hsize_t>{rows, columns});
  if (ds.close() < 0) fail(dataset, "cannot close dataset (disk full?)");
}

void File::write_rows_of(const std::string& dataset, hid_t memory_type, std::size_t first, std::size_t rows,
                         std::size_t columns, const void* data) {
  if (rows == 0) return;
  Id ds = open_dataset(dataset);
  const hsize_t start[2] = {first, 0}, size[2] = {rows, columns};
  const hsize_t elements = rows * columns;
  Id file_space(H5Dget_space(ds.get()), H5Sclose);
  Id memory_space(H5Screate_simple(1, &elements, nullptr), H5Sclose);
  if (!file_space.valid() || !memory_space.valid() ||
      H5Sselect_hyperslab(file_space.get(), H5S_SELECT_SET, start, nullptr, size, nullptr) < 0)
    fail(dataset, fmt::format("cannot select rows {} to {}", first, first + rows));
  if (H5Dwrite(ds.get(), memory_type, memory_space.get(), file_space.get(), H5P_DEFAULT, data) < 0)
    fail(dataset, "cannot write data (disk full?)");
  if (ds.close() < 0) fail(dataset, "cannot close dataset (disk full?)");
}

void File::write_rows(const std::string& dataset, std::size_t first, std::span<const double> values,
                      std::size_t columns) {
  write_rows_of(dataset, H5T_NATIVE_DOUBLE, first, values.size() / columns, columns, values.data());
}

void File::write_rows(const std::string& dataset, std::size_t first, std::span<const std::uint64_t> values) {
  write_rows_of(dataset, H5T_NATIVE_UINT64, first, values.size(), 1, values.data());
}

void File::write_rows(const std::string& dataset, std::size_t first, std::span<const std::int32_t> values) {
  write_rows_of(dataset, H5T_NATIVE_INT32, first, values.size(), 1, values.data());
}

void File::write_dataset_in_pieces(const std::string& dataset, std::size_t rows, std::size_t columns,
                                   const DoublePieceFill& fill) {
  write_pieces<double>(dataset, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, rows, columns, fill);
}

void File::write_dataset_in_pieces(const std::string& dataset, std::size_t rows, const IdPieceFill& fill) {
  write_pieces<std::uint64_t>(dataset, H5T_STD_U64LE, H5T_NATIVE_UINT64, rows, 1, fill);
}

void File::write_table(const std::string& dataset, const std::vector<double>& values, std::size_t columns,
                       const StringAttributes& attributes) {
  write_numeric_dataset(dataset, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {values.size() / columns, columns}, values.data(),
                        attributes);
}

void File::write_table(const std::string& dataset, const std::vector<std::uint64_t>& values, std::size_t columns,
                       const StringAttributes& attributes) {
  write_numeric_dataset(dataset, H5T_STD_U64LE, H5T_NATIVE_UINT64, {values.size() / columns, columns}, values.data(),
                        attributes);
}

void File::write_dataset(const std::string& dataset, std::span<const std::int32_t> values,
                         const StringAttributes& attributes) {
  write_numeric_dataset(dataset, H5T_STD_I32LE, H5T_NATIVE_INT32, {values.size()}, values.data(), attributes);
}

void File::write_string_dataset(const std::string& dataset, const std::string& text) {
  Id type = fixed_string_type(text.size());
  if (!type.valid()) fail(dataset, "cannot create string type");
  Id space(H5Screate(H5S_SCALAR), H5Sclose);
  Id lcpl = intermediate_groups_lcpl();
  Id ds(H5Dcreate2(file_.get(), dataset.c_str(), type.get(), space.get(), lcpl.get(), H5P_DEFAULT, H5P_DEFAULT),
        H5Dclose);
  if (!ds.valid()) fail(dataset, "cannot create dataset");
  if (H5Dwrite(ds.get(), type.get(), H5S_ALL, H5S_ALL, H5P_DEFAULT, text.c_str()) < 0)
    fail(dataset, "cannot write data (disk full?)");
  if (ds.close() < 0) fail(dataset, "cannot close dataset (disk full?)");
}

void File::write_numeric_attribute(const std::string& object, const std::string& name, hid_t file_type,
                                   hid_t memory_type, const std::vector<hsize_t>& dims, const void* data) {
  const std::string where = join_path(object, name);
  if (!exists(object)) fail(object, "not found (writing attribute " + name + ")");
  if (has_attribute(object, name) && H5Adelete_by_name(file_.get(), object.c_str(), name.c_str(), H5P_DEFAULT) < 0)
    fail(where, "cannot replace attribute");
  Id space = dims.empty() ? Id(H5Screate(H5S_SCALAR), H5Sclose)
                          : Id(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr), H5Sclose);
  if (!space.valid()) fail(where, "cannot create dataspace");
  Id attr(H5Acreate_by_name(file_.get(), object.c_str(), name.c_str(), file_type, space.get(), H5P_DEFAULT,
                            H5P_DEFAULT, H5P_DEFAULT),
          H5Aclose);
  if (!attr.valid()) fail(where, "cannot create attribute");
  const bool empty = std::any_of(dims.begin(), dims.end(), [](hsize_t d) { return d == 0; });
  if (!empty && H5Awrite(attr.get(), memory_type, data) < 0) fail(where, "cannot write attribute");
}

void File::write_attribute(const std::string& object, const std::string& name, double value) {
  write_numeric_attribute(object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {}, &value);
}

void File::write_attribute(const std::string& object, const std::string& name, int value) {
  const std::int32_t v = value;
  write_numeric_attribute(object, name, H5T_STD_I32LE, H5T_NATIVE_INT32, {}, &v);
}

void File::write_attribute(const std::string& object, const std::string& name, std::int64_t value) {
  write_numeric_attribute(object, name, H5T_STD_I64LE, H5T_NATIVE_INT64, {}, &value);
}

void File::write_attribute(const std::string& object, const std::string& name, const std::string& value) {
  const std::string where = join_path(object, name);
  if (!exists(object)) fail(object, "not found (writing attribute " + name + ")");
  if (has_attribute(object, name) && H5Adelete_by_name(file_.get(), object.c_str(), name.c_str(), H5P_DEFAULT) < 0)
    fail(where, "cannot replace attribute");
  Id type = fixed_string_type(value.size());
  if (!type.valid()) fail(where, "cannot create string type");
  Id space(H5Screate(H5S_SCALAR), H5Sclose);
  Id attr(H5Acreate_by_name(file_.get(), object.c_str(), name.c_str(), type.get(), space.get(), H5P_DEFAULT,
                            H5P_DEFAULT, H5P_DEFAULT),
          H5Aclose);
  if (!attr.valid()) fail(where, "cannot create attribute");
  if (H5Awrite(attr.get(), type.get(), value.c_str()) < 0) fail(where, "cannot write attribute");
}

void File::write_attribute(const std::string& object, const std::string& name, const std::vector<double>& values) {
  write_numeric_attribute(object, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {values.size()}, values.data());
}

void File::write_attribute(const std::string& object, const std::string& name,
                           const std::vector<std::int32_t>& values) {
  write_numeric_attribute(object, name, H5T_STD_I32LE, H5T_NATIVE_INT32, {values.size()}, values.data());
}

void File::write_attribute(const std::string& object, const std::string& name,
                           const std::vector<std::uint32_t>& values) {
  write_numeric_attribute(object, name, H5T_STD_U32LE, H5T_NATIVE_UINT32, {values.size()}, values.data());
}

void File::write_attribute(const std::string& object, const std::string& name,
                           const std::vector<std::int64_t>& values) {
  write_numeric_attribute(object, name, H5T_STD_I64LE, H5T_NATIVE_INT64, {values.size()}, values.data());
}

void File::write_attribute(const std::string& object, const std::string& name,
                           const std::vector<std::uint64_t>& values) {
  write_numeric_attribute(object, name, H5T_STD_U64LE, H5T_NATIVE_UINT64, {values.size()}, values.data());
}

// --- Helpers shared by the GADGET/SWIFT-layout writers ---------------------------------------

AtomicFile::AtomicFile(std::string path, std::string what)
    : path_(std::move(path)), tmp_(path_ + ".tmp"), prefix_("cannot create " + what + " " + path_ + ": ") {
  namespace fs = std::filesystem;
  if (path_.empty()) throw InputError("cannot create " + what + ": empty file name");
  std::error_code ec;
  fs::path parent = fs::path(path_).parent_path();
  if (parent.empty()) parent = ".";
  if (!fs::exists(parent, ec)) throw InputError(prefix_ + "folder " + parent.string() + " does not exist");
  if (!fs::is_directory(parent, ec)) throw InputError(prefix_ + parent.string() + " is not a folder");
  if (::access(parent.c_str(), W_OK | X_OK) != 0)
    throw InputError(prefix_ + "folder " + parent.string() + " is not writable");
  if (fs::is_directory(path_, ec)) throw InputError(prefix_ + "a folder of that name exists");
  write([&](File&) {});
}

AtomicFile::~AtomicFile() {
  if (!file_) return;
  file_.reset();  // closes; a failure here has nothing left to report
  std::error_code ec;
  std::filesystem::remove(tmp_, ec);
}

void AtomicFile::write(const std::function<void(File&)>& part) {
  std::string reason;
  try {
    if (!file_) file_ = std::make_unique<File>(tmp_, File::Mode::create);
    part(*file_);
  } catch (const std::exception& e) {
    reason = e.what();
    if (reason.empty()) reason = "unknown error";
  }
  if (!reason.empty()) fail(std::move(reason));
}

void AtomicFile::commit() {
  std::string reason;
  try {
    if (file_) file_->close();
    file_.reset();
  } catch (const std::exception& e) {
    reason = e.what();
    if (reason.empty()) reason = "unknown error";
  }
  if (reason.empty()) {
    std::error_code ec;
    std::filesystem::rename(tmp_, path_, ec);
    if (ec) reason = "cannot rename " + tmp_ + " to " + path_ + ": " + ec.message();
  }
  if (!reason.empty()) fail(std::move(reason));
}

void AtomicFile::fail(std::string reason) {
  file_.reset();
  std::error_code ec;
  std::filesystem::remove(tmp_, ec);
  // Messages from File start with the temporary file's name; the prefix already says it.
  if (reason.rfind(tmp_ + ": ", 0) == 0) reason = reason.substr(tmp_.size() + 2);
  throw InputError(prefix_ + reason);
}

void write_file_atomically(const std::string& path, const std::string& what,
                           const std::function<void(File&)>& fill) {
  AtomicFile file(path, what);
  file.write(fill);
  file.commit();
}

void write_gadget_header(File& file, const std::array<std::uint64_t, 6>& counts, const std::vector<double>& box_size,
                         double time, const cosmology::CosmologyParams* cosmology) {
  file.create_group("/Header");
  const std::string h = "/Header";
  constexpr std::uint64_t two32 = std::uint64_t{1} << 32;
  if (*std::max_element(counts.begin(), counts.end()) < two32) {
    std::vector<std::uint32_t> c(6);
    for (int t = 0; t < 6; ++t) c[static_cast<std::size_t>(t)] = static_cast<std::uint32_t>(counts[t]);
    file.write_attribute(h, "NumPart_ThisFile", c);
  } else {
    file.write_attribute(h, "NumPart_ThisFile", std::vector<std::uint64_t>(counts.begin(), counts.end()));
  }
  std::vector<std::uint32_t> low(6, 0), high(6, 0);
  for (int t = 0; t < 6; ++t) {
    low[t] = static_cast<std::uint32_t>(counts[t] % two32);
    high[t] = static_cast<std::uint32_t>(counts[t] / two32);
  }
  file.write_attribute(h, "NumPart_Total", low);
  file.write_attribute(h, "NumPart_Total_HighWord", high);
  file.write_attribute(h, "MassTable", std::vector<double>(6, 0.0));
  file.write_attribute(h, "Time", time);
  file.write_attribute(h, "Redshift", cosmology != nullptr ? 1.0 / time - 1.0 : 0.0);
  if (box_size.size() == 1) {
    file.write_attribute(h, "BoxSize", box_size[0]);
  } else {
    file.write_attribute(h, "BoxSize", box_size);
  }
  file.write_attribute(h, "NumFilesPerSnapshot", 1);
  file.write_attribute(h, "Dimension", 3);
  file.write_attribute(h, "Omega0", cosmology != nullptr ? cosmology->omega_m : 0.0);
  file.write_attribute(h, "OmegaLambda", cosmology != nullptr ? cosmology->omega_lambda : 0.0);
  file.write_attribute(h, "HubbleParam", cosmology != nullptr ? cosmology->hubble_param : 1.0);
  if (cosmology != nullptr) file.write_attribute(h, "OmegaBaryon", cosmology->omega_b);
  for (const char* flag : {"Flag_Sfr", "Flag_Cooling", "Flag_Feedback", "Flag_StellarAge", "Flag_Metals",
                           "Flag_Entropy_ICs"})
    file.write_attribute(h, flag, 0);
  file.write_attribute(h, "Flag_DoublePrecision", 1);
}

}  // namespace fountain::io::hdf5
