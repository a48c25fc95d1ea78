// The engine: owns particles and cells, builds the task graph and advances the run step by step.
#pragma once
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "cooling/RadiativeCooling.hpp"
#include "engine/RunConfig.hpp"
#include "step/StepContext.hpp"
#include "step/StepTasks.hpp"
#include "particles/CollisionlessParticles.hpp"
#include "particles/GasParticles.hpp"
#include "domain/RankLayout.hpp"
#include "space/Space.hpp"
#include "step/StarFormationTally.hpp"
#include "tasks/Executor.hpp"
#include "tasks/TaskGraph.hpp"
#include "timestep/Integration.hpp"
#include "step/TimeLine.hpp"

namespace fountain {

class MessageWriter;
class MessageReader;
namespace star_formation {
struct StarFormationState;
}
namespace feedback {
struct FeedbackState;
}
namespace domain {
class RankExchange;
}
class Collectives;
class CollectivesOverRanks;

// Sums over all particles (gas at predicted values), for conservation checks.
struct Totals {
  double mass = 0.0;
  Vec3 momentum;
  double kinetic = 0.0;
  double thermal = 0.0;
  double potential = 0.0;  // gravitational, each pair counted once (zero without gravity)
  double reservoir = 0.0;  // feedback energy held in reservoirs (not yet thermal)
  double energy() const { return kinetic + thermal + potential; }
};

struct StepInfo {
  long long step = 0;
  double time = 0.0;
  double dt = 0.0;
  std::size_t active = 0;        // active particles
  std::size_t tasks_run = 0;
  bool rebuilt = false;
  bool recut_at_end = false;     // the cells were recut last thing (star formation changed the particles)
  double wall_s = 0.0;           // whole step
  double tasks_wall_s = 0.0;     // inside the executor
  double tasks_busy_s = 0.0;     // summed over threads, inside tasks
};

class Engine {
 public:
  // The gas one rank read of a run across ranks that hold shares (RunConfig::ranks_hold_shares):
  // the file's rows [first, first + gas.size()) of `total`, or (a restart set's pieces) the
  // places in the run given one by one; with dm_shared, the collisionless particles alike
  // (otherwise every rank read every one).
  struct GasShare {
    std::size_t first = 0, total = 0;
    std::vector<std::uint64_t> places;  // empty: first, first + 1, ...
    bool dm_shared = false;
    std::size_t dm_total = 0;
    std::vector<std::uint64_t> dm_places;  // empty: dm_first, dm_first + 1, ...
    std::size_t dm_first = 0;
  };
  // Without `share`, the gas is every particle of the run.
  Engine(const RunConfig& config, GasParticles gas, CollisionlessParticles dm = {},
         std::optional<GasShare> share = std::nullopt);
  ~Engine();

  // First densities (twice, so the MSPH rule sees real densities), forces and timesteps.
  void initialise();
  bool finished() const { return ti_current_ >= TimeLine::ticks; }
  // Advances to the next time a particle's step ends, or to ti_stop if earlier.
  StepInfo step(IntegerTime ti_stop = TimeLine::ticks);
  // Drifts every particle this rank keeps current to the current time (before a snapshot).
  void drift_all();

  // Drifts everything and recuts the cells now. Called before a restart file is written, so
  // that the saved run and the restarted one continue from the same cells, bit for bit.
  void rebuild_now();
  // Continues a run from a restart file's particles (in place of initialise()). A file written
  // inside a step holds the particles at that step's end, ti_current; the step began at
  // ti_step_begin, which the first step after the restart reports as its start.
  // The mesh step (comoving TreePM) in progress is restored with it.
  struct MeshStepState {
    int bin = -1;
    IntegerTime ti_begin = 0;
  };
  void restore(IntegerTime ti_current, long long steps, IntegerTime ti_step_begin, MeshStepState mesh_step);
  MeshStepState mesh_step() const;
  // Called inside step() right after the cells were recut because the run needed it, before
  // that step's tasks: a restart file written then holds the particles just as the recut
  // left them, and restore() recuts them into the same cells, so the restarted run goes on
  // exactly as this one, and writing the file changes nothing in the run. (A step that ends
  // with a recut says so in StepInfo::recut_at_end: that is such a point too.)
  void set_after_rebuild(std::function<void()> f) { after_rebuild_ = std::move(f); }

  // Densities, h and forces of the particles active at ti, with no kick: for tests that
  // compare the loops with direct summation.
  void compute_hydro_at(IntegerTime ti);

