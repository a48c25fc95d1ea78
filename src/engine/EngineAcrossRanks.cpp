// The engine's work across MPI ranks: who owns which leaf, and what the ranks send each other (docs/design.md, "MPI").
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <limits>

#include "domain/DomainDecomposition.hpp"
#include "domain/RankExchange.hpp"
#include "engine/CellMessages.hpp"
#include "engine/Engine.hpp"
#include "star_formation/StarFormationLoop.hpp"

namespace fountain {

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

void Engine::poll_receives(std::span<const int> waiting, std::vector<int>& opened) {
  std::vector<int> handles, arrived;
  for (int t : waiting) handles.push_back(recv_handle_[static_cast<std::size_t>(graph_.task(t).ci)]);
  ranks_->test_recvs(handles, arrived);
  for (int k : arrived) opened.push_back(waiting[static_cast<std::size_t>(k)]);
}

std::pair<std::vector<std::size_t>, std::vector<std::size_t>> Engine::owned_particles() const {
  std::pair<std::vector<std::size_t>, std::vector<std::size_t>> out;
  if (space_.leaves().empty()) {  // before the first recut: rank 0 speaks for all
    if (rank_ == 0) {
      for (std::size_t i = 0; i < gas_.size(); ++i) out.first.push_back(i);
      for (std::size_t i = 0; i < dm_.size(); ++i) out.second.push_back(i);
    }
    return out;
  }
  for (int c : space_.leaves()) {
    if (!mine(c)) continue;
    const Cell& cell = space_.cell(c);
    for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) out.first.push_back(i);
    for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i) out.second.push_back(i);
  }
  return out;
}

std::pair<std::size_t, std::size_t> Engine::list_share(int rank) const {
  const std::size_t n = space_.leaves().size(), ranks = static_cast<std::size_t>(ranks_->size());
  const auto r = static_cast<std::size_t>(rank);
  return {n * r / ranks, n * (r + 1) / ranks};
}

void Engine::find_neighbour_lists(const ForEach& for_each) {
  // Each rank of a replicated recut would otherwise find every list on its own threads: the
  // lists are the same on every rank, so each finds a share and they are handed round.
  if (!ranks_) {
    space_.find_neighbours(for_each);
    return;
  }
  const auto [first, last] = list_share(rank_);
  space_.find_neighbours(for_each, first, last);
}

void Engine::share_neighbour_lists() {
  if (!ranks_) return;
  const std::vector<int>& leaves = space_.leaves();
  lists_buffer_.clear();
  MessageWriter w(lists_buffer_);
  const auto [first, last] = list_share(rank_);
  for (std::size_t l = first; l < last; ++l)
    for (const std::vector<int>* list : {&space_.neighbours(leaves[l]), &space_.surroundings(leaves[l])}) {
      w.put(list->size());
      w.put(list->data(), list->size());
    }
  const auto all = ranks_->allgather(lists_buffer_);
  std::vector<int> neighbours, surroundings;
  for (int r = 0; r < ranks_->size(); ++r) {
    if (r == rank_) continue;
    MessageReader in(all[static_cast<std::size_t>(r)]);
    const auto [from, to] = list_share(r);
    for (std::size_t l = from; l < to; ++l) {
      for (std::vector<int>* list : {&neighbours, &surroundings}) {
        list->resize(in.get<std::size_t>());
        in.get(list->data(), list->size());
      }
      space_.set_lists(l, neighbours, surroundings);
    }
    if (!in.done()) throw std::logic_error(fmt::format("rank {} sent more neighbour lists than expected", r));
  }
}

int Engine::rank() const { return rank_; }
int Engine::ranks() const { return ranks_ ? ranks_->size() : 1; }
bool Engine::any_rank(bool yes) const { return ranks_ ? ranks_->any(yes) : yes; }

std::vector<double> Engine::from_every_rank(double mine) const {
  if (!ranks_) return {mine};
  std::vector<double> out;
  for (const auto& theirs : ranks_->allgather_values(std::span<const double>(&mine, 1), "one value")) out.push_back(theirs[0]);
  return out;
}
std::uint64_t Engine::bytes_sent() const { return ranks_ ? ranks_->traffic().bytes : 0; }
std::uint64_t Engine::messages_sent() const { return ranks_ ? ranks_->traffic().messages : 0; }
std::uint64_t Engine::ghost_bytes_sent() const { return ranks_ ? ranks_->traffic().point_to_point_bytes : 0; }

