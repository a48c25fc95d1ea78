// The layout of a run across MPI ranks: which rank owns each leaf, which ranks keep each leaf current, and where the cut along the leaves' Hilbert curve lies.
#pragma once
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "core/Vec3.hpp"
#include "space/Space.hpp"

namespace fountain::domain {

// Every rank holds the same layout (each decides it from the same inputs), so senders and
// receivers agree on every message without asking each other. Alone, one rank owns and keeps
// everything.
class RankLayout {
 public:
  RankLayout() = default;
  // halo_mode: each rank keeps current only its own leaves and their neighbours.
  RankLayout(int rank, int ranks, bool halo_mode, double repartition_imbalance, long long repartition_min_steps)
      : rank_(rank), ranks_(ranks), halo_mode_(halo_mode), imbalance_(repartition_imbalance),
        min_steps_(repartition_min_steps) {}

  int rank() const { return rank_; }
  int ranks() const { return ranks_; }
  bool halo_mode() const { return halo_mode_; }
  int owner(int c) const { return owner_.empty() ? rank_ : owner_[static_cast<std::size_t>(c)]; }
  bool mine(int c) const { return owner_.empty() || owner_[static_cast<std::size_t>(c)] == rank_; }
  const std::vector<int>& owners() const { return owner_; }
  // Whether this rank keeps leaf c current (in halo mode not every leaf; else all).
  bool keeps_current(int c) const { return !halo_mode_ || held_[static_cast<std::size_t>(c)]; }
  // In halo mode: whether rank r keeps leaf c current; the ranks that do, sorted.
  bool holds(int r, int c) const;
  const std::vector<std::vector<int>>& holders() const { return holders_; }

  // Owners for the leaves of a fresh recut. The cut along the curve stays while it still
  // shares the work well (judged once it has stood repartition_min_steps); else it is made
  // anew from the work measured since it was made (located by leaf centres: `measured`, from
  // every rank), or from particle counts when nothing was measured yet. `steps`: the run's.
  void assign_owners(const Space& space, const std::vector<std::pair<Vec3, double>>& measured, long long steps);
  // The same cut made per top-level cell, before the cells below them exist (halo mode's
  // recut, where each top cell is built by its owner): `counts`, every top cell's particles
  // on all ranks, is the work where nothing was measured. Returns the owner of each top cell;
  // set_owners_from_tops then gives every cell its top cell's owner, once the cells stand.
  std::vector<int> assign_top_owners(const Space& space, const std::vector<double>& counts,
                                     const std::vector<std::pair<Vec3, double>>& measured, long long steps);
  void set_owners_from_tops(const Space& space);
  int top_owner(int t) const { return top_owner_[static_cast<std::size_t>(t)]; }
  // Halo mode, after assign_owners: the ranks that read each leaf (its neighbours' owners).
  void find_holders(const Space& space);

  // Task time measured in this rank's leaves since owners were last chosen (ns per cell).
  // (Sized to the cells on first use after a recut, zero: costs() is empty before any was taken.)
  std::vector<double>& costs_of(std::size_t ncells) {
    if (cost_.size() != ncells) cost_.assign(ncells, 0.0);
    return cost_;
  }
  const std::vector<double>& costs() const { return cost_; }

  // How often the cut was made.
  int partitions() const { return partitions_; }
  // In halo mode, the share of the leaves this rank kept current, averaged over the recuts.
  double held_share() const {
    return leaves_seen_ > 0 ? static_cast<double>(leaves_held_) / static_cast<double>(leaves_seen_) : 1.0;
  }

 private:
  // The owner of each unit (leaf or top cell, centred at `centres`) from the cut along the
  // curve: kept while it shares the work well, else made anew.
  std::vector<int> cut_along_curve(const Space& space, const std::vector<Vec3>& centres, const std::vector<double>& counts,
                                   const std::vector<std::pair<Vec3, double>>& measured, long long steps,
                                   const std::function<std::size_t(const Vec3&)>& unit_at);

  int rank_ = 0, ranks_ = 1;
  bool halo_mode_ = false;
  double imbalance_ = 0.1;
  long long min_steps_ = 100;
  std::vector<int> owner_;                  // per cell; empty when running alone
  std::vector<int> top_owner_;              // per top-level cell, where owners are chosen per top cell
  std::vector<double> cost_;                // measured task time per cell since owners were chosen (ns)
  std::vector<std::uint64_t> cut_keys_;     // where ranks 1.. begin along the leaves' Hilbert curve
  std::vector<std::pair<Vec3, double>> work_since_cut_;  // (leaf centre, task ns) measured since the cut, before this interval
  long long cut_step_ = 0;                  // the step count when the cut was made
  int partitions_ = 0;
  std::vector<std::vector<int>> holders_;   // per leaf: the ranks keeping it current (sorted)
  std::vector<char> held_;                  // per cell: this rank keeps it current
  long long leaves_held_ = 0, leaves_seen_ = 0;  // summed over the recuts
};

}  // namespace fountain::domain
