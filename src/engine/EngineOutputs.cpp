// The state as rank 0 writes it out: every particle in the run's order, in pieces from each leaf's owner.
#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <tuple>

#include "domain/RankExchange.hpp"
#include "engine/CellMessages.hpp"
#include "engine/Engine.hpp"

namespace fountain {

namespace {

// A run of consecutive leaves (in particle order) with one owner: one stretch of the arrays.
struct OwnedRun {
  int owner;
  std::size_t first, count;
};

// `range_of(c)`: {the cell's first particle in the run's order, its count, its first in this
// rank's arrays}. A run's first is this rank's (meaningful where it owns the run).
template <class RangeOf>
std::vector<OwnedRun> owned_runs(const Space& space, const domain::RankLayout& layout, RangeOf range_of) {
  std::vector<std::pair<std::size_t, int>> by_first;
  for (int c : space.leaves()) {
    const auto [run_first, count, local_first] = range_of(c);
    if (count > 0) by_first.emplace_back(run_first, c);
  }
  std::sort(by_first.begin(), by_first.end());
  std::vector<OwnedRun> runs;
  std::size_t run_end = 0;
  for (const auto& [run_first, c] : by_first) {
    const auto [unused, count, local_first] = range_of(c);
    const int owner = layout.owner(c);
    // Leaves next to each other in the run's order with one owner lie next to each other in
    // its arrays too (its arrays hold leaves in the run's order).
    if (!runs.empty() && runs.back().owner == owner && run_end == run_first) {
      runs.back().count += count;
    } else {
      runs.push_back({owner, local_first, count});
    }
    run_end = run_first + count;
  }
  return runs;
}

}  // namespace

template <class Store, class RangeOf>
void Engine::stream_store(Store& store, std::size_t total, RangeOf range_of, const StatePiece<Store>& consume) {
  const std::vector<OwnedRun> runs = owned_runs(space_, layout_, range_of);
  std::size_t covered = 0;
  for (const OwnedRun& run : runs) covered += run.count;
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
  // Halo mode holds no collisionless particles.
  stream_store(gas_, gas_total_, [&](int c) {
    return std::tuple{run_first_[static_cast<std::size_t>(c)], space_.cell(c).count, space_.cell(c).first};
  }, gas);
}

}  // namespace fountain
