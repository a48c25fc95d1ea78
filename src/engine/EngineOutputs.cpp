// The state as rank 0 writes it out: every particle in the run's order, in pieces from each leaf's owner.
#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <type_traits>

#include "domain/RankExchange.hpp"
#include "engine/CellMessages.hpp"
#include "engine/Engine.hpp"

namespace fountain {

template <class Store>
void Engine::stream_store(Store& store, const StatePiece<Store>& consume) {
  constexpr bool kGas = std::is_same_v<Store, GasParticles>;
  // Runs of consecutive leaves in the run's order with one owner: the leaves cover the run's
  // order end to end, and a rank's arrays hold its leaves in that order, so a run is one
  // stretch of its owner's arrays.
  struct OwnedRun {
    int owner;
    std::size_t first, count;  // first: in the owner's arrays
  };
  std::vector<OwnedRun> runs;
  std::size_t covered = 0;
  for (int c : leaves_in_run_order()) {
    const Cell& cell = space_.cell(c);
    const int owner = layout_.owner(c);
    const std::size_t first = kGas ? cell.first : cell.dm_first, count = kGas ? cell.count : cell.dm_count;
    if (count == 0) continue;
    if (!runs.empty() && runs.back().owner == owner) {
      runs.back().count += count;
    } else {
      runs.push_back({owner, first, count});
    }
    covered += count;
  }
  const std::size_t total = kGas ? gas_total_ : dm_total_;
  if (covered != total) throw std::logic_error(fmt::format("the leaves hold {} of {} particles", covered, total));
  const std::size_t chunk = std::max<std::size_t>(1, config_.output.gather_particles);
  // Both sides walk the same runs in the same order, and messages from one sender arrive in
  // the order sent: rank 0 knows from whom each piece comes and how many there are.
  if (rank() == 0) {
    Store piece;
    for (const OwnedRun& run : runs) {
      if (run.owner == 0) {
        consume(store, run.first, run.count);
        continue;
      }
      for (std::size_t left = run.count; left > 0;) {
        MessageReader reader(ranks_->receive(run.owner));
        const auto n = static_cast<std::size_t>(reader.get<std::uint64_t>());
        if (n == 0 || n > left)
          throw std::logic_error(fmt::format("rank {} sent {} particles of a run of {} still due", run.owner, n, left));
        piece.resize(n);
        unpack_particle_range(reader, piece, 0, n);
        if (!reader.done()) throw std::logic_error(fmt::format("rank {} sent more than {} particles", run.owner, n));
        consume(piece, 0, n);
        left -= n;
      }
    }
    // An output's messages are far larger than a step's: their buffer goes with them.
    ranks_->release_buffers();
  } else {
    std::vector<char> buffer;
    for (const OwnedRun& run : runs) {
      if (run.owner != rank()) continue;
      for (std::size_t at = run.first; at < run.first + run.count; at += chunk) {
        const std::size_t n = std::min(chunk, run.first + run.count - at);
        buffer.clear();
        MessageWriter w(buffer);
        w.put(static_cast<std::uint64_t>(n));
        pack_particle_range(w, store, at, n);
        ranks_->send(0, buffer);
      }
    }
  }
}

void Engine::stream_state(const StatePiece<GasParticles>& gas, const StatePiece<CollisionlessParticles>& collisionless) {
  // Where rank 0 holds every particle, current (alone, the replicated state, halo mode before
  // its first recut), its own arrays are the state.
  if (!ranks_ || !layout_.halo_mode() || space_.leaves().empty()) {
    if (rank() != 0) return;
    gas(gas_, 0, gas_.size());
    collisionless(dm_, 0, dm_.size());
    return;
  }
  stream_store(gas_, gas);
  stream_store(dm_, collisionless);
}

}  // namespace fountain
