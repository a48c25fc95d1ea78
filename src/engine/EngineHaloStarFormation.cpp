// Star formation without feedback sites in halo mode: tallies summed as one rank sums them, and spawning and dissolving in rounds of events across ranks (docs/design.md, "Halo mode").
#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <utility>
#include <vector>

#include "domain/RankExchange.hpp"
#include "engine/CellMessages.hpp"
#include "engine/Engine.hpp"
#include "space/NeighbourSearch.hpp"
#include "star_formation/StarFormationLoop.hpp"

namespace fountain {

namespace {

// The held leaves in the run's order: where each starts in the run and in this rank's arrays
// (both grow along it), to turn a place into an index here and back.
class HeldPlaces {
 public:
  struct Run {
    std::uint64_t place;
    std::size_t local, count;
    int leaf;
  };
  explicit HeldPlaces(std::vector<Run> runs) : runs_(std::move(runs)) {}

  // The run holding `place`, or nullptr if no held leaf does.
  const Run* of_place(std::uint64_t place) const {
    auto it = std::upper_bound(runs_.begin(), runs_.end(), place, [](std::uint64_t p, const Run& r) { return p < r.place; });
    if (it == runs_.begin()) return nullptr;
    --it;
    return place < it->place + it->count ? &*it : nullptr;
  }
  const Run& of_local(std::size_t i) const {
    auto it = std::upper_bound(runs_.begin(), runs_.end(), i, [](std::size_t j, const Run& r) { return j < r.local; });
    if (it == runs_.begin() || i >= std::prev(it)->local + std::prev(it)->count)
      throw std::logic_error(fmt::format("gas particle {} is in no leaf held here", i));
    return *std::prev(it);
  }
  std::uint64_t place(std::size_t i) const {
    const Run& r = of_local(i);
    return r.place + (i - r.local);
  }