  double time() const { return timeline_.time(ti_current_); }
  // Comoving runs (whose time() is ln a): the scale factor now, the cosmic time since the
  // start, and the cosmic time a step of `bin` from now spans. Plain runs: 1, time() and the
  // step itself.
  double scale_factor() const;
  double cosmic_time() const;
  double cosmic_step(int bin) const;
  IntegerTime ti_current() const { return ti_current_; }
  // When the step in progress began (inside step(): the previous step's end); ti_current()
  // between steps.
  IntegerTime ti_step_begin() const { return ti_step_begin_; }
  const TimeLine& timeline() const { return timeline_; }
  IntegerTime to_ticks(double t) const;
  long long steps() const { return steps_; }
  // Particle-steps whose h was held at hydro.h_max short of neighbours, since the start.
  long long h_max_capped() const { return h_max_capped_particles_; }
  long long h_min_held() const { return h_min_held_particles_; }  // particle-steps at the floor of h
  // Force interactions the MSPH rule dropped since the start (an SPH run: none).
  long long msph_decoupled() const { return msph_decoupled_; }

  GasParticles& gas() { return gas_; }
  const GasParticles& gas() const { return gas_; }
  CollisionlessParticles& dark_matter() { return dm_; }
  const CollisionlessParticles& dark_matter() const { return dm_; }
  const Space& space() const { return space_; }
  const RunConfig& config() const { return config_; }
  const tasks::TaskTypeRegistry& task_types() const { return tasks_.registry(); }
  const tasks::TaskGraph& graph() const { return graph_; }
  const std::vector<tasks::TaskRecord>& last_records() const { return records_; }
  // The graph last_records() index into: the current one, or the one the last step ran if
  // the cells were recut since (after star particles were spawned, say).
  const tasks::TaskGraph& records_graph() const { return records_stale_ ? records_graph_ : graph_; }
  int threads() const { return executor_.threads(); }
  // Energy radiated by cooling since the start of the run (internal units), for energy
  // conservation checks; set_radiated_energy continues it after a restart.
  double radiated_energy() const { return radiated_; }
  void set_radiated_energy(double e) { radiated_ = e; }
  // The run's radiative cooling, or null when it is off.
  const cooling::RadiativeCooling* cooling() const { return cooling_.get(); }
  Totals totals() const;
  // What star formation and feedback did since the start of the run, and in the last step
  // (zero when star formation is off); set_star_formation_total continues it after a restart.
  const star_formation::StarFormationTally& star_formation_total() const { return sf_total_; }
  const star_formation::StarFormationTally& star_formation_last_step() const { return sf_last_step_; }
  void set_star_formation_total(const star_formation::StarFormationTally& t) { sf_total_ = t; }
  // Tallies this step's star formation, then spawns stars and dissolves gas (recutting the
  // cells if any particle came or went). Every step ends with it; public so that tests can
  // apply it to a state they set up.
  void finish_star_formation();
  std::uint64_t next_particle_id() const { return next_id_; }
  void set_next_particle_id(std::uint64_t id) { next_id_ = id; }
  void set_record_timeline(bool on) { record_timeline_ = on; }

