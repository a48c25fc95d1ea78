// One particle field as an HDF5 dataset, in the types that restart files and snapshots hold.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "core/Vec3.hpp"
#include "io/Hdf5File.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/TimeBin.hpp"

namespace fountain::io {

// Doubles, vectors and ids as they are; integer times as uint64; bins, flags and species as
// int32 (the narrowest integer type the HDF5 wrapper writes).
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<double>& v);
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<Vec3>& v);
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<std::uint64_t>& v);
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<std::int64_t>& v);
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<TimeBin>& v);
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<std::uint8_t>& v);
void write_field(hdf5::File& f, const std::string& dataset, const std::vector<Species>& v);

// The same datasets written in runs of rows: create_field makes the dataset of `rows` rows for
// a field of the type of `like` (its values are not read), write_field_rows writes
// values[0 .. n) as rows first .. first + n.
template <class T>
void create_field(hdf5::File& f, const std::string& dataset, std::size_t rows, const std::vector<T>& like);
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const double> v);
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const Vec3> v);
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const std::uint64_t> v);
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const std::int64_t> v);
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const TimeBin> v);
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const std::uint8_t> v);
void write_field_rows(hdf5::File& f, const std::string& dataset, std::size_t first, std::span<const Species> v);

template <class T>
void create_field(hdf5::File& f, const std::string& dataset, std::size_t rows, const std::vector<T>& /*like*/) {
  using Row = hdf5::File::RowType;
  if constexpr (std::is_same_v<T, double>) {
    f.create_rows_dataset(dataset, Row::float64, rows);
  } else if constexpr (std::is_same_v<T, Vec3>) {
    f.create_rows_dataset(dataset, Row::float64, rows, 3);
  } else if constexpr (std::is_same_v<T, std::uint64_t> || std::is_same_v<T, std::int64_t>) {
    f.create_rows_dataset(dataset, Row::uint64, rows);
  } else {
    static_assert(std::is_same_v<T, TimeBin> || std::is_same_v<T, std::uint8_t> || std::is_same_v<T, Species>);
    f.create_rows_dataset(dataset, Row::int32, rows);
  }
}

// Reads back what write_field wrote, into the field's own type; with `rows`, only those rows.
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<double>& v,
                const hdf5::RowRange* rows = nullptr);
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<Vec3>& v,
                const hdf5::RowRange* rows = nullptr);
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<std::uint64_t>& v,
                const hdf5::RowRange* rows = nullptr);
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<std::int64_t>& v,
                const hdf5::RowRange* rows = nullptr);
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<TimeBin>& v,
                const hdf5::RowRange* rows = nullptr);
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<std::uint8_t>& v,
                const hdf5::RowRange* rows = nullptr);
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<Species>& v,
                const hdf5::RowRange* rows = nullptr);

}  // namespace fountain::io
