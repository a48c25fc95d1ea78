// The state as rank 0 writes it out: every particle in the run's order, in pieces from each leaf's owner.
#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <stdexcept>

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

template <class RangeOf>
std::vector<OwnedRun> owned_runs(const Space& space, const domain::RankLayout& layout, RangeOf range_of) {
  std::vector<std::pair<std::size_t, int>> by_first;
  for (int c : space.leaves()) {
    const auto [first, count] = range_of(space.cell(c));
    if (count > 0) by_first.emplace_back(first, c);
  }
  std::sort(by_first.begin(), by_first.end());
  std::vector<OwnedRun> runs;
  for (const auto& [first, c] : by_first) {
    const std::size_t count = range_of(space.cell(c)).second;
    const int owner = layout.owner(c);
    if (!runs.empty() && runs.back().owner == owner && runs.back().first + runs.back().count == first) {
      runs.back().count += count;
    } else {
      runs.push_back({owner, first, count});
    }
  }
  return runs;
}

}  // namespace

template <class Store, class RangeOf>
void Engine::stream_store(Store& store, RangeOf range_of, const StatePiece<Store>& consume) {
  const std::vector<OwnedRun> runs = owned_runs(space_, layout_, range_of);
  std::size_t covered = 0;
  for (const OwnedRun& run : runs) covered += run.count;
  if (covered != store.size())
    throw std::logic_error(fmt::format("the leaves hold {} of {} particles", covered, store.size()));
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
        unpack_particle_range(reader, piece, n);
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
  // Where every copy is current (alone, the replicated state), rank 0's own arrays are the state.
  if (!ranks_ || !layout_.halo_mode() || all_current_ || space_.leaves().empty()) {
    if (rank() != 0) return;
    gas(gas_, 0, gas_.size());
    collisionless(dm_, 0, dm_.size());
    return;
  }
  stream_store(gas_, [](const Cell& c) { return std::pair{c.first, c.count}; }, gas);
  stream_store(dm_, [](const Cell& c) { return std::pair{c.dm_first, c.dm_count}; }, collisionless);
}

}  // namespace fountain