  // Across MPI ranks (docs/design.md, "MPI"): every rank stores every particle (or, in halo
  // mode, only its own leaves and their neighbours), each runs the tasks of the cells it
  // owns, and the ranks exchange what those tasks change.
  int rank() const;
  int ranks() const;
  // Whether any rank says yes (the one rank's answer when alone): for decisions that every
  // rank must take together, such as writing a restart file.
  bool any_rank(bool yes) const;
  // Every rank's value, in rank order (this rank's alone when running alone); every rank
  // must call it.
  std::vector<double> from_every_rank(double mine) const;
  // The ranks' collectives for work spread over them (the group finders), or null when alone.
  Collectives* collectives() const;
  // How often the cut of the leaves between ranks was chosen.
  int partitions() const { return layout_.partitions(); }
  // Wall seconds since the start: in the task graphs, and in the exchanges after them
  // (across ranks: waiting for the slowest rank, then the cells' state).
  double graph_seconds() const { return graph_s_; }
  // The exchanges after the last graph, in ns since it began ({0, 0} when running alone).
  std::pair<std::int64_t, std::int64_t> last_exchange_ns() const { return last_exchange_ns_; }
  double exchange_seconds() const { return exchange_s_; }
  // Wall seconds in rebuilds (the drift before, the recut, the neighbour lists and graph,
  // across ranks the owners and what goes between ranks with them).
  double rebuild_seconds() const { return rebuild_s_; }
  // Whether this run holds on each rank only its own leaves and their neighbours (MPI runs
  // without gravity, star formation and collisionless particles: docs/design.md, "Halo mode").
  bool halo_mode() const { return layout_.halo_mode(); }
  // In halo mode, the share of the leaves this rank held, averaged over the recuts (1
  // otherwise).
  double held_share() const { return layout_.held_share(); }
  // Halo mode with star formation: spawning and dissolving across ranks since the start,
  // alike on every rank (steps that had events, owners' turns at them, events handled, and
  // neighbours in another rank's leaves that took a dissolved particle's share).
  struct EventRounds {
    long long steps = 0, turns = 0, events = 0, foreign_receivers = 0;
  };
  const EventRounds& event_rounds() const { return event_rounds_; }
  // The periodic mesh's side and this rank's share of it: planes and bytes (0 without one).
  struct MeshShare {
    int cells = 0, planes = 0;
    std::size_t bytes = 0;
  };
  MeshShare mesh_share() const;
  // Across ranks with domain.assemble_gravity_tree: the trees this rank assembled (one per
  // task graph) and what the other ranks sent it for them, summed (all 0 otherwise).
  struct TreeAssembly {
    long long assemblies = 0, nodes_received = 0, sources_received = 0;
  };
  TreeAssembly tree_assembly() const { return tree_assembly_; }
  // The particles in the run's order, handed to rank 0 in pieces: gas(store, first, count)
  // for every gas particle in turn, then collisionless(...) likewise; the other ranks' calls
  // hand nothing (every rank calls it at the same point). Where rank 0 holds only some
  // particles (halo mode), each leaf's owner sends its particles, at most
  // output.gather_particles a message, so rank 0 holds at most one message of them beside
  // its own; alone, or with every particle here and current, rank 0 passes its arrays whole.
  template <class Store>
  using StatePiece = std::function<void(const Store&, std::size_t first, std::size_t count)>;
  void stream_state(const StatePiece<GasParticles>& gas, const StatePiece<CollisionlessParticles>& collisionless);
  // This rank's own particles, a leaf at a time: gas(store, first, count) and
  // collisionless(...) for each leaf it owns (the leaves and their particles' order are the
  // same on any number of ranks); before the first recut, a particle at a time, of the share a
  // rank in halo mode read, or else of rank 0's every particle. What a sum over the run each
  // rank takes its part of reads, with no particle sent.
  void visit_own_state(const StatePiece<GasParticles>& gas, const StatePiece<CollisionlessParticles>& collisionless) const;
  // The gas and collisionless particles (indices) of the leaves this rank owns, in the
  // run's order: what it writes of a restart set. Every particle when alone.
  std::pair<std::vector<std::size_t>, std::vector<std::size_t>> owned_particles() const;
  // Gas particles on all ranks (gas().size() when alone or while every rank holds all of them;
  // in halo mode each rank holds only the leaves it keeps current).
  std::size_t gas_count() const;
  // Collisionless particles on all ranks (as gas_count()).
  std::size_t collisionless_count() const;
  // Those of species s on all ranks (in halo mode a sum over ranks: every rank calls it).
  std::size_t collisionless_count(Species s) const;
  // The places in the run's order of this rank's gas particles `local` (indices into gas()).
  std::vector<std::size_t> run_places(const std::vector<std::size_t>& local) const;
  // The same for collisionless particles of the leaves this rank owns (indices into dark_matter()).
  std::vector<std::size_t> run_collisionless_places(const std::vector<std::size_t>& local) const;
  // Bytes and messages this rank sent since the start of the run.
  std::uint64_t bytes_sent() const;
  std::uint64_t messages_sent() const;
  std::uint64_t ghost_bytes_sent() const;  // of bytes_sent(): the ghost results, cell to cell
  std::uint64_t recut_bytes_sent() const { return recut_bytes_; }  // of bytes_sent(): halo mode's recuts

