#include "io/FieldDatasets.hpp"

namespace fountain::io {

namespace {
template <class T>
std::vector<std::int32_t> as_int32(std::span<const T> v) {
  std::vector<std::int32_t> out(v.size());
  for (std::size_t k = 0; k < v.size(); ++k) out[k] = static_cast<std::int32_t>(v[k]);
  return out;
}

// Small integers come back through doubles, which hold every int32 exactly.
template <class T>
void read_small_integers(const hdf5::File& f, const std::string& dataset, std::vector<T>& v,
                         const hdf5::RowRange* rows) {
  const std::vector<double> raw = f.read_doubles(dataset, rows);
  v.assign(raw.size(), T{});
  for (std::size_t k = 0; k < raw.size(); ++k) v[k] = static_cast<T>(static_cast<int>(raw[k]));
}
}  // namespace

void write_field(hdf5::File& f, const std::string& dataset, const std::vector<double>& v) { f.write_dataset(dataset, v); }
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<Vec3>& v) { f.write_dataset(dataset, v); }
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<std::uint64_t>& v) {
  f.write_dataset(dataset, v);
}
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<std::int64_t>& v) {
  f.write_dataset(dataset, std::vector<std::uint64_t>(v.begin(), v.end()));
}
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<TimeBin>& v) {
  f.write_dataset(dataset, as_int32(std::span<const TimeBin>(v)));
}
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<std::uint8_t>& v) {
  f.write_dataset(dataset, as_int32(std::span<const std::uint8_t>(v)));
}
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<Species>& v) {
  f.write_dataset(dataset, as_int32(std::span<const Species>(v)));
}

void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const double> v) {
  f.write_rows(dataset, first, v);
}
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const Vec3> v) {
  f.write_rows(dataset, first, std::span<const double>(reinterpret_cast<const double*>(v.data()), 3 * v.size()), 3);
}
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const std::uint64_t> v) {
  f.write_rows(dataset, first, v);
}
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const std::int64_t> v) {
  const std::vector<std::uint64_t> out(v.begin(), v.end());
  f.write_rows(dataset, first, std::span<const std::uint64_t>(out));
}
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const TimeBin> v) {
  f.write_rows(dataset, first, std::span<const std::int32_t>(as_int32(v)));
}
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const std::uint8_t> v) {
  f.write_rows(dataset, first, std::span<const std::int32_t>(as_int32(v)));
}
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const Species> v) {
  f.write_rows(dataset, first, std::span<const std::int32_t>(as_int32(v)));
}

void read_field(const hdf5::File& f, const std::string& dataset, std::vector<double>& v, const hdf5::RowRange* rows) {
  v = f.read_doubles(dataset, rows);
}
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<Vec3>& v, const hdf5::RowRange* rows) {
  v = f.read_vec3(dataset, rows);
}
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<std::uint64_t>& v,
                const hdf5::RowRange* rows) {
  v = f.read_uint64(dataset, rows);
}
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<std::int64_t>& v,
                const hdf5::RowRange* rows) {
  const std::vector<std::uint64_t> raw = f.read_uint64(dataset, rows);
  v.assign(raw.size(), 0);
  for (std::size_t k = 0; k < raw.size(); ++k) v[k] = static_cast<std::int64_t>(raw[k]);
}
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<TimeBin>& v, const hdf5::RowRange* rows) {
  read_small_integers(f, dataset, v, rows);
}
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<std::uint8_t>& v,
                const hdf5::RowRange* rows) {
  read_small_integers(f, dataset, v, rows);
}
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<Species>& v, const hdf5::RowRange* rows) {
  read_small_integers(f, dataset, v, rows);
}

}  // namespace fountain::io
