// One particle field as an HDF5 dataset, in the types that restart files and snapshots hold.
#pragma once
#include <cstdint>
#include <string>
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

// Reads back what write_field wrote, into the field's own type.
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<double>& v);
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<Vec3>& v);
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<std::uint64_t>& v);
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<std::int64_t>& v);
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<TimeBin>& v);
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<std::uint8_t>& v);
void read_field(const hdf5::File& f, const std::string& dataset, std::vector<Species>& v);

}  // namespace fountain::io