std::vector<std::pair<Vec3, double>> Engine::measured_work() const {
  // The work each rank measured in its leaves since owners were last chosen, located by the
  // leaves' centres so that it can be given to the leaves of the next recut. Summed in rank
  // order from an allgather (not a reduction, whose rounding may differ between ranks).
  std::vector<std::pair<Vec3, double>> measured;
  if (leaf_cost_.empty()) return measured;
  std::vector<double> total(leaf_cost_.size(), 0.0);
  for (const auto& part : ranks_->allgather_values(std::span<const double>(leaf_cost_), "cell costs"))
    for (std::size_t c = 0; c < total.size(); ++c) total[c] += part[c];
  for (int c : space_.leaves())
    if (total[static_cast<std::size_t>(c)] > 0.0) measured.push_back({space_.cell(c).centre(), total[static_cast<std::size_t>(c)]});
  return measured;
}

void Engine::assign_owners(const std::vector<std::pair<Vec3, double>>& measured) {
  // Owners are chosen per leaf, not per top-level cell: every rank holds every particle, so
  // the grain of the cut is free, and the top-level grid (which changes the results, bit by
  // bit) need not depend on the rank count. Leaves are ordered along a Hilbert curve through
  // their centres, so each rank's leaves form a compact region.
  const std::vector<int>& leaves = space_.leaves();
  const std::size_t nl = leaves.size();
  constexpr int bits = 16;
  const double cells_per_side = static_cast<double>(1u << bits);
  // The curve runs through a cube as wide as the box's longest side, not through the box
  // stretched to a cube: in an elongated box (Sod's 4 x 1 x 1) a stretched curve may cut
  // lengthwise, giving ranks four times the common surface.
  const double side = std::max({space_.box_size().x, space_.box_size().y, space_.box_size().z});
  std::vector<std::uint64_t> key(nl);
  for (std::size_t l = 0; l < nl; ++l) {
    const Vec3 x = space_.cell(leaves[l]).centre();
    std::array<std::uint32_t, 3> q;
    for (int k = 0; k < 3; ++k)
      q[static_cast<std::size_t>(k)] = static_cast<std::uint32_t>(
          std::clamp((x[k] - space_.box_lo()[k]) / side * cells_per_side, 0.0, cells_per_side - 1.0));
    key[l] = domain::hilbert_key(q[0], q[1], q[2], bits);
  }
  std::vector<int> curve(nl);
  for (std::size_t l = 0; l < nl; ++l) curve[l] = static_cast<int>(l);
  std::sort(curve.begin(), curve.end(), [&](int a, int b) {
    return key[static_cast<std::size_t>(a)] != key[static_cast<std::size_t>(b)] ? key[static_cast<std::size_t>(a)] < key[static_cast<std::size_t>(b)] : a < b;
  });
  // Work per leaf: what was measured where the leaf now is since the cut was made (the
  // intervals between recuts are carried over), or its particle count at first. One interval
  // is a few steps, and one task slowed by the host (a descheduled rank) could make it look
  // 30% imbalanced: a cut redone on that (Sedov 250k, 2 ranks: 6 cuts instead of 1) moved
  // the boundary off the blast's plane of symmetry and made the run ~10% slower.
  std::vector<double> work(nl, 0.0);
  std::vector<int> slot(space_.cells().size(), -1);
  for (std::size_t l = 0; l < nl; ++l) slot[static_cast<std::size_t>(leaves[l])] = static_cast<int>(l);
  if (measured.empty()) {
    for (std::size_t l = 0; l < nl; ++l)
      work[l] = static_cast<double>(space_.cell(leaves[l]).count + space_.cell(leaves[l]).dm_count);
  } else {
    std::vector<std::pair<Vec3, double>> since_cut;
    since_cut.swap(work_since_cut_);
    since_cut.insert(since_cut.end(), measured.begin(), measured.end());
    for (const auto& [x, cost] : since_cut) {
      int c = space_.cell_at(x);
      while (!space_.cell(c).leaf) {  // an empty octant: the first leaf below stands in
        int next = -1;
        for (int ch : space_.cell(c).children)
          if (ch >= 0 && next < 0) next = ch;
        c = next;
      }
      work[static_cast<std::size_t>(slot[static_cast<std::size_t>(c)])] += cost;
    }
  }
  // The cut points stay (as positions on the curve) while they still share the work well.
  const int n = ranks_->size();
  auto owners_from_cuts = [&] {
    std::vector<int> own(nl);
    for (std::size_t l = 0; l < nl; ++l)
      own[l] = static_cast<int>(std::upper_bound(cut_keys_.begin(), cut_keys_.end(), key[l]) - cut_keys_.begin());
    return own;
  };
  // A cut is judged only once it has stood for a span of steps. Judged on the few steps since
  // the last recut, a core slowed by the host for a while made the cut follow it (Sedov 250k,
  // 2 ranks: 12-14 cuts, each with a migration), and a cut made from the first steps' work
  // left the ranks 12% apart for the rest of the run, where the symmetric cut from particle
  // counts was even (docs/performance.md, domain.repartition_min_steps).
  std::vector<int> leaf_owner;
  if (cut_keys_.size() == static_cast<std::size_t>(n - 1)) {
    leaf_owner = owners_from_cuts();
    const bool judged = steps_ - cut_step_ >= config_.repartition_min_steps;
    if (judged && domain::needs_repartition(domain::imbalance(work, leaf_owner, n), config_.repartition_imbalance))
      leaf_owner.clear();
  }
  if (leaf_owner.empty()) {
    const std::vector<int> cut = domain::partition(curve, work, n);
    // Rank r starts at the first leaf along the curve that the cut gives to r or beyond.
    cut_keys_.assign(static_cast<std::size_t>(n - 1), std::numeric_limits<std::uint64_t>::max());
    for (int l : curve)
      for (int r = 1; r <= cut[static_cast<std::size_t>(l)]; ++r)
        cut_keys_[static_cast<std::size_t>(r - 1)] = std::min(cut_keys_[static_cast<std::size_t>(r - 1)], key[static_cast<std::size_t>(l)]);
    leaf_owner = owners_from_cuts();
    ++partitions_;
    cut_step_ = steps_;
  } else if (!measured.empty()) {
    work_since_cut_.clear();
    for (std::size_t l = 0; l < nl; ++l)
      if (work[l] > 0.0) work_since_cut_.push_back({space_.cell(leaves[l]).centre(), work[l]});
  }
  owner_.assign(space_.cells().size(), 0);
  for (std::size_t l = 0; l < nl; ++l) owner_[static_cast<std::size_t>(leaves[l])] = leaf_owner[l];
  leaf_cost_.assign(space_.cells().size(), 0.0);
}

