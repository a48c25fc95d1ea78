// Halo mode's recut across ranks: each rank holds only the leaves it keeps current, and each top cell is built by its owner (docs/design.md, "Halo mode").
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "core/PeriodicWrap.hpp"
#include "domain/BoundsAcrossRanks.hpp"
#include "domain/RankExchange.hpp"
#include "engine/CellMessages.hpp"
#include "engine/Engine.hpp"

namespace fountain {

namespace {

// Where a cell's particles start in the arrays of a rank that does not hold it: far past any
// array, so that a read of them fails at once rather than reading another leaf's.
constexpr std::size_t kNotHeld = std::numeric_limits<std::size_t>::max() / 4;

// Bytes a particle takes in a recut's message: its fields, and at most this much beside them.
constexpr std::size_t kParticleHeaderBytes = 16;

// Each of `places` with its index, sorted by place. What a rank has at a recut comes as a few
// runs already in order (its held leaves' particles, then each sender's arrivals in the
// sender's order), so neighbouring runs are merged rather than the whole sorted anew.
std::vector<std::pair<std::uint64_t, std::size_t>> sorted_by_place(const std::vector<std::uint64_t>& places) {
  std::vector<std::pair<std::uint64_t, std::size_t>> out(places.size());
  std::vector<std::size_t> runs{0};
  for (std::size_t i = 0; i < places.size(); ++i) {
    out[i] = {places[i], i};
    if (i > 0 && places[i] < places[i - 1]) runs.push_back(i);
  }
  runs.push_back(places.size());
  while (runs.size() > 2) {
    const std::size_t m = runs.size() - 1;  // runs now, each [runs[k], runs[k + 1])
    std::vector<std::size_t> merged{0};
    for (std::size_t k = 0; k + 1 < m; k += 2) {
      std::inplace_merge(out.begin() + static_cast<std::ptrdiff_t>(runs[k]), out.begin() + static_cast<std::ptrdiff_t>(runs[k + 1]),
                         out.begin() + static_cast<std::ptrdiff_t>(runs[k + 2]));
      merged.push_back(runs[k + 2]);
    }
    if (m % 2 == 1) merged.push_back(runs[m]);
    runs = std::move(merged);
  }
  return out;
}

// A particle this rank takes at a recut: its top cell, its place in the run's order before
// the recut, and where it is in this rank's arrays.
struct RecutEntry {
  int top;
  std::uint64_t place;
  std::size_t at;
};

// Orders `entries` by top cell and, within one, by place. Counted out by top cell, then
// sorted within each: a top cell's entries are a few runs already in order (this rank's,
// then each sender's), and short.
void order_by_top_and_place(std::vector<RecutEntry>& entries, std::size_t ntop) {
  std::vector<std::size_t> bucket(ntop + 1, 0);
  for (const RecutEntry& e : entries) ++bucket[static_cast<std::size_t>(e.top) + 1];
  std::partial_sum(bucket.begin(), bucket.end(), bucket.begin());
  std::vector<RecutEntry> by_top(entries.size());
  std::vector<std::size_t> next(bucket.begin(), bucket.end() - 1);
  for (const RecutEntry& e : entries) by_top[next[static_cast<std::size_t>(e.top)]++] = e;
  for (std::size_t t = 0; t < ntop; ++t)
    std::sort(by_top.begin() + static_cast<std::ptrdiff_t>(bucket[t]), by_top.begin() + static_cast<std::ptrdiff_t>(bucket[t + 1]),
              [](const RecutEntry& a, const RecutEntry& b) { return a.place < b.place; });
  entries = std::move(by_top);
}

// Where each of `tops` (this rank's top cells, in order) starts in `entries` (ordered by top
// cell), checked against the count each should have.
template <class Count>
std::vector<std::size_t> top_cell_starts(const std::vector<RecutEntry>& entries, const std::vector<int>& tops,
                                         std::size_t ntop, Count&& count) {
  std::vector<std::size_t> begin(ntop, 0);
  std::size_t j = 0;
  for (int t : tops) {
    begin[static_cast<std::size_t>(t)] = j;
    while (j < entries.size() && entries[j].top == t) ++j;
    if (j - begin[static_cast<std::size_t>(t)] != count(t))
      throw std::logic_error(
          fmt::format("top cell {}: {} particles arrived of {}", t, j - begin[static_cast<std::size_t>(t)], count(t)));
  }
  if (j != entries.size()) throw std::logic_error("particles arrived for a top cell this rank does not own");
  return begin;
}

// The places in the run's order of the particles at `local` in arrays that hold the leaves
// `kept` picks end to end in the run's order (`leaves`): leaf c starts at first_here(c) there
// and at run_first[c] in the run.
template <class Kept, class FirstHere>
std::vector<std::size_t> places_in_run(const std::vector<std::size_t>& local, const std::vector<int>& leaves, Kept&& kept,
                                       FirstHere&& first_here, const std::vector<std::size_t>& run_first,
                                       const char* no_leaf) {
  std::vector<std::pair<std::size_t, int>> starts;
  for (int c : leaves)
    if (kept(c)) starts.emplace_back(first_here(c), c);
  std::vector<std::size_t> out(local.size());
  for (std::size_t k = 0; k < local.size(); ++k) {
    auto it = std::upper_bound(starts.begin(), starts.end(), std::pair{local[k], std::numeric_limits<int>::max()});
    if (it == starts.begin()) throw std::logic_error(fmt::format(fmt::runtime(no_leaf), local[k]));
    --it;
    out[k] = run_first[static_cast<std::size_t>(it->second)] + (local[k] - it->first);
  }
  return out;
}

}  // namespace

void Engine::recut_across_ranks(const std::vector<std::pair<Vec3, double>>& measured, const ForEach& for_each) {
  const int me = layout_.rank();
  const auto nranks = static_cast<std::size_t>(ranks_->size());
  HaloRecut& r = halo_recut_;
  // Every particle this rank holds (all current) with its place in the run's order, and which
  // it owns. At the first recut of a run each rank holds the share of the file it read, in
  // the file's order (or the pieces of a restart set it read, with their places), and owns
  // it. At the first recut of a restart from one file every rank holds every particle, as
  // read, and takes all as its own: all then find the same box, counts and
  // owners without a word, and none need be sent. Until this rank's arrays are made anew
  // (hold_leaves) they keep every copy: the holders of a new leaf then need only be told
  // which particles it holds.
  const bool first_recut = space_.leaves().empty();
  r.everyone = first_recut && !holds_read_share_;
  r.from_shares = first_recut && holds_read_share_;
  std::vector<std::size_t> own;
  r.place.assign(gas_.size(), 0);
  r.source.clear();
  r.old_first.clear();
  r.old_holders.clear();
  if (first_recut) {
    own.resize(gas_.size());
    std::iota(own.begin(), own.end(), std::size_t{0});
    if (share_places_.empty()) {
      std::iota(r.place.begin(), r.place.end(), std::uint64_t{share_first_});
    } else {
      r.place = share_places_;
    }
    if (r.from_shares) r.source.assign(gas_.size(), me);
  } else {
    const std::vector<int> leaves = leaves_in_run_order();
    for (int c : leaves) {
      r.old_first.push_back(run_first_[static_cast<std::size_t>(c)]);
      r.old_holders.push_back(layout_.holders()[static_cast<std::size_t>(c)]);
      if (!keeps_current(c)) continue;
      const Cell& cell = space_.cell(c);
      for (std::size_t k = 0; k < cell.count; ++k) {
        r.place[cell.first + k] = run_first_[static_cast<std::size_t>(c)] + k;
        // Dissolved gas (mass 0) goes, as one rank's recut drops it: the places of those that
        // stay keep their order, so they stand for the new ones.
        if (mine(c) && gas_.mass[cell.first + k] > 0.0) own.push_back(cell.first + k);
      }
    }
  }

  // Collisionless particles have no holders (no loop reads another leaf's): every one in this
  // rank's arrays is its own, an owned leaf's in the run's order, unless every rank read every
  // one (from initial conditions, or a restart file written whole), in the run's order.
  r.dm_everyone = r.everyone || (first_recut && !dm_shared_);
  r.dm_place.resize(dm_.size());
  if (first_recut && dm_shared_) {
    r.dm_place = dm_share_places_;
  } else if (first_recut) {
    std::iota(r.dm_place.begin(), r.dm_place.end(), std::uint64_t{0});
  } else {
    for (int c : space_.leaves()) {
      if (!mine(c)) continue;
      const Cell& cell = space_.cell(c);
      for (std::size_t k = 0; k < cell.dm_count; ++k) r.dm_place[cell.dm_first + k] = run_dm_first_[static_cast<std::size_t>(c)] + k;
    }
    // Stars spawned since the last recut follow the owned leaves' particles in the arrays.
    const std::size_t spawned_at = dm_.size() - spawned_places_.size();
    std::copy(spawned_places_.begin(), spawned_places_.end(), r.dm_place.begin() + static_cast<std::ptrdiff_t>(spawned_at));
  }
  spawned_places_.clear();

  // The box (a periodic one's images inside it, for every copy alike; an open one's bounds over
  // every rank's particles, exact in any order) and the top-level grid.
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  if (space_.periodic()) {
    for (Vec3& x : gas_.x) x = wrap_into_box(x, space_.config().box_size);
    for (Vec3& x : dm_.x) x = wrap_into_box(x, space_.config().box_size);
  } else {
    auto widen = [&](const Vec3& x) {
      for (int k = 0; k < 3; ++k) {
        lo[k] = std::min(lo[k], x[k]);
        hi[k] = std::max(hi[k], x[k]);
      }
    };
    for (std::size_t i : own) widen(gas_.x[i]);
    for (const Vec3& x : dm_.x) widen(x);
    if (!r.everyone) domain::widen_to_every_rank(*ranks_, lo, hi, "box bounds");
  }
  gas_total_ = r.everyone ? own.size() : static_cast<std::size_t>(ranks_->sum(static_cast<long long>(own.size())));
  dm_total_ = r.dm_everyone ? dm_.size() : static_cast<std::size_t>(ranks_->sum(static_cast<long long>(dm_.size())));
  space_.set_frame(lo, hi, gas_total_, dm_total_);
  const std::size_t ntop = space_.cells().size();

  // Each particle's top cell, the particles per top cell on every rank (gas, then
  // collisionless), and the top cells' owners, chosen by both counts.
  std::vector<int> top(own.size()), dm_top(dm_.size());
  std::vector<double> here(2 * ntop, 0.0);
  for (std::size_t k = 0; k < own.size(); ++k) {
    top[k] = space_.top_cell_at(gas_.x[own[k]]);
    here[static_cast<std::size_t>(top[k])] += 1.0;
  }
  for (std::size_t i = 0; i < dm_.size(); ++i) {
    dm_top[i] = space_.top_cell_at(dm_.x[i]);
    here[ntop + static_cast<std::size_t>(dm_top[i])] += 1.0;
  }
  std::vector<double> counts = here;
  if (!r.everyone) {
    const auto all = ranks_->allgather_values(std::span<const double>(here), "particles per top cell");
    for (std::size_t t = 0; t < 2 * ntop; ++t) {
      if (t >= ntop && r.dm_everyone) break;
      counts[t] = 0.0;
      for (const auto& theirs : all) counts[t] += theirs[t];
    }
  }
  std::vector<double> work(ntop);
  for (std::size_t t = 0; t < ntop; ++t) work[t] = counts[t] + counts[ntop + t];
  const std::vector<int> top_owner = layout_.assign_top_owners(space_, work, measured, steps_);
  std::size_t start = 0, dm_start = 0;
  for (std::size_t t = 0; t < ntop; ++t) {
    Cell& cell = space_.cell(static_cast<int>(t));
    cell.first = start;
    cell.count = static_cast<std::size_t>(counts[t]);
    start += cell.count;
    cell.dm_first = dm_start;
    cell.dm_count = static_cast<std::size_t>(counts[ntop + t]);
    dm_start += cell.dm_count;
  }

  // Each particle goes to its top cell's owner, with its place and top cell (at the first
  // recut each rank keeps its top cells' and leaves the rest).
  std::vector<RecutEntry> entries, dm_entries;
  std::vector<std::vector<std::size_t>> to(nranks), dm_to(nranks);
  for (std::size_t k = 0; k < own.size(); ++k) {
    const auto q = static_cast<std::size_t>(top_owner[static_cast<std::size_t>(top[k])]);
    if (q == static_cast<std::size_t>(me)) {
      entries.push_back({top[k], r.place[own[k]], own[k]});
    } else if (!r.everyone) {
      to[q].push_back(own[k]);
    }
  }
  for (std::size_t i = 0; i < dm_.size(); ++i) {
    const auto q = static_cast<std::size_t>(top_owner[static_cast<std::size_t>(dm_top[i])]);
    if (q == static_cast<std::size_t>(me)) {
      dm_entries.push_back({dm_top[i], r.dm_place[i], i});
    } else if (!r.dm_everyone) {
      dm_to[q].push_back(i);
    }
  }
  send_in_rounds(
      gas_, to,
      [&](std::size_t i, MessageWriter& w) {
        w.put(r.place[i]);
        w.put(space_.top_cell_at(gas_.x[i]));
      },
      [&](int q, std::size_t at, std::size_t n, MessageReader& reader) {
        for (std::size_t j = 0; j < n; ++j) {
          const auto p = reader.get<std::uint64_t>();
          entries.push_back({reader.get<int>(), p, at + j});
          r.place.push_back(p);
          if (r.from_shares) r.source.push_back(q);
        }
      });
  if (!r.dm_everyone)
    send_in_rounds(
        dm_, dm_to,
        [&](std::size_t i, MessageWriter& w) {
          w.put(r.dm_place[i]);
          w.put(dm_top[i]);
        },
        [&](int, std::size_t at, std::size_t n, MessageReader& reader) {
          for (std::size_t j = 0; j < n; ++j) {
            const auto p = reader.get<std::uint64_t>();
            dm_entries.push_back({reader.get<int>(), p, at + j});
          }
        });
  // This rank's top cells' particles ordered by top cell and, within one, by place: the order
  // they had, in which one rank's recut takes them.
  order_by_top_and_place(entries, ntop);
  order_by_top_and_place(dm_entries, ntop);
  std::vector<std::size_t>& order = r.owned;
  order.resize(entries.size());
  std::vector<std::size_t> scratch(entries.size());
  for (std::size_t j = 0; j < entries.size(); ++j) order[j] = entries[j].at;
  std::vector<std::size_t>& dm_order = r.dm_owned;
  dm_order.resize(dm_entries.size());
  std::vector<std::size_t> dm_scratch(dm_entries.size());
  for (std::size_t j = 0; j < dm_entries.size(); ++j) dm_order[j] = dm_entries[j].at;

  // The octrees of this rank's top cells, each from its own particles (in `order` and
  // `dm_order`, which come back in the recut's order), and each leaf's record (h_max, v_max,
  // step end).
  std::vector<int> mine_tops;
  for (std::size_t t = 0; t < ntop; ++t)
    if (top_owner[t] == me) mine_tops.push_back(static_cast<int>(t));
  // Where each of this rank's top cells starts in `order` and in `dm_order`.
  const std::vector<std::size_t> begin = top_cell_starts(entries, mine_tops, ntop, [&](int t) { return space_.cell(t).count; });
  const std::vector<std::size_t> dm_begin =
      top_cell_starts(dm_entries, mine_tops, ntop, [&](int t) { return space_.cell(t).dm_count; });
  std::vector<std::vector<Cell>> subtrees(ntop);
  for_each(mine_tops.size(), [&](std::size_t m) {
    const auto t = static_cast<std::size_t>(mine_tops[m]);
    const Cell& cell = space_.cell(mine_tops[m]);
    subtrees[t] = space_.build_subtree(cell, gas_.x, std::span<std::size_t>(order).subspan(begin[t], cell.count),
                                       std::span<std::size_t>(scratch).subspan(begin[t], cell.count), dm_.x,
                                       std::span<std::size_t>(dm_order).subspan(dm_begin[t], cell.dm_count),
                                       std::span<std::size_t>(dm_scratch).subspan(dm_begin[t], cell.dm_count));
  });
  for (int t : mine_tops) {
    const std::size_t b = begin[static_cast<std::size_t>(t)], dm_b = dm_begin[static_cast<std::size_t>(t)];
    for (Cell& cell : subtrees[static_cast<std::size_t>(t)]) {
      if (!cell.leaf) continue;
      IntegerTime end = TimeLine::ticks;
      for (std::size_t j = b + cell.first; j < b + cell.first + cell.count; ++j) {
        const std::size_t i = order[j];
        cell.h_max = std::max(cell.h_max, gas_.h[i]);
        cell.v_max = std::max(cell.v_max, norm(gas_.v_full[i]));
        end = std::min(end, due_end(gas_.time_bin[i], gas_.ti_begin[i]));
      }
      for (std::size_t j = dm_b + cell.dm_first; j < dm_b + cell.dm_first + cell.dm_count; ++j) {
        const std::size_t i = dm_order[j];
        end = std::min(end, due_end(dm_.time_bin[i], dm_.ti_begin[i]));
      }
      cell.ti_end_min = end;
    }
  }

  // Every rank's subtrees to every rank: all make the same cells.
  std::vector<char> buffer;
  MessageWriter w(buffer);
  for (int t : mine_tops) {
    const auto& sub = subtrees[static_cast<std::size_t>(t)];
    w.put(t);
    w.put(static_cast<std::uint64_t>(sub.size()));
    w.put(sub.data(), sub.size());
  }
  const auto all = ranks_->allgather(buffer);
  for (std::size_t q = 0; q < nranks; ++q) {
    if (static_cast<int>(q) == me) continue;
    MessageReader reader(all[q]);
    while (!reader.done()) {
      const int t = reader.get<int>();
      auto& sub = subtrees[static_cast<std::size_t>(t)];
      sub.resize(static_cast<std::size_t>(reader.get<std::uint64_t>()));
      reader.get(sub.data(), sub.size());
    }
  }
  for (std::size_t t = 0; t < ntop; ++t)
    if (subtrees[t].empty()) throw std::logic_error(fmt::format("no rank built top cell {}", t));
  space_.assemble(subtrees);
  space_.set_covers();
  for (int c : space_.leaves()) space_.cell(c).ti_drift = ti_current_;
  run_first_.resize(space_.cells().size());
  run_dm_first_.resize(space_.cells().size());
  for (std::size_t c = 0; c < run_first_.size(); ++c) {
    run_first_[c] = space_.cell(static_cast<int>(c)).first;
    run_dm_first_[c] = space_.cell(static_cast<int>(c)).dm_first;
  }
  layout_.set_owners_from_tops(space_);
}

void Engine::hold_leaves() {
  const HaloRecut& r = halo_recut_;
  // The leaves in the run's order; where each of this rank's own leaves starts in r.owned.
  const std::vector<int> leaves = leaves_in_run_order();
  // Where each leaf that `picked` takes starts when they are laid end to end in the run's
  // order (kNotHeld for the others), and how many particles they hold.
  auto laid_end_to_end = [&](auto picked, auto count) {
    std::vector<std::size_t> first(space_.cells().size(), kNotHeld);
    std::size_t n = 0;
    for (int c : leaves)
      if (picked(c)) {
        first[static_cast<std::size_t>(c)] = n;
        n += count(space_.cell(c));
      }
    return std::pair{std::move(first), n};
  };
  const auto gas_count = [](const Cell& cell) { return cell.count; };
  const auto [in_owned, n_owned] = laid_end_to_end([&](int c) { return mine(c); }, gas_count);
  if (n_owned != r.owned.size())
    throw std::logic_error(fmt::format("{} particles owned, {} in the leaves", r.owned.size(), n_owned));
  // This rank's arrays are to hold the leaves it keeps current, in the run's order.
  const auto [local_first, held] = laid_end_to_end([&](int c) { return keeps_current(c); }, gas_count);
  std::vector<std::size_t> order(held, kNotHeld);  // for each new place here: the particle now in gas_
  for (int c : leaves)
    if (mine(c))
      std::copy_n(r.owned.begin() + static_cast<std::ptrdiff_t>(in_owned[static_cast<std::size_t>(c)]), space_.cell(c).count,
                  order.begin() + static_cast<std::ptrdiff_t>(local_first[static_cast<std::size_t>(c)]));
  // Whether rank q held a current copy of particle i (here) before the recut: it held that
  // particle's leaf, or read it (every rank held every particle before a restart's first recut).
  auto had_copy = [&](int q, std::size_t i) {
    if (r.everyone) return true;
    if (r.from_shares) return r.source[i] == q;
    const std::uint64_t place = r.place[i];
    const auto l = static_cast<std::size_t>(std::upper_bound(r.old_first.begin(), r.old_first.end(), place) - r.old_first.begin()) - 1;
    const auto& h = r.old_holders[l];
    return std::binary_search(h.begin(), h.end(), q);
  };
  // Where each particle this rank has (held before, read, or arrived in the recut) now lies,
  // by place (at a restart's first recut its place is its index).
  std::vector<std::pair<std::uint64_t, std::size_t>> by_place;
  if (!r.everyone) {
    by_place = sorted_by_place(r.place);
  }
  // Each owner tells the holders of its leaves which particles they hold, by place, and then
  // sends whole only those a holder had no current copy of.
  const auto nranks = static_cast<std::size_t>(ranks_->size());
  std::vector<std::vector<std::size_t>> whole(nranks);  // to each rank, in the order named
  std::vector<std::vector<std::size_t>> slots(nranks);  // from each rank: the new places they take
  exchange_with_ranks(
      [&](int q, MessageWriter& w) {
        auto& send = whole[static_cast<std::size_t>(q)];
        for (int c : leaves) {
          if (!mine(c) || !layout_.holds(q, c)) continue;
          const std::size_t from = in_owned[static_cast<std::size_t>(c)];
          for (std::size_t k = 0; k < space_.cell(c).count; ++k) {
            const std::size_t i = r.owned[from + k];
            const bool copy = had_copy(q, i);
            w.put(r.place[i]);
            w.put(static_cast<std::uint8_t>(copy));
            if (!copy) send.push_back(i);
          }
        }
      },
      [&](int q, MessageReader& reader) {
        auto& from = slots[static_cast<std::size_t>(q)];
        for (int c : leaves) {
          if (layout_.owner(c) != q || !keeps_current(c)) continue;
          const std::size_t first = local_first[static_cast<std::size_t>(c)];
          for (std::size_t k = 0; k < space_.cell(c).count; ++k) {
            const auto p = reader.get<std::uint64_t>();
            const bool copy = reader.get<std::uint8_t>() != 0;
            if (copy && r.everyone) {
              order[first + k] = static_cast<std::size_t>(p);
            } else if (copy) {
              const auto it = std::lower_bound(by_place.begin(), by_place.end(), std::pair{p, std::size_t{0}});
              if (it == by_place.end() || it->first != p)
                throw std::logic_error(fmt::format("rank {} took rank {} to hold particle {}", q, layout_.rank(), p));
              order[first + k] = it->second;
            } else {
              from.push_back(first + k);
            }
          }
        }
      },
      "the leaves' holders");
  std::vector<std::size_t> taken(nranks, 0);
  send_in_rounds(gas_, whole, [](std::size_t, MessageWriter&) {},
                     [&](int q, std::size_t at, std::size_t n, MessageReader&) {
                       const auto& from = slots[static_cast<std::size_t>(q)];
                       std::size_t& k = taken[static_cast<std::size_t>(q)];
                       if (k + n > from.size())
                         throw std::logic_error(fmt::format("rank {} sent more particles than it named", q));
                       for (std::size_t j = 0; j < n; ++j) order[from[k++]] = at + j;
                     });
  for (std::size_t q = 0; q < nranks; ++q)
    if (taken[q] != slots[q].size())
      throw std::logic_error(fmt::format("rank {} sent {} of the {} particles it named", q, taken[q], slots[q].size()));
  // The arrays: what this rank holds, in the run's order (in place, through one buffer).
  gas_.permute(order, {}, &permute_scratch_);
  // After the first recut the arrays hold less than they did: the room for the rest goes.
  if (r.everyone || r.from_shares) gas_.for_each_field([](auto& field) { field.shrink_to_fit(); });
  holds_read_share_ = false;
  std::vector<std::uint64_t>().swap(share_places_);
  for (std::size_t c = 0; c < local_first.size(); ++c) space_.cell(static_cast<int>(c)).first = local_first[c];

  // The collisionless particles: only the owner of a leaf holds them, so its arrays are its
  // own leaves' end to end in the run's order, as r.dm_owned lists them already.
  const auto [dm_local_first, dm_owned] =
      laid_end_to_end([&](int c) { return mine(c); }, [](const Cell& cell) { return cell.dm_count; });
  if (dm_owned != r.dm_owned.size())
    throw std::logic_error(fmt::format("{} collisionless particles owned, {} in the leaves", r.dm_owned.size(), dm_owned));
  dm_.permute(r.dm_owned, {}, &permute_scratch_);
  if (r.dm_everyone || dm_shared_) dm_.for_each_field([](auto& field) { field.shrink_to_fit(); });
  dm_shared_ = false;
  std::vector<std::uint64_t>().swap(dm_share_places_);
  for (std::size_t c = 0; c < dm_local_first.size(); ++c) space_.cell(static_cast<int>(c)).dm_first = dm_local_first[c];
  halo_recut_ = {};
}

template <class Store>
void Engine::send_in_rounds(Store& store, const std::vector<std::vector<std::size_t>>& to,
                            const std::function<void(std::size_t, MessageWriter&)>& header,
                            const std::function<void(int, std::size_t, std::size_t, MessageReader&)>& arrived) {
  const int me = layout_.rank();
  const auto nranks = static_cast<std::size_t>(ranks_->size());
  // Every rank's counts to every rank: each knows how many particles arrive, and all how
  // many rounds there are.
  // At most domain.message_bytes to each rank a round (every particle packs to one size).
  Store one;
  one.resize(1);
  std::vector<char> probe;
  MessageWriter probe_writer(probe);
  const std::size_t zero = 0;
  pack_particles(probe_writer, one, std::span<const std::size_t>(&zero, 1));
  const std::size_t per_rank = std::max<std::size_t>(1, config_.message_bytes / (probe.size() + kParticleHeaderBytes));
  std::vector<long long> sending(nranks, 0);
  for (std::size_t q = 0; q < nranks; ++q)
    if (static_cast<int>(q) != me) sending[q] = static_cast<long long>(to[q].size());
  const auto plan = ranks_->allgather_values(std::span<const long long>(sending), "particles to send");
  std::size_t arriving = 0, rounds = 0;
  for (std::size_t q = 0; q < nranks; ++q) {
    arriving += static_cast<std::size_t>(plan[q][static_cast<std::size_t>(me)]);
    for (long long count : plan[q]) rounds = std::max(rounds, (static_cast<std::size_t>(count) + per_rank - 1) / per_rank);
  }
  // Room for exactly these: doubling the arrays' room would set the run's peak memory.
  store.for_each_field([&](auto& field) { field.reserve(store.size() + arriving); });
  std::vector<std::size_t> slice, into;
  for (std::size_t round = 0; round < rounds; ++round) {
    to_ranks_.clear();
    to_rank_sizes_.assign(nranks, 0);
    MessageWriter w(to_ranks_);
    for (std::size_t q = 0; q < nranks; ++q) {
      if (static_cast<int>(q) == me) continue;
      const std::size_t before = to_ranks_.size();
      const std::size_t from = std::min(to[q].size(), round * per_rank);
      slice.assign(to[q].begin() + static_cast<std::ptrdiff_t>(from),
                   to[q].begin() + static_cast<std::ptrdiff_t>(std::min(to[q].size(), from + per_rank)));
      w.put(static_cast<std::uint64_t>(slice.size()));
      for (std::size_t i : slice) header(i, w);
      pack_particles(w, store, slice);
      to_rank_sizes_[q] = to_ranks_.size() - before;
    }
    const auto in = ranks_->alltoall(to_ranks_, to_rank_sizes_);
    for (std::size_t q = 0; q < nranks; ++q) {
      if (static_cast<int>(q) == me) continue;
      MessageReader reader(in[q]);
      const auto n = static_cast<std::size_t>(reader.get<std::uint64_t>());
      const std::size_t at = store.size();
      arrived(static_cast<int>(q), at, n, reader);
      store.resize(at + n);
      into.resize(n);
      std::iota(into.begin(), into.end(), at);
      unpack_particles(reader, store, into);
      if (!reader.done()) throw std::logic_error(fmt::format("rank {} sent more particles than it announced", q));
    }
  }
  // The buffers of the largest exchange (a run's first recut, where most particles move) go.
  std::vector<char>().swap(to_ranks_);
  ranks_->release_buffers();
}

std::vector<int> Engine::leaves_in_run_order() const {
  // Leaves are numbered by the depth-first walk of each top cell in turn after all the top
  // cells, so a top cell that is itself a leaf comes before split ones: sort by the run's order.
  // Where the gas and the collisionless particles start both grow along it, and no leaf is
  // empty, so the pair orders every two leaves (a leaf without gas shares its start with the
  // next).
  std::vector<int> leaves = space_.leaves();
  std::sort(leaves.begin(), leaves.end(), [&](int a, int b) {
    const auto ua = static_cast<std::size_t>(a), ub = static_cast<std::size_t>(b);
    return std::pair{run_first_[ua], run_dm_first_[ua]} < std::pair{run_first_[ub], run_dm_first_[ub]};
  });
  return leaves;
}

std::size_t Engine::gas_count() const { return layout_.halo_mode() ? gas_total_ : gas_.size(); }

std::size_t Engine::collisionless_count() const { return layout_.halo_mode() ? dm_total_ : dm_.size(); }

std::size_t Engine::collisionless_count(Species s) const {
  const std::size_t here = dm_.count(s);
  if (!layout_.halo_mode() || space_.leaves().empty()) return here;
  return static_cast<std::size_t>(ranks_->sum(static_cast<long long>(here)));
}

std::vector<std::size_t> Engine::run_collisionless_places(const std::vector<std::size_t>& local) const {
  if (!layout_.halo_mode() || space_.leaves().empty()) return local;
  // This rank's arrays hold its own leaves' collisionless particles, in the run's order.
  return places_in_run(
      local, leaves_in_run_order(), [&](int c) { return mine(c); }, [&](int c) { return space_.cell(c).dm_first; },
      run_dm_first_, "collisionless particle {} is in no leaf owned here");
}

std::vector<std::size_t> Engine::run_places(const std::vector<std::size_t>& local) const {
  if (!layout_.halo_mode() || space_.leaves().empty()) return local;
  // The held leaves lie in the arrays in the run's order.
  return places_in_run(
      local, leaves_in_run_order(), [&](int c) { return keeps_current(c); }, [&](int c) { return space_.cell(c).first; },
      run_first_, "particle {} is in no leaf held here");
}

}  // namespace fountain