 private:
  void rebuild();
  // Every leaf this rank keeps current, to ti_current_.
  void drift_current(integration::ForceInputs force_inputs);
  void converge_density(Phase phase);
  void wake_requested();
  void collect_radiated();  // adds the cells' radiated energy of this step to the total
  void setup_star_formation();
  void remove_dissolved();      // gas marked dissolved (mass 0) leaves the arrays
  // Each module's task types, in the order the modules run; across ranks the exchanges too.
  void set_displacement_limits();
  // Per term k < terms, the sum over every particle of the run of what gas_terms(i, out) and
  // collisionless_terms(i, out) add to out[k], as one rank sums it whatever the ranks: per leaf
  // (its gas, then its collisionless particles), the leaves' sums in the order of
  // space().leaves(); in halo mode each leaf is summed by its owner.
  template <class GasTerms, class CollisionlessTerms>
  std::vector<double> sums_over_leaves(std::size_t terms, GasTerms&& gas_terms, CollisionlessTerms&& collisionless_terms) const;
  // Comoving TreePM: at ti_current_, starts a mesh step if one is due (and the first), and
  // sets the mesh's kick factors for this step (StepContext::MeshStep).
  void plan_mesh_step();
  void setup_comoving();
  void setup_periodic_gravity();
  void register_tasks();
  // Across ranks: the ghost results' sends and receives, and the exchanges around feedback
  // (EngineAcrossRanks.cpp).
  void register_exchange_tasks(int drift, int kick_close, int ghost, int force, int star_formation_done);
  void add_feedback_exchanges(int star_formation_done, int feedback_apply);
  void build_graph();
  // The leaves' neighbour lists: across ranks each finds those of its share of the leaves (by
  // slot, not by owner: every rank needs every list) and share_neighbour_lists, a collective,
  // hands them round; one rank finds all.
  void find_neighbour_lists(const ForEach& for_each);
  void share_neighbour_lists();
  std::pair<std::size_t, std::size_t> list_share(int rank) const;
  void prepare_step(IntegerTime ti);
  std::size_t activate(Phase phase);
  void run_graph(StepInfo* info);
  void guess_smoothing_lengths();
  bool mine(int c) const { return layout_.mine(c); }
  bool keeps_current(int c) const { return layout_.keeps_current(c); }
  // Whether leaf c's collisionless particles are in this rank's arrays (halo mode: its owner's only).
  bool holds_collisionless(int c) const { return !layout_.halo_mode() || layout_.mine(c); }
  std::vector<std::pair<Vec3, double>> measured_work() const;  // (leaf centre, task ns) over all ranks
  void plan_ghost_exchange();
  void post_receives();
  void poll_receives(std::span<const int> waiting, std::vector<int>& opened);  // the recv gates
  void sync_owned_cells(bool gas_cells_only);  // every rank's active cells to every other rank
  void sync_feedback_sites();
  // Each rank's active leaves (every leaf if asked; with gas, if asked), packed by `pack`, to every other rank.
  template <class Pack, class Unpack>
  void exchange_active_leaves(bool gas_leaves_only, std::vector<char>& buffer, Pack&& pack, Unpack&& unpack,
                              const char* what, bool every_leaf = false);
  void finish_exchanges();
  template <class Store>
  void stream_store(Store& store, const StatePiece<Store>& consume);  // stream_state's, in halo mode
  void combine_wake_requests();  // the limiter's requests of every rank, combined on every rank
  // Calls fn(i) for each gas particle of the leaves drifted in this run of the graph (that
  // this rank holds): the force loop asks to wake only neighbours of active particles, which
  // are drifted.
  template <class F>
  void for_each_drifted_gas(F&& fn) const {
    for (int c : space_.leaves()) {
      if (!drifted_[static_cast<std::size_t>(c)] || !keeps_current(c)) continue;
      const Cell& cell = space_.cell(c);
      for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) fn(i);
    }
  }
  void add_measured_costs();
  // Halo mode (EngineHaloRecut.cpp): the recut across ranks. Each rank sends the particles it
  // owns to their new top cells' owners, which build those top cells' octrees and share the
  // cells; this rank's arrays then hold the particles it owns, in the run's order.
  void recut_across_ranks(const std::vector<std::pair<Vec3, double>>& measured, const ForEach& for_each);
  // Then, once the holders are known, this rank's arrays: its own leaves' particles (which
  // the recut left in them) and copies of the other leaves it reads, from their owners, all in
  // the run's order.
  void hold_leaves();
  std::vector<int> leaves_in_run_order() const;  // halo mode: by run_first_
  // Halo mode with star formation (EngineHaloStarFormation.cpp): the tallies of the leaves
  // that formed stars, from their owners to every rank.
  void gather_leaf_tallies();
  // Spawning and dissolving across ranks, in the run's order as one rank's loop goes, in
  // rounds of each owner's consecutive events; the changed particles go to every holder.
  // Returns whether any particle was created or dissolved (alike on every rank).
  bool spawn_and_dissolve_across_ranks();
  // Sends each rank q the particles to[q] (indices into gas_), each after what `header`
  // writes of it, in rounds of at most a bounded number of particles, so that no message
  // grows with the run. The arrivals join the arrays' end (room for all made at once):
  // `arrived(q, at, n, reader)` reads the headers of n particles from q, which are unpacked
  // into at, at + 1, ... after it returns.
  template <class Store>
  void send_in_rounds(Store& store, const std::vector<std::vector<std::size_t>>& to,
                      const std::function<void(std::size_t, MessageWriter&)>& header,
                      const std::function<void(int, std::size_t, std::size_t, MessageReader&)>& arrived);
  // Which step end a particle of bin `bin` whose step began at ti_begin is due at, seen from
  // a recut at ti_current_.
  IntegerTime due_end(TimeBin bin, IntegerTime ti_begin) const;
  void exchange_halo();
  // One all-to-all: `pack(q, w)` writes what goes to rank q, `unpack(r, reader)` reads what
  // rank r sent, which it must take whole (`what` names it if not).
  void exchange_with_ranks(const std::function<void(int, MessageWriter&)>& pack,
                           const std::function<void(int, MessageReader&)>& unpack, const char* what);
  // All-to-alls in rounds of bounded size: each rank sends every rank, for each of its own
  // leaves (in the order of `leaves`) that `travels`, what `pack(q, c, w)` writes, and
  // `unpack(r, c, reader)` reads what rank r wrote of its leaf c.
  void exchange_leaves_in_rounds(const std::vector<int>& leaves, const std::function<bool(int)>& travels,
                                 const std::function<void(int, int, MessageWriter&)>& pack,
                                 const std::function<void(int, int, MessageReader&)>& unpack, const char* what);

