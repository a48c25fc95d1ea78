// Halo mode across MPI ranks: each rank keeps current only its own leaves and their neighbours (docs/design.md, "Halo mode").
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

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
  exchange_leaves_in_rounds(
      leaves, [&](int c) { return drifted_[static_cast<std::size_t>(c)] != 0; },
      [&](int q, int c, MessageWriter& w) {
        const auto uc = static_cast<std::size_t>(c);
        w.put(CellUpdate::of(space_.cell(c)));
        w.put(wake_radiated_[uc]);
        if (!layout_.holds(q, c)) return;
        // send_to_ is planned only for graphs that exchange ghost results.
        const bool ghost_sent = ghost_exchange_ && std::binary_search(send_to_[uc].begin(), send_to_[uc].end(), q);
        pack_moved_gas(w, space_, gas_, c, gas_moved_, ghost_sent, config_.gravity.enabled, ctx_->long_range != nullptr,
                       sf_ != nullptr);
      },
      [&](int, int c, MessageReader& reader) {
        const auto uc = static_cast<std::size_t>(c);
        reader.get<CellUpdate>().apply_to(space_.cell(c));
        wake_radiated_[uc] = reader.get<double>();
        if (layout_.keeps_current(uc))
          unpack_moved_gas(reader, space_, gas_, c, gas_moved_, ghost_exchange_ && need_recv_[uc], config_.gravity.enabled,
                           ctx_->long_range != nullptr, sf_ != nullptr);
      },
      "cell state");
}

void Engine::exchange_leaves_in_rounds(const std::vector<int>& leaves, const std::function<bool(int)>& travels,
                                       const std::function<void(int, int, MessageWriter&)>& pack,
                                       const std::function<void(int, int, MessageReader&)>& unpack, const char* what) {
  const auto n = static_cast<std::size_t>(ranks_->size());
  const auto me = static_cast<std::size_t>(layout_.rank());
  // Per rank: where in `leaves` the next round resumes, sending to it and reading from it.
  std::vector<std::size_t> sent(n, 0), read(n, 0);
  for (;;) {
    to_ranks_.clear();
    to_rank_sizes_.assign(n, 0);
    MessageWriter w(to_ranks_);
    bool left = false;
    for (std::size_t q = 0; q < n; ++q) {
      if (q == me) continue;
      const std::size_t before = to_ranks_.size();
      std::size_t& k = sent[q];
      for (; k < leaves.size(); ++k) {
        const int c = leaves[k];
        if (!travels(c) || !mine(c)) continue;
        // Whole leaves, at least one a round: a round ends past domain.message_bytes, never
        // inside a leaf, so the buffers kept from step to step stay about that size.
        if (to_ranks_.size() - before >= config_.message_bytes) break;
        pack(static_cast<int>(q), c, w);
      }
      left = left || k < leaves.size();
      to_rank_sizes_[q] = to_ranks_.size() - before;
    }
    const auto in = ranks_->alltoall(to_ranks_, to_rank_sizes_);
    for (std::size_t r = 0; r < n; ++r) {
      if (r == me) continue;
      MessageReader reader(in[r]);
      std::size_t& k = read[r];
      for (; k < leaves.size() && !reader.done(); ++k) {
        const int c = leaves[k];
        if (!travels(c) || layout_.owner(c) != static_cast<int>(r)) continue;
        unpack(static_cast<int>(r), c, reader);
      }
      if (!reader.done()) throw std::logic_error(fmt::format("rank {} sent more {} than expected", r, what));
    }
    if (!ranks_->any(left)) break;
  }
  for (std::size_t r = 0; r < n; ++r)
    for (std::size_t k = read[r]; k < leaves.size(); ++k)
      if (r != me && travels(leaves[k]) && layout_.owner(leaves[k]) == static_cast<int>(r))
        throw std::logic_error(fmt::format("rank {} sent no {} of leaf {}", r, what, leaves[k]));
}

}  // namespace fountain