void Engine::plan_ghost_exchange() {
  const std::size_t ncells = space_.cells().size();
  send_to_.assign(ncells, {});
  need_recv_.assign(ncells, 0);
  // Every rank sees every cell's owner, activity and neighbours, so sender and receiver
  // agree on each message without asking each other.
  for (int c : space_.leaves()) {
    if (!cell_active_[static_cast<std::size_t>(c)] || space_.cell(c).count == 0) continue;
    const int reader = owner_[static_cast<std::size_t>(c)];
    for (int n : space_.neighbours(c)) {
      const auto un = static_cast<std::size_t>(n);
      if (!cell_active_[un] || owner_[un] == reader) continue;
      if (owner_[un] == rank_) {
        auto& to = send_to_[un];
        if (std::find(to.begin(), to.end(), reader) == to.end()) to.push_back(reader);
      }
      if (reader == rank_) need_recv_[un] = 1;
    }
  }
  for (auto& to : send_to_) std::sort(to.begin(), to.end());
}

void Engine::post_receives() {
  recv_handle_.assign(space_.cells().size(), -1);
  for (int t : step_tasks_) {
    const tasks::Task& task = graph_.task(t);
    if (task.type != recv_type_) continue;
    recv_handle_[static_cast<std::size_t>(task.ci)] =
        ranks_->post_recv(owner_[static_cast<std::size_t>(task.ci)], task.ci, ghost_results_bytes(space_, task.ci));
  }
}

template <class Pack, class Unpack>
void Engine::exchange_active_leaves(bool gas_leaves_only, std::vector<char>& buffer, Pack&& pack, Unpack&& unpack,
                                    const char* what, bool every_leaf) {
  // Every rank knows every leaf's owner and activity, so each reads the others' messages
  // leaf by leaf without being told which leaves they hold.
  auto sends = [&](int c, int r) {
    const auto uc = static_cast<std::size_t>(c);
    return (every_leaf || cell_active_[uc]) && owner_[uc] == r && (!gas_leaves_only || space_.cell(c).count > 0);
  };
  buffer.clear();  // keeps its capacity from step to step
  MessageWriter w(buffer);
  for (int c : space_.leaves())
    if (sends(c, rank_)) pack(w, c);
  const auto all = ranks_->allgather(buffer);
  for (int r = 0; r < ranks_->size(); ++r) {
    if (r == rank_) continue;
    MessageReader in(all[static_cast<std::size_t>(r)]);
    for (int c : space_.leaves())
      if (sends(c, r)) unpack(in, c);
    if (!in.done()) throw std::logic_error(fmt::format("rank {} sent more {} than expected", r, what));
  }
}