  RunConfig config_;
  GasParticles gas_;
  CollisionlessParticles dm_;
  Space space_;
  TimeLine timeline_;
  StepTasks tasks_;
  int send_type_ = -1, recv_type_ = -1;  // across ranks
  tasks::TaskGraph graph_;
  tasks::Executor executor_;
  std::unique_ptr<StepContext> ctx_;
  // Comoving runs: the expansion and the timeline in ln a (null otherwise).
  std::unique_ptr<cosmology::Background> background_;
  std::unique_ptr<cosmology::IntegrationFactors> expansion_factors_;
  std::unique_ptr<ComovingTimeLine> comoving_;
  std::unique_ptr<cooling::CoolingTable> cooling_table_;
  std::unique_ptr<cooling::RadiativeCooling> cooling_;
  std::vector<tasks::TaskRecord> records_;
  tasks::TaskGraph records_graph_;  // the graph of records_ once graph_ was rebuilt
  bool records_stale_ = false;
  std::vector<char> cell_active_;
  std::vector<double> moved_;  // per cell: how far its particles moved since the rebuild (prepare_step)
  std::vector<std::pair<int, int>> cell_tasks_;  // each leaf's tasks: [first, second)
  std::vector<std::vector<int>> leaf_tasks_;     // per task type, per cell: its task (-1: none)
  std::vector<std::vector<int>> step_task_ids_;  // per task type: the per-step tasks
  std::vector<char> listed_;  // step_tasks_ as flags per task (the urgent tasks' search)
  std::vector<int> step_tasks_;                  // the tasks the current step runs
  bool feedback_sites_anywhere_ = true;  // across ranks: some rank has a feedback site this step
  std::unique_ptr<star_formation::StarFormationState> sf_;
  std::unique_ptr<feedback::FeedbackState> fb_;  // with star formation
  star_formation::StarFormationTally sf_total_, sf_last_step_;
  std::uint64_t next_id_ = 0;  // for spawned stars
  double radiated_ = 0.0;
  IntegerTime ti_current_ = 0;
  IntegerTime ti_step_begin_ = 0;
  long long steps_ = 0;
  long long h_capped_steps_ = 0;  // steps whose h solve was capped by a cell's reach
  long long h_max_capped_steps_ = 0, h_max_capped_particles_ = 0;  // held at hydro.h_max, short of neighbours
  long long h_min_held_particles_ = 0;  // held at the floor of h (hydro.h_min_ratio), with more neighbours
  long long msph_decoupled_ = 0;        // force interactions the MSPH rule dropped
  bool rebuild_pending_ = true;
  bool initialised_ = false;  // the first forces and timesteps are done
  std::function<void()> after_rebuild_;
  bool record_timeline_ = false;

