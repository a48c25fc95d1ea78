// GADGET's unformatted binary snapshot format (1, and 2's labelled blocks), as N-GenIC, 2LPTic and MUSIC write initial conditions.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/Vec3.hpp"

namespace fountain::io {

// The 256-byte header, with the particle totals as 64-bit (low word + 2^32 high word).
struct GadgetHeader {
  std::array<std::uint64_t, 6> count_this_file{};
  std::array<std::uint64_t, 6> count_total{};
  std::array<double, 6> mass_table{};  // 0: masses per particle in the MASS block
  double time = 0.0;                   // the scale factor in cosmological files
  double redshift = 0.0;
  double box_size = 0.0;
  double omega0 = 0.0, omega_lambda = 0.0, hubble_param = 0.0;
  int files = 1;
  int flag_sfr = 0, flag_feedback = 0, flag_cooling = 0, flag_stellar_age = 0, flag_metals = 0;
  int flag_entropy_ics = 0;  // 1: the U block holds the entropic function, not u
};

// One particle type's values as the file stores them (GADGET units and conventions: no
// conversion is done here). Masses are per particle, from the MASS block or the mass table.
struct GadgetParticles {
  std::vector<Vec3> x, v;
  std::vector<std::uint64_t> id;
  std::vector<double> mass;
  std::vector<double> u;  // type 0 only; empty when the file has no U block
};

struct GadgetSnapshot {
  GadgetHeader header;  // of the first file, with count_this_file summed over all files
  std::array<GadgetParticles, 6> types;
};

// Reads `path`, or the set path.0 .. path.(n-1) when `path` itself does not exist (n from the
// first file's header). Byte order (from the first record's marker), format 1 or 2 (a first
// record of 8 bytes is format 2's label), float or double (from each block's size) and 32- or
// 64-bit IDs (likewise) are detected. Blocks after U (a snapshot's RHO, HSML, ...) are not
// read. A missing, truncated or inconsistent file throws InputError naming the file and block.
GadgetSnapshot read_gadget_binary(const std::string& path);

// Whether the file at `path` (or path.0) starts as a GADGET binary file does.
bool is_gadget_binary(const std::string& path);

struct GadgetBinaryLayout {
  bool double_precision = false;
  bool long_ids = false;
  bool swap_bytes = false;  // write the other byte order
  int format = 1;           // 1, or 2 (labelled blocks)
  int files = 1;            // > 1: path.0 .. path.(files-1), particles dealt in order
};

// Writes the snapshot (count_total and counts taken from `types`; the mass table is written
// as given, and the MASS block holds the types whose table entry is 0).
void write_gadget_binary(const std::string& path, const GadgetSnapshot& snapshot, const GadgetBinaryLayout& layout);

}  // namespace fountain::io
