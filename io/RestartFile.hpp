// Restart files: the whole state of a run, versioned and checksummed, in portable HDF5.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "particles/CollisionlessParticles.hpp"
#include "particles/GasParticles.hpp"
#include "step/StarFormationTally.hpp"

namespace fountain::io {

// 3: dark matter (/DarkMatter), gas a_grav and potential, particle counts in /Restart.
// 6: hybrid gas fields, stars among the collisionless particles, star formation tally.
// 7: the integer time at which the step in progress began (TiStepBegin).
// 8: the particle fields stored and checksummed in the order of the table of particle fields
//    (particles/ParticleFields.hpp), the fields it flags for restarts.
// 9: the mesh step of comoving TreePM (MeshStepBin, MeshStepBegin) and the mesh's parts of
//    the accelerations and potentials.
inline constexpr int kRestartFormatVersion = 10;

struct RestartState {
  GasParticles gas;
  CollisionlessParticles dm;  // empty in a run without dark matter
  std::int64_t ti_current = 0;
  // A file written inside a step (after its recut, before its tasks) holds the particles at
  // the step's end time ti_current; the step began at ti_step_begin (= ti_current otherwise).
  std::int64_t ti_step_begin = 0;
  // Comoving TreePM: the mesh step in progress (bin -1: none).
  int mesh_step_bin = -1;
  std::int64_t mesh_step_begin = 0;
  long long steps = 0;
  int snapshots_written = 0;
  int next_output = 1;
  double radiated_energy = 0.0;  // by cooling, since the start
  std::uint64_t next_particle_id = 0;  // the id the next spawned star takes (0: none spawned yet)
  star_formation::StarFormationTally star_formation;  // since the start
  std::string parameters_yaml;  // the parameters the run was started with
  long long serial = 0;  // of the last piece set written (0: none), for the next set's names
  // Read as a share (RestartShare): `gas` holds some of the run's particles, gas_places each
  // one's place in the run (a set's pieces), or, read_as_rows, the places gas_first,
  // gas_first + 1, ... (rows of a file written whole), of gas_total in all. Read whole:
  // gas_shared is false, gas_places is empty and gas_total is gas.size().
  bool gas_shared = false;
  bool read_as_rows = false;
  std::vector<std::uint64_t> gas_places;
  std::uint64_t gas_first = 0;
  std::uint64_t gas_total = 0;
  // The same for the collisionless particles (`dm`), read as a share with the gas.
  std::vector<std::uint64_t> dm_places;
  std::uint64_t dm_first = 0;
  std::uint64_t dm_total = 0;
};

// Writes atomically (temporary file, then rename). Every field of the gas (/Gas) and of the
// collisionless particles, dark matter and stars (/DarkMatter) that the table of particle fields
// flags for restarts is stored under its key, with the particle counts, a format version and a
// checksum over all of it.
void write_restart(const std::string& path, const RestartState& state);
// The same from a run's own stores, which are written where they lie, never copied; the
// particles of `scalars` are not read.
void write_restart(const std::string& path, const RestartState& scalars, const GasParticles& gas,
                   const CollisionlessParticles& dm);

// Across MPI ranks a restart is a set: each rank writes a piece with the particles of the
// cells it owns, each with its index in the run's particle order, then rank 0 writes the file
// at `path` itself (the master), holding everything else and naming the pieces by file name
// (they sit beside it, so a run folder can be moved). Pieces carry the write's serial number
// in their names, so a set being written never overwrites the one the master names: a run
// killed half-way through writing keeps the previous set whole.
struct RestartPiece {
  GasParticles gas;
  CollisionlessParticles dm;
  std::vector<std::uint64_t> gas_index, dm_index;  // each particle's place in the whole run
};
std::string restart_piece_name(const std::string& path, long long serial, int rank);
void write_restart_piece(const std::string& piece_path, const RestartPiece& piece);
// A piece of a run's own stores: their rows gas_rows and dm_rows (as the run holds them,
// not copied whole; one field at a time is gathered), each row's place in the run in
// gas_index and dm_index. The file is that of the RestartPiece of those rows.
struct RestartPieceRows {
  const GasParticles& gas;
  const std::vector<std::size_t>& gas_rows;
  const CollisionlessParticles& dm;
  const std::vector<std::size_t>& dm_rows;
  const std::vector<std::uint64_t>& gas_index;
  const std::vector<std::uint64_t>& dm_index;
};
void write_restart_piece(const std::string& piece_path, const RestartPieceRows& piece);
// `scalars` is the state without particles; the totals are the whole run's particle counts.
void write_restart_master(const std::string& path, const RestartState& scalars, long long serial, int pieces,
                          std::uint64_t gas_total, std::uint64_t dm_total);
// Removes the pieces beside `path` that its current master (if any) does not name.
void remove_stale_restart_pieces(const std::string& path);

// Reads and verifies a restart file, or a master and its pieces (put back in the run's
// order): a missing file or piece, another format version, a field whose length disagrees
// with the stored particle count, a checksum that does not match (a corrupted file), or
// pieces that do not fill the run's particles exactly once, throws InputError naming the file.
RestartState read_restart(const std::string& path);

// Across ranks that hold shares of the particles (runs without star formation): rank r of R
// reads the pieces p of a set with p % R == r, with their places, each piece's checksum
// checked; whether the pieces fill the run's particles exactly once is for the ranks to check
// together. Of a file written whole (by one rank) each rank keeps the rows [N r / R,
// N (r + 1) / R) of the gas and of the collisionless particles, as of initial conditions,
// reading the rest a run of rows at a time for the checksum only.
struct RestartShare {
  int rank = 0, ranks = 1;
  std::uint64_t rows_per_read = 65536;  // of a file written whole, per field and read
};
RestartState read_restart(const std::string& path, const RestartShare& share);

}  // namespace fountain::io
