// Halo mode across MPI ranks: each rank keeps current only its own leaves and their neighbours (docs/design.md, "Halo mode").
#include <fmt/format.h>

#include <algorithm>

#include "domain/RankExchange.hpp"
#include "engine/CellMessages.hpp"
#include "engine/Engine.hpp"
#include "timestep/Integration.hpp"

namespace fountain {

void Engine::exchange_with_ranks(const std::function<void(int, MessageWriter&)>& pack,
                                 const std::function<void(int, MessageReader&)>& unpack, const char* what) {
  const int n = ranks_->size();
  to_ranks_.clear();
  to_rank_sizes_.assign(static_cast<std::size_t>(n), 0);
  MessageWriter w(to_ranks_);
  for (int q = 0; q < n; ++q) {
    const std::size_t before = to_ranks_.size();
    if (q != layout_.rank()) pack(q, w);
    to_rank_sizes_[static_cast<std::size_t>(q)] = to_ranks_.size() - before;
  }
  const auto in = ranks_->alltoall(to_ranks_, to_rank_sizes_);
  for (int r = 0; r < n; ++r) {
    if (r == layout_.rank()) continue;
    MessageReader reader(in[static_cast<std::size_t>(r)]);
    unpack(r, reader);
    if (!reader.done()) throw std::logic_error(fmt::format("rank {} sent more {} than expected", r, what));
  }
}

void Engine::exchange_halo() {
  const std::vector<int>& leaves = space_.leaves();
  const std::size_t ncells = space_.cells().size();
  wake_radiated_.assign(ncells, 0.0);
  if (config_.hydro.timestep_limiter) {
    // Any rank may ask to wake a particle of a leaf it reads. The requests are combined, the
    // woken particles join those whose state is sent, and each owner wakes its leaves now,
    // with the state as its tasks left it, as one rank does after the graph.
    combine_wake_requests();
    for_each_drifted_gas([&](std::size_t i) {
      if (gas_.wake_bin[i] != kNoBin) gas_moved_[i] = 1;
    });
    for (int c : leaves) {
      if (!mine(c) || !drifted_[static_cast<std::size_t>(c)]) continue;  // no requests elsewhere
      // One rank adds what the kicks radiated before waking, and what the wake gave back
      // after it: kept apart so that the sums round alike.
      Cell& cell = space_.cell(c);
      const double kicks = cell.radiated;
      cell.radiated = 0.0;
      integration::wake(*ctx_, c);
      wake_radiated_[static_cast<std::size_t>(c)] = cell.radiated;
      cell.radiated = kicks;
    }
    for_each_drifted_gas([&](std::size_t i) { gas_.wake_bin[i] = kNoBin; });
  }
  // Each drifted leaf's record goes to every rank (all take the same decisions from them);
  // its changed particles only to the ranks that hold a copy.
  exchange_with_ranks(
      [&](int q, MessageWriter& w) {
        for (int c : leaves) {
          const auto uc = static_cast<std::size_t>(c);
          if (!drifted_[uc] || !mine(c)) continue;
          w.put(CellUpdate::of(space_.cell(c)));
          w.put(wake_radiated_[uc]);
          if (!layout_.holds(q, c)) continue;
          // send_to_ is planned only for graphs that exchange ghost results.
          const bool ghost_sent =
              ghost_exchange_ && std::binary_search(send_to_[uc].begin(), send_to_[uc].end(), q);
          pack_moved_gas(w, space_, gas_, c, gas_moved_, ghost_sent);
        }
      },
      [&](int r, MessageReader& reader) {
        for (int c : leaves) {
          const auto uc = static_cast<std::size_t>(c);
          if (!drifted_[uc] || layout_.owner(uc) != r) continue;
          reader.get<CellUpdate>().apply_to(space_.cell(c));
          wake_radiated_[uc] = reader.get<double>();
          if (layout_.keeps_current(uc)) unpack_moved_gas(reader, space_, gas_, c, gas_moved_, ghost_exchange_ && need_recv_[uc]);
        }
      },
      "cell state");
}

}  // namespace fountain