  std::unique_ptr<domain::RankExchange> ranks_;   // null when running alone
  std::unique_ptr<CollectivesOverRanks> collectives_;  // the gravity tree's and the group finders', across ranks
  int gravity_tree_type_ = -1;  // the gravity tree task's type (-1: no gravity)
  TreeAssembly tree_assembly_;
  domain::RankLayout layout_;               // who owns and who keeps each leaf
  std::vector<std::vector<int>> send_to_;   // per cell: the ranks its ghost results go to this run
  std::vector<int> recv_handle_;            // per cell: its posted receive this run (-1: none)
  std::vector<char> need_recv_;             // per cell: this rank reads its ghost results this run
  bool ghost_exchange_ = false;             // this run of the graph sends ghost results (send_to_, need_recv_ hold)
  double graph_s_ = 0.0, exchange_s_ = 0.0, rebuild_s_ = 0.0;
  std::pair<std::int64_t, std::int64_t> last_exchange_ns_{0, 0};
  std::vector<char> gas_moved_, dm_moved_;  // per particle: active in this run of the graph
  std::vector<char> sync_buffer_;           // this rank's cells, packed for the others
  std::vector<char> wake_buffer_;           // this rank's wake requests, packed for the others
  std::vector<char> lists_buffer_;          // this rank's share of the neighbour lists, packed for the others
  // Halo mode: where each cell's gas particles start in the run's order (cell.first is where
  // they start in this rank's arrays, for the leaves it keeps current), and how many there are.
  std::vector<std::size_t> run_first_;
  std::size_t gas_total_ = 0;
  // The same for the collisionless particles, which only their leaf's owner holds (no loop
  // reads another leaf's): an owned leaf's lie in this rank's arrays in the run's order.
  std::vector<std::size_t> run_dm_first_;
  std::size_t dm_total_ = 0;
  // Before the first recut: the collisionless particles here are a share of the run's, with
  // their places (otherwise every rank read every one, in the run's order).
  bool dm_shared_ = false;
  std::vector<std::uint64_t> dm_share_places_;
  // Halo mode: the places in the run's order of the star particles spawned here since the
  // last recut (appended to the arrays past the owned leaves', in this order).
  std::vector<std::uint64_t> spawned_places_;
  EventRounds event_rounds_;
  // Halo mode before the first recut: this rank's arrays hold the share of the gas it read,
  // from the run's place share_first_ on (the file's order, in which one rank recuts them).
  bool holds_read_share_ = false;
  std::size_t share_first_ = 0;
  std::vector<std::uint64_t> share_places_;  // a restart's share: each particle's place
  std::vector<std::byte> permute_scratch_;  // halo mode's recut: one buffer, kept from one to the next
  // What a halo-mode recut hands on to hold_leaves.
  struct HaloRecut {
    bool everyone = false;                    // every rank held every particle (the first recut of a restart)
    bool from_shares = false;                 // each rank held the share it read (the first recut)
    std::vector<int> source;                  // then, per particle here: the rank that read it
    std::vector<std::uint64_t> place;         // per particle here: its place in the run's order before the recut
    std::vector<std::size_t> owned;           // this rank's particles (indices) in the recut's order
    std::vector<std::uint64_t> old_first;     // the leaves before the recut: where each began in the run's order
    std::vector<std::vector<int>> old_holders;  // and the ranks that held it
    bool dm_everyone = false;                 // every rank held every collisionless particle
    std::vector<std::uint64_t> dm_place;      // as place and owned, for the collisionless particles
    std::vector<std::size_t> dm_owned;
  };
  HaloRecut halo_recut_;
  std::vector<tasks::TaskRecord> mpi_records_;  // task times when no timeline is recorded
  std::uint64_t recut_bytes_ = 0;           // sent by the recuts: their inputs, the migrations
  std::vector<char> drifted_;               // per cell: drifted in this run of the graph
  std::vector<double> wake_radiated_;       // per cell: energy radiated by the wake's undoing of kicks
  // Halo mode's messages to ranks 0, 1, ... end to end in one buffer (MPI sends from it as it
  // is), with each one's size; reused.
  std::vector<char> to_ranks_;
  std::vector<std::size_t> to_rank_sizes_;
};

}  // namespace fountain
