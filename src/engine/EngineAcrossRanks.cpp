// The engine's work across MPI ranks: what the ranks send each other (who owns which leaf is domain/RankLayout) (docs/design.md, "MPI").
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstring>
#include <limits>

#include "domain/DomainDecomposition.hpp"
#include "domain/RankExchange.hpp"
#include "engine/CellMessages.hpp"
#include "engine/CollectivesOverRanks.hpp"
#include "engine/Engine.hpp"
#include "feedback/FeedbackLoop.hpp"

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
    if (layout_.rank() == 0) {
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

void Engine::visit_own_state(const StatePiece<GasParticles>& gas,
                             const StatePiece<CollisionlessParticles>& collisionless) const {
  if (space_.leaves().empty()) {
    // Before the first recut a rank in halo mode holds the share it read, and owns it;
    // otherwise rank 0 holds every particle and speaks for all. No leaves split the state
    // the same way for every rank count yet: a particle at a time.
    if (!layout_.halo_mode() && layout_.rank() != 0) return;
    for (std::size_t i = 0; i < gas_.size(); ++i) gas(gas_, i, 1);
    for (std::size_t i = 0; i < dm_.size(); ++i) collisionless(dm_, i, 1);
    return;
  }
  for (int c : space_.leaves()) {
    if (!mine(c)) continue;
    const Cell& cell = space_.cell(c);
    if (cell.count > 0) gas(gas_, cell.first, cell.count);
    if (cell.dm_count > 0) collisionless(dm_, cell.dm_first, cell.dm_count);
  }
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
  const auto [first, last] = list_share(layout_.rank());
  space_.find_neighbours(for_each, first, last);
}

void Engine::share_neighbour_lists() {
  if (!ranks_) return;
  const std::vector<int>& leaves = space_.leaves();
  lists_buffer_.clear();
  MessageWriter w(lists_buffer_);
  const auto [first, last] = list_share(layout_.rank());
  for (std::size_t l = first; l < last; ++l)
    for (const std::vector<int>* list : {&space_.neighbours(leaves[l]), &space_.surroundings(leaves[l])}) {
      w.put(list->size());
      w.put(list->data(), list->size());
    }
  const auto all = ranks_->allgather(lists_buffer_);
  std::vector<int> neighbours, surroundings;
  for (int r = 0; r < ranks_->size(); ++r) {
    if (r == layout_.rank()) continue;
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

int Engine::rank() const { return layout_.rank(); }
int Engine::ranks() const { return ranks_ ? ranks_->size() : 1; }
bool Engine::any_rank(bool yes) const { return ranks_ ? ranks_->any(yes) : yes; }

std::vector<double> Engine::from_every_rank(double mine) const {
  if (!ranks_) return {mine};
  std::vector<double> out;
  for (const auto& theirs : ranks_->allgather_values(std::span<const double>(&mine, 1), "one value")) out.push_back(theirs[0]);
  return out;
}
Collectives* Engine::collectives() const { return collectives_.get(); }
std::uint64_t Engine::bytes_sent() const { return ranks_ ? ranks_->traffic().bytes : 0; }
std::uint64_t Engine::messages_sent() const { return ranks_ ? ranks_->traffic().messages : 0; }
std::uint64_t Engine::ghost_bytes_sent() const { return ranks_ ? ranks_->traffic().point_to_point_bytes : 0; }

std::vector<std::pair<Vec3, double>> Engine::measured_work() const {
  // The work each rank measured in its leaves since owners were last chosen, located by the
  // leaves' centres so that it can be given to the leaves of the next recut. Summed in rank
  // order from an allgather (not a reduction, whose rounding may differ between ranks).
  std::vector<std::pair<Vec3, double>> measured;
  const std::vector<double>& cost = layout_.costs();
  if (cost.empty()) return measured;
  std::vector<double> total(cost.size(), 0.0);
  for (const auto& part : ranks_->allgather_values(std::span<const double>(cost), "cell costs"))
    for (std::size_t c = 0; c < total.size(); ++c) total[c] += part[c];
  for (int c : space_.leaves())
    if (total[static_cast<std::size_t>(c)] > 0.0) measured.push_back({space_.cell(c).centre(), total[static_cast<std::size_t>(c)]});
  return measured;
}


void Engine::plan_ghost_exchange() {
  const std::size_t ncells = space_.cells().size();
  send_to_.assign(ncells, {});
  need_recv_.assign(ncells, 0);
  // Every rank sees every cell's owner, activity and neighbours, so sender and receiver
  // agree on each message without asking each other.
  for (int c : space_.leaves()) {
    if (!cell_active_[static_cast<std::size_t>(c)] || space_.cell(c).count == 0) continue;
    const int reader = layout_.owner(static_cast<std::size_t>(c));
    for (int n : space_.neighbours(c)) {
      const auto un = static_cast<std::size_t>(n);
      if (!cell_active_[un] || layout_.owner(un) == reader) continue;
      if (layout_.owner(un) == layout_.rank()) {
        auto& to = send_to_[un];
        if (std::find(to.begin(), to.end(), reader) == to.end()) to.push_back(reader);
      }
      if (reader == layout_.rank()) need_recv_[un] = 1;
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
        ranks_->post_recv(layout_.owner(static_cast<std::size_t>(task.ci)), task.ci, ghost_results_bytes(space_, task.ci));
  }
}

template <class Pack, class Unpack>
void Engine::exchange_active_leaves(bool gas_leaves_only, std::vector<char>& buffer, Pack&& pack, Unpack&& unpack,
                                    const char* what, bool every_leaf) {
  // Every rank knows every leaf's owner and activity, so each reads the others' messages
  // leaf by leaf without being told which leaves they hold.
  auto sends = [&](int c, int r) {
    const auto uc = static_cast<std::size_t>(c);
    return (every_leaf || cell_active_[uc]) && layout_.owner(uc) == r && (!gas_leaves_only || space_.cell(c).count > 0);
  };
  buffer.clear();  // keeps its capacity from step to step
  MessageWriter w(buffer);
  for (int c : space_.leaves())
    if (sends(c, layout_.rank())) pack(w, c);
  const auto all = ranks_->allgather(buffer);
  for (int r = 0; r < ranks_->size(); ++r) {
    if (r == layout_.rank()) continue;
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
  // Each rank's requests (leaf, place in it, bin) go to every rank and are combined by the
  // minimum: a few per step, where a reduction over the whole array sent a byte per particle.
  // (By leaf: in halo mode a particle's index differs between the ranks that hold it.)
  // Only the drifted leaves can hold requests, so only they are scanned, not every particle.
  wake_buffer_.clear();
  MessageWriter w(wake_buffer_);
  for (int c : space_.leaves()) {
    if (!drifted_[static_cast<std::size_t>(c)] || !keeps_current(c)) continue;
    const Cell& cell = space_.cell(c);
    for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
      if (gas_.wake_bin[i] == kNoBin) continue;
      w.put(c);
      w.put(static_cast<std::uint32_t>(i - cell.first));
      w.put(gas_.wake_bin[i]);
    }
  }
  const auto all = ranks_->allgather(wake_buffer_);
  for (int r = 0; r < ranks_->size(); ++r) {
    if (r == layout_.rank()) continue;
    MessageReader in(all[static_cast<std::size_t>(r)]);
    while (!in.done()) {
      const int c = in.get<int>();
      const auto k = in.get<std::uint32_t>();
      const auto bin = in.get<TimeBin>();
      if (c < 0 || static_cast<std::size_t>(c) >= space_.cells().size() || k >= space_.cell(c).count)
        throw std::logic_error(fmt::format("rank {} asked to wake particle {} of cell {}", r, k, c));
      if (!keeps_current(c)) continue;  // (in halo mode) a leaf this rank does not hold
      TimeBin& mine_bin = gas_.wake_bin[space_.cell(c).first + k];
      mine_bin = std::min(mine_bin, bin);
    }
  }
}

void Engine::finish_exchanges() {
  const auto t0 = std::chrono::steady_clock::now();
  ranks_->finish();
  add_measured_costs();
  // What each rank's tasks changed reaches every other rank; then the decisions every rank
  // must take alike (recut the cells, shorten whose steps) are made from the same data.
  if (layout_.halo_mode()) {
    exchange_halo();
  } else {
    sync_owned_cells(false);
    if (config_.hydro.timestep_limiter) combine_wake_requests();
  }
  ctx_->cover_exceeded = ranks_->any(ctx_->cover_exceeded.load());
  ctx_->h_capped = static_cast<int>(ranks_->sum(static_cast<long long>(ctx_->h_capped.load())));
  ctx_->h_max_capped = static_cast<int>(ranks_->sum(static_cast<long long>(ctx_->h_max_capped.load())));
  ctx_->h_min_held = static_cast<int>(ranks_->sum(static_cast<long long>(ctx_->h_min_held.load())));
  ctx_->msph_decoupled = ranks_->sum(ctx_->msph_decoupled.load());
  exchange_s_ += seconds_since(t0);
}

void Engine::add_measured_costs() {
  const std::vector<tasks::TaskRecord>& records = record_timeline_ ? records_ : mpi_records_;
  std::vector<double>& cost = layout_.costs_of(space_.cells().size());
  for (int t : step_tasks_) {
    const tasks::Task& task = graph_.task(t);
    const tasks::TaskRecord& rec = records[static_cast<std::size_t>(t)];
    if (task.ci < 0 || rec.thread < 0 || task.type == recv_type_) continue;
    cost[static_cast<std::size_t>(task.ci)] += static_cast<double>(rec.end_ns - rec.start_ns);
  }
}

void Engine::add_feedback_exchanges(int star_formation_done, int feedback_apply) {
  // Feedback reads neighbours in any leaf, as star formation left them; it is their only
  // reader before the exchange after the graph, so with no site on any rank (a run before
  // its first stars) one sum replaces both exchanges.
  tasks_[star_formation_done].run = [this](const tasks::Task&) {
    long long sites = 0;
    for (int c : space_.leaves())
      if (mine(c)) sites += static_cast<long long>(fb_->cells[static_cast<std::size_t>(c)].sites.size());
    feedback_sites_anywhere_ = ranks_->sum(sites) > 0;
    if (feedback_sites_anywhere_) sync_owned_cells(true);
  };
  TaskKind::Run apply = tasks_[feedback_apply].run;
  tasks_[feedback_apply].run = [this, apply](const tasks::Task& t) {
    if (feedback_sites_anywhere_) sync_feedback_sites();
    apply(t);
  };
}

void Engine::register_exchange_tasks(int drift, int kick_close, int ghost, int force, int star_formation_done) {
  // A leaf's ghost results are sent once its ghost is done; a foreign leaf's arrive by a
  // receive that its readers wait for. A receive runs only once its message is in (the
  // executor polls for it), so no worker blocks and every rank's sends go out.
  TaskKind send = TaskKind::leaf({"send", "ghost", "mpi"}, Stage::Exchange, [this](const tasks::Task& t) {
    domain::RankExchange::Buffer b;
    b.reserve(ghost_results_bytes(space_, t.ci));
    MessageWriter w(b);
    pack_ghost_results(w, space_, gas_, t.ci);
    // Each send keeps its buffer until it completes: copies for all but the last rank.
    const std::vector<int>& to = send_to_[static_cast<std::size_t>(t.ci)];
    for (std::size_t k = 0; k + 1 < to.size(); ++k) ranks_->post_send(to[k], t.ci, b);
    if (!to.empty()) ranks_->post_send(to.back(), t.ci, std::move(b));
  });
  TaskKind recv = TaskKind::leaf({"recv", "ghost", "mpi"}, Stage::Exchange, [this](const tasks::Task& t) {
    const auto& b = ranks_->wait_recv(recv_handle_[static_cast<std::size_t>(t.ci)]);
    MessageReader r(b);
    unpack_ghost_results(r, space_, gas_, t.ci);
  });
  for (TaskKind* k : {&send, &recv}) {
    k->gas_leaves_only = true;
    // Explicit edges, not the leaf's write chain: a send that is not listed this run must
    // not cut the chain from the ghost to the force loop.
    k->writes_leaf = false;
    k->activation = TaskKind::Activation::Custom;
  }
  send.active_if = [this](int c) { return ghost_exchange_ && !send_to_[static_cast<std::size_t>(c)].empty(); };
  recv.active_if = [this](int c) { return ghost_exchange_ && need_recv_[static_cast<std::size_t>(c)] != 0; };
  send_type_ = tasks_.add(std::move(send));
  recv_type_ = tasks_.add(std::move(recv));
  tasks_.link([=, send = send_type_, recv = recv_type_](GraphBuilder& g) {
    for (int c : g.leaves()) {
      // Across ranks, the end of star formation brings in every other rank's leaves: no
      // drift of a foreign leaf may still be running then.
      if (star_formation_done >= 0) g.depends(g.task(drift, c), g.step_tasks(star_formation_done).front());
      const int s = g.task(send, c);
      if (s < 0) continue;
      g.depends(g.task(ghost, c), s);
      g.depends(g.task(drift, c), g.task(recv, c));
      g.depends(s, g.task(kick_close, c));
    }
    for (int c : g.leaves()) {
      const int f = g.task(force, c);
      if (f < 0) continue;
      for (int n : g.neighbours(c)) g.depends(g.task(recv, n), f);
    }
  });
}

}  // namespace fountain