void Engine::sync_owned_cells(bool gas_cells_only) {
  exchange_active_leaves(
      gas_cells_only, sync_buffer_,
      [&](MessageWriter& w, int c) {
        pack_cell_state(w, space_, gas_, dm_, c, gas_moved_, dm_moved_, StateFields::StepChanged);
      },
      [&](MessageReader& r, int c) {
        unpack_cell_state(r, space_, gas_, dm_, c, gas_moved_, dm_moved_, StateFields::StepChanged);
      },
      "cell state");
}

void Engine::sync_feedback_sites() {
  exchange_active_leaves(
      true, sync_buffer_,
      [&](MessageWriter& w, int c) { pack_feedback_sites(w, fb_->cells[static_cast<std::size_t>(c)]); },
      [&](MessageReader& r, int c) { unpack_feedback_sites(r, fb_->cells[static_cast<std::size_t>(c)]); },
      "feedback sites");
}

void Engine::combine_wake_requests() {
  // Each rank's requests (particle, bin) go to every rank and are combined by the minimum:
  // a few per step, where a reduction over the whole array sent a byte per particle.
  // Only the drifted leaves can hold requests, so only they are scanned, not every particle.
  wake_buffer_.clear();
  MessageWriter w(wake_buffer_);
  for_each_drifted_gas([&](std::size_t i) {
    if (gas_.wake_bin[i] == kNoBin) return;
    w.put(static_cast<std::uint64_t>(i));
    w.put(gas_.wake_bin[i]);
  });
  const auto all = ranks_->allgather(wake_buffer_);
  for (int r = 0; r < ranks_->size(); ++r) {
    if (r == rank_) continue;
    MessageReader in(all[static_cast<std::size_t>(r)]);
    while (!in.done()) {
      const auto i = in.get<std::uint64_t>();
      const auto bin = in.get<TimeBin>();
      if (i >= gas_.wake_bin.size())
        throw std::logic_error(fmt::format("rank {} asked to wake particle {} of {}", r, i, gas_.wake_bin.size()));
      gas_.wake_bin[i] = std::min(gas_.wake_bin[i], bin);
    }
  }
}

void Engine::gather_state() {
  if (!halo_mode_ || all_current_ || space_.leaves().empty()) return;
  exchange_active_leaves(
      false, sync_buffer_, [&](MessageWriter& w, int c) { pack_cell_state(w, space_, gas_, dm_, c, {}, {}); },
      [&](MessageReader& r, int c) { unpack_cell_state(r, space_, gas_, dm_, c, {}, {}); }, "whole state", true);
  all_current_ = true;
}

void Engine::finish_exchanges() {
  const auto t0 = std::chrono::steady_clock::now();
  ranks_->finish();
  add_measured_costs();
  // What each rank's tasks changed reaches every other rank; then the decisions every rank
  // must take alike (recut the cells, shorten whose steps) are made from the same data.
  if (halo_mode_) {
    exchange_halo();
  } else {
    sync_owned_cells(false);
    if (config_.hydro.timestep_limiter) combine_wake_requests();
  }
  ctx_->cover_exceeded = ranks_->any(ctx_->cover_exceeded.load());
  ctx_->h_capped = static_cast<int>(ranks_->sum(static_cast<long long>(ctx_->h_capped.load())));
  ctx_->h_max_capped = static_cast<int>(ranks_->sum(static_cast<long long>(ctx_->h_max_capped.load())));
  exchange_s_ += seconds_since(t0);
}

void Engine::add_measured_costs() {
  const std::vector<tasks::TaskRecord>& records = record_timeline_ ? records_ : mpi_records_;
  if (leaf_cost_.size() != space_.cells().size()) leaf_cost_.assign(space_.cells().size(), 0.0);
  for (int t : step_tasks_) {
    const tasks::Task& task = graph_.task(t);
    const tasks::TaskRecord& rec = records[static_cast<std::size_t>(t)];
    if (task.ci < 0 || rec.thread < 0 || task.type == recv_type_) continue;
    leaf_cost_[static_cast<std::size_t>(task.ci)] += static_cast<double>(rec.end_ns - rec.start_ns);
  }
}

}  // namespace fountain