 private:
  std::vector<Run> runs_;
};

// A particle due to spawn or dissolve, by place, and the rank that owns it.
struct Event {
  std::uint64_t place;
  int owner;
  bool operator<(const Event& o) const { return place < o.place; }
};

}  // namespace

void Engine::gather_leaf_tallies() {
  // Each owner's leaves that formed stars; every rank then sums all leaves in one order.
  struct LeafTally {
    std::int64_t leaf;  // as wide as the tally's fields: no padding travels
    star_formation::StarFormationTally tally;
  };
  std::vector<LeafTally> mine_formed;
  for (int c : space_.leaves()) {
    const auto& t = fb_->cells[static_cast<std::size_t>(c)].tally;
    if (mine(c) && t != star_formation::StarFormationTally{}) mine_formed.push_back({c, t});
  }
  const auto all = ranks_->allgather_lists(std::span<const LeafTally>(mine_formed), "star formation tallies");
  for (std::size_t q = 0; q < all.size(); ++q)
    for (const LeafTally& t : all[q]) {
      const auto c = static_cast<int>(t.leaf);
      if (layout_.owner(c) != static_cast<int>(q))
        throw std::logic_error(fmt::format("rank {} sent the tally of leaf {}, owned by rank {}", q, c, layout_.owner(c)));
      fb_->cells[static_cast<std::size_t>(c)].tally = t.tally;
    }
}

bool Engine::spawn_and_dissolve_across_ranks() {
  const StarFormationParams& p = sf_->params;
  const int me = layout_.rank();
  std::vector<HeldPlaces::Run> runs;
  for (int c : leaves_in_run_order())
    if (keeps_current(c)) {
      const Cell& cell = space_.cell(c);
      runs.push_back({run_first_[static_cast<std::size_t>(c)], cell.first, cell.count, c});
    }
  const HeldPlaces held(std::move(runs));

  // Every rank's own particles due to spawn or dissolve now, in the run's order. A dissolve
  // only adds to its neighbours, so later events can only be spawns it brings about, or
  // dissolves it calls off (rechecked when their turn comes).
  std::vector<std::uint64_t> due;
  for (int c : space_.leaves()) {
    if (!mine(c)) continue;
    const Cell& cell = space_.cell(c);
    for (std::size_t k = 0; k < cell.count; ++k) {
      const std::size_t i = cell.first + k;
      if (star_formation::due_to_spawn(gas_, p, i) || star_formation::due_to_dissolve(gas_, p, i))
        due.push_back(run_first_[static_cast<std::size_t>(c)] + k);
    }
  }
  std::vector<Event> events;
  {
    const auto all = ranks_->allgather_lists(std::span<const std::uint64_t>(due), "particles due to spawn or dissolve");
    for (std::size_t q = 0; q < all.size(); ++q)
      for (std::uint64_t place : all[q]) events.push_back({place, static_cast<int>(q)});
  }
  if (events.empty()) return false;
  std::sort(events.begin(), events.end());
  ++event_rounds_.steps;

  const long long before = sf_->step_tally.stars_spawned + sf_->step_tally.gas_dissolved;
  const std::uint64_t first_id = next_id_;
  // Rounds: the owner of the next event handles its events in the run's order, as one rank's
  // loop does, until the next belongs to another rank; then every rank takes what it changed.
  while (!events.empty()) {
    const int turn = events.front().owner;
    std::vector<char> message;
    ++event_rounds_.turns;
    if (turn == me) {
      std::vector<std::size_t> touched;
      std::uint64_t foreign = 0;  // receivers in other ranks' leaves
      std::size_t pos = 0;
      for (; pos < events.size() && events[pos].owner == me; ++pos) {
        const std::uint64_t place = events[pos].place;
        const HeldPlaces::Run* run = held.of_place(place);
        if (!run || !mine(run->leaf)) throw std::logic_error(fmt::format("particle {} is not owned here", place));
        const std::size_t i = run->local + (place - run->place);
        if (star_formation::due_to_spawn(gas_, p, i)) {
          const std::uint64_t id = next_id_++;
          star_formation::spawn(*ctx_, *sf_, i, id);
          // Its place among the collisionless particles: after every one there was, in the
          // order of the spawning (as one rank appends it).
          spawned_places_.push_back(dm_total_ + (id - first_id));
          touched.push_back(i);
        }
        if (!star_formation::due_to_dissolve(gas_, p, i)) continue;
        // Its neighbours within h lie in leaves this rank holds, as its density loop's do.
        for (int c : space_.leaves()) {
          const Cell& cell = space_.cell(c);
          if (cell.count > 0 && !keeps_current(c) && reach_distance(space_, gas_.x[i], cell) < gas_.h[i])
            throw std::logic_error(fmt::format("particle {} dissolves into leaf {}, which this rank does not hold", place, c));
        }
        std::vector<std::size_t> receivers;
        if (!star_formation::dissolve(*ctx_, *sf_, i, [&](std::size_t j) { receivers.push_back(j); })) continue;
        touched.push_back(i);
        for (std::size_t j : receivers) {
          touched.push_back(j);
          if (!mine(held.of_local(j).leaf)) ++foreign;
          // A neighbour later in the run's order whose hidden stars now reach the threshold
          // spawns in this pass, as one rank's loop reaches it.
          const std::uint64_t pj = held.place(j);
          if (pj <= place || !star_formation::due_to_spawn(gas_, p, j)) continue;
          const Event e{pj, layout_.owner(held.of_local(j).leaf)};
          const auto at = std::lower_bound(events.begin() + static_cast<std::ptrdiff_t>(pos) + 1, events.end(), e);
          if (at == events.end() || at->place != pj) events.insert(at, e);
        }
      }
      std::sort(touched.begin(), touched.end());
      touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
      MessageWriter w(message);
      w.put(static_cast<std::uint64_t>(pos));
      w.put(foreign);
      w.put(next_id_);
      w.put(sf_->step_tally);
      w.put(static_cast<std::uint64_t>(events.size() - pos));
      for (std::size_t k = pos; k < events.size(); ++k) {
        w.put(events[k].place);
        w.put(events[k].owner);
      }
      w.put(static_cast<std::uint64_t>(touched.size()));
      for (std::size_t i : touched) {
        w.put(held.place(i));
        pack_event_fields(w, gas_, std::span<const std::size_t>(&i, 1));
      }
    }
    const auto all = ranks_->allgather(message);
    MessageReader r(all[static_cast<std::size_t>(turn)]);
    if (r.done()) throw std::logic_error(fmt::format("rank {} sent nothing in its turn at spawning and dissolving", turn));
    event_rounds_.events += static_cast<long long>(r.get<std::uint64_t>());
    event_rounds_.foreign_receivers += static_cast<long long>(r.get<std::uint64_t>());
    const auto next_id = r.get<std::uint64_t>();
    const auto tally = r.get<star_formation::StarFormationTally>();
    std::vector<Event> left(static_cast<std::size_t>(r.get<std::uint64_t>()));
    for (Event& e : left) {
      e.place = r.get<std::uint64_t>();
      e.owner = r.get<int>();
    }
    const auto n = static_cast<std::size_t>(r.get<std::uint64_t>());
    GasParticles elsewhere;  // what this rank holds no copy of
    elsewhere.resize(1);
    const std::size_t zero = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const auto place = r.get<std::uint64_t>();
      const HeldPlaces::Run* run = turn == me ? nullptr : held.of_place(place);
      if (run) {
        const std::size_t i = run->local + (place - run->place);
        unpack_event_fields(r, gas_, std::span<const std::size_t>(&i, 1));
      } else {
        unpack_event_fields(r, elsewhere, std::span<const std::size_t>(&zero, 1));
      }
    }
    if (!r.done()) throw std::logic_error(fmt::format("rank {} sent more than its turn at spawning and dissolving", turn));
    next_id_ = next_id;
    sf_->step_tally = tally;
    events = std::move(left);
    if (!events.empty() && events.front().owner == turn)
      throw std::logic_error(fmt::format("rank {} left its own event at place {}", turn, events.front().place));
  }
  return sf_->step_tally.stars_spawned + sf_->step_tally.gas_dissolved != before;
}

}  // namespace fountain
