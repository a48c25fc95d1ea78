#include "engine/Engine.hpp"

#include <fmt/format.h>
#include <tbb/info.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <stdexcept>

#include "core/IdealGas.hpp"
#include "core/Error.hpp"
#include "cooling/CoolingLoop.hpp"
#include "cooling/CoolingTasks.hpp"
#include "feedback/FeedbackTasks.hpp"
#include "domain/BoundsAcrossRanks.hpp"
#include "domain/RankExchange.hpp"
#include "engine/CellMessages.hpp"
#include "engine/CollectivesOverRanks.hpp"
#include "gravity/GravityLoop.hpp"
#include "gravity/GravityTasks.hpp"
#include "gravity/LongRangeForce.hpp"
#include "gravity/TreeAcrossRanks.hpp"
#include "cosmology/IntegrationFactors.hpp"
#include "hydro/HydroLoops.hpp"
#include "hydro/HydroTasks.hpp"
#include "star_formation/StarFormationLoop.hpp"
#include "star_formation/StarFormationTasks.hpp"
#include "tasks/ThreadPinning.hpp"
#include "timestep/Integration.hpp"
#include "timestep/IntegrationTasks.hpp"

namespace fountain {

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The cores of this rank's task threads, or none when threads float (the default).
std::vector<int> pinned_cpus(const RunConfig& config) {
  if (!config.pin_threads) return {};
  const int threads = config.threads > 0 ? config.threads : tbb::info::default_concurrency();
  const auto place = domain::RankExchange::node_place();
  return tasks::pinning_plan(tasks::allowed_cpus(), threads, place.rank, place.ranks);
}
}  // namespace

Engine::Engine(const RunConfig& config, GasParticles gas, CollisionlessParticles dm, std::optional<GasShare> share)
    : config_(config),
      gas_(std::move(gas)),
      dm_(std::move(dm)),
      space_(config.space),
      executor_(config.threads, pinned_cpus(config)) {
  timeline_.t_begin = config_.t_begin;
  timeline_.t_end = config_.t_end;
  gas_total_ = share ? share->total : gas_.size();
  holds_read_share_ = share.has_value();
  share_first_ = share ? share->first : 0;
  if (share) share_places_ = std::move(share->places);
  if (!share_places_.empty() && share_places_.size() != gas_.size())
    throw std::logic_error(fmt::format("a share of {} particles with {} places", gas_.size(), share_places_.size()));
  dm_shared_ = share && share->dm_shared;
  dm_total_ = dm_shared_ ? share->dm_total : dm_.size();
  if (dm_shared_) dm_share_places_ = std::move(share->dm_places);
  if (dm_shared_ && dm_share_places_.empty()) {
    dm_share_places_.resize(dm_.size());
    std::iota(dm_share_places_.begin(), dm_share_places_.end(), std::uint64_t{share->dm_first});
  }
  if (dm_shared_ && dm_share_places_.size() != dm_.size())
    throw std::logic_error(fmt::format("a share of {} collisionless particles with {} places", dm_.size(),
                                       dm_share_places_.size()));
  // Dark matter alone (a collisionless cosmological run) needs gravity; nothing at all is no run.
  if (gas_total_ == 0 && (dm_total_ == 0 || !config_.gravity.enabled)) throw InputError("no gas particles to simulate");
  if (dm_total_ > 0 && !config_.gravity.enabled)
    throw InputError(fmt::format("the initial conditions hold {} dark matter particles but gravity is off "
                                 "(set gravity.enabled: true)",
                                 dm_total_));
  ranks_ = domain::RankExchange::world();
  // A zoom's low-resolution particles soften in proportion to the high-resolution ones by
  // their mass's cube root: the reference is the lightest high-resolution particle (or, with
  // none, the lightest low-resolution one).
  for (Species kind : {Species::DarkMatter, Species::LowResDarkMatter}) {
    double lightest = 0.0;
    for (std::size_t i = 0; i < dm_.size(); ++i)
      if (dm_.species[i] == kind && (lightest == 0.0 || dm_.mass[i] < lightest)) lightest = dm_.mass[i];
    if (dm_shared_) {  // this rank's share of them: the lightest over every rank's
      const double here = lightest;
      for (const auto& theirs : ranks_->allgather_values(std::span<const double>(&here, 1), "lightest particle"))
        if (theirs[0] > 0.0 && (lightest == 0.0 || theirs[0] < lightest)) lightest = theirs[0];
    }
    if (lightest > 0.0 && config_.gravity.low_res_reference_mass == 0.0) config_.gravity.low_res_reference_mass = lightest;
  }
  ctx_.reset(new StepContext{gas_, space_, config_.hydro, config_.integration, timeline_, dm_, config_.gravity, nullptr, {}});
  if (executor_.threads() > 1)
    ctx_->in_task_for_each = [this](std::size_t n, const std::function<void(std::size_t)>& fn) {
      executor_.for_each_in_task(n, fn);
    };
  if (config_.cooling.enabled) {
    cooling_table_ = std::make_unique<cooling::CoolingTable>(config_.cooling.tables(), config_.cooling.metallicity);
    cooling_ = std::make_unique<cooling::RadiativeCooling>(*cooling_table_, config_.physical_units(),
                                                           config_.cooling.hydrogen_fraction);
    ctx_->cooling = cooling_.get();
  }
  for (std::size_t i = 0; i < gas_.size(); ++i)
    if (!(gas_.mass_initial[i] > 0.0)) gas_.mass_initial[i] = gas_.mass[i];
  // Star formation's spawning and feedback read and change particles anywhere: those runs
  // keep every rank's copy whole; every other run holds only its own cells and their halo.
  if (ranks_)
    layout_ = domain::RankLayout(ranks_->rank(), ranks_->size(), config_.ranks_hold_shares(),
                                 config_.repartition_imbalance, config_.repartition_min_steps);
  if (ranks_) ctx_->owns_leaf = [this](int c) { return layout_.mine(c); };
  ctx_->halo_mode = layout_.halo_mode();
  if (share && !layout_.halo_mode())
    throw std::logic_error("a rank read a share of the gas, but this run keeps every particle on every rank");
  // Each rank builds the tree of its own leaves' particles and assembles each step's tree
  // from it and what the other ranks send for its walks (docs/gravity.md, "Across ranks").
  if (ranks_) collectives_ = std::make_unique<CollectivesOverRanks>(*ranks_);
  if (ranks_ && config_.gravity.enabled && (config_.assemble_gravity_tree || layout_.halo_mode())) {
    ctx_->tree_messages = collectives_.get();
    if (layout_.halo_mode()) {
      ctx_->leaf_places = &run_first_;
      ctx_->leaf_dm_places = &run_dm_first_;
      ctx_->gas_total = &gas_total_;
    }
  }
  if (config_.star_formation.enabled) setup_star_formation();
  if (config_.comoving.enabled) setup_comoving();
  if (config_.gravity.enabled && config_.space.periodic) setup_periodic_gravity();
  register_tasks();
  guess_smoothing_lengths();
}

// A comoving run: the 2^56 ticks span ln a_begin .. ln a_end (the plain timeline then reads
// ln a), and the forces and criteria read the expansion at each step's time.
void Engine::setup_comoving() {
  const ComovingConfig& c = config_.comoving;
  if (std::fabs(config_.hydro.gamma - 5.0 / 3.0) > 1e-12)
    throw InputError(fmt::format("a comoving run needs hydro.gamma = 5/3 (its u' = a^2 u); it is {}", config_.hydro.gamma));
  // The matter of the expanding background gravitates; and with gravity every rank keeps every
  // particle current, which the displacement limits below read.
  if (!config_.gravity.enabled) throw InputError("a comoving run needs gravity (gravity.enabled: true)");
  if (!config_.space.periodic) throw InputError("a comoving run needs a periodic box (initial_conditions.periodic: true)");
  // H0 = 100 km/s/Mpc in the run's units: exactly 100 in the default h-scaled units.
  background_ = std::make_unique<cosmology::Background>(c.cosmology, cosmology::hubble0_in(config_.units));
  expansion_factors_ = std::make_unique<cosmology::IntegrationFactors>(*background_, config_.hydro.gamma, c.a_begin, c.a_end);
  comoving_ = std::make_unique<ComovingTimeLine>(*expansion_factors_);
  timeline_.t_begin = std::log(c.a_begin);
  timeline_.t_end = std::log(c.a_end);
  ctx_->comoving = comoving_.get();
  ctx_->set_time(0);
  if (comoving_->bin_for(config_.integration.dt_max, 0, config_.integration.max_dln_a) < 0)
    throw InputError(fmt::format("time_integration.dt_max = {} is shorter than one tick of the timeline in ln a from "
                                 "a = {} to {}; raise it or shorten the run",
                                 config_.integration.dt_max, c.a_begin, c.a_end));
}

// GADGET-2's MaxRMSDisplacementFac: the RMS particle moves at most this fraction of a length
// (a species' spacing, or the mesh's r_s) in a step.
constexpr double kRmsDisplacementFactor = 0.25;

// The RMS-displacement limit of a comoving run (GADGET-2's MaxRMSDisplacementFac): per
// species s, dt <= C a^2 d_s / v'_rms,s with d_s = (m_min,s / (Omega_s rho_crit0))^(1/3) the
// mean spacing of its lightest particles, so that no species moves, on average, more than a
// quarter of its spacing in a step. Recomputed at each recut, as GADGET does at each domain
// decomposition, from every particle, summed as one rank sums them (sums_over_leaves).
void Engine::set_displacement_limits() {
  const cosmology::CosmologyParams& c = config_.comoving.cosmology;
  const double rho_crit = 3.0 * background_->hubble0() * background_->hubble0() /
                          (8.0 * std::numbers::pi * config_.gravity.G);
  const double a = comoving_->scale_factor(static_cast<double>(ti_current_));
  // Per species: the sum of v'^2 and the count of particles with mass (the dark matter of the
  // high-resolution species only), and the smallest mass.
  constexpr double kNone = std::numeric_limits<double>::infinity();
  double m_gas = kNone, m_dm = kNone;
  auto dm_mass = [&](std::size_t i) { return dm_.species[i] == Species::DarkMatter ? dm_.mass[i] : 0.0; };
  const std::vector<double> sums = sums_over_leaves(
      4,
      [&](std::size_t i, double* out) {
        if (!(gas_.mass[i] > 0.0)) return;
        m_gas = std::min(m_gas, gas_.mass[i]);
        out[0] += dot(gas_.v_full[i], gas_.v_full[i]);
        out[1] += 1.0;
      },
      [&](std::size_t i, double* out) {
        if (!(dm_mass(i) > 0.0)) return;
        m_dm = std::min(m_dm, dm_mass(i));
        out[2] += dot(dm_.v_full[i], dm_.v_full[i]);
        out[3] += 1.0;
      });
  if (layout_.halo_mode())
    for (double* m : {&m_gas, &m_dm})
      for (double theirs : from_every_rank(*m)) *m = std::min(*m, theirs);
  auto limit = [&](double v2, double count, double m_min, double omega) {
    if (count == 0.0 || !(v2 > 0.0) || !(omega > 0.0)) return kNone;
    const double spacing = std::cbrt(m_min / (omega * rho_crit));
    return kRmsDisplacementFactor * a * a * spacing / std::sqrt(v2 / count);
  };
  const double omega_dm = gas_count() > 0 ? c.omega_m - c.omega_b : c.omega_m;
  const double omega_gas = collisionless_count() > 0 ? c.omega_b : c.omega_m;
  ctx_->dt_rms_gas = limit(sums[0], sums[1], m_gas, omega_gas);
  ctx_->dt_rms_dark_matter = limit(sums[2], sums[3], m_dm, omega_dm);
}

template <class GasTerms, class CollisionlessTerms>
std::vector<double> Engine::sums_over_leaves(std::size_t terms, GasTerms&& gas_terms,
                                             CollisionlessTerms&& collisionless_terms) const {
  const std::vector<int>& leaves = space_.leaves();
  std::vector<double> partial(leaves.size() * terms, 0.0);
  for (std::size_t l = 0; l < leaves.size(); ++l) {
    const int c = leaves[l];
    if (!holds_collisionless(c)) continue;  // halo mode: the owner sums a leaf
    const Cell& cell = space_.cell(c);
    double* out = partial.data() + l * terms;
    for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) gas_terms(i, out);
    for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i) collisionless_terms(i, out);
  }
  if (layout_.halo_mode()) {
    const auto all = ranks_->allgather_values(std::span<const double>(partial), "sums over leaves");
    for (std::size_t l = 0; l < leaves.size(); ++l) {
      const auto& owners = all[static_cast<std::size_t>(layout_.owner(leaves[l]))];
      std::copy_n(owners.begin() + static_cast<std::ptrdiff_t>(l * terms), terms,
                  partial.begin() + static_cast<std::ptrdiff_t>(l * terms));
    }
  }
  std::vector<double> total(terms, 0.0);
  for (std::size_t l = 0; l < leaves.size(); ++l)
    for (std::size_t k = 0; k < terms; ++k) total[k] += partial[l * terms + k];
  return total;
}

// GADGET-2's separate long-range step (docs/physics.md §11, "The mesh step"): the mesh force is
// recomputed only when every particle is synchronised at the end of the mesh step, whose
// length keeps the RMS particle from moving more than a quarter of r_s (dt <= C a^2 r_s /
// v'_rms over all particles), within the largest step in ln a and dt_max.
void Engine::plan_mesh_step() {
  StepContext::MeshStep& m = ctx_->mesh_step;
  m.due = false;
  m.close_kick = m.open_kick = m.predict_kick = 0.0;
  if (!comoving_ || !ctx_->long_range) return;
  const double now = static_cast<double>(ti_current_);
  if (m.active() && ti_current_ != m.ti_end()) {
    m.predict_kick = comoving_->gravity_kick(m.midpoint(), now);
    return;
  }
  const double v2 = sums_over_leaves(
      1, [&](std::size_t i, double* out) { out[0] += dot(gas_.v_full[i], gas_.v_full[i]); },
      [&](std::size_t i, double* out) { out[0] += dot(dm_.v_full[i], dm_.v_full[i]); })[0];
  const double n = static_cast<double>(gas_count() + collisionless_count());
  const double a = comoving_->scale_factor(now);
  const double v_rms = n > 0.0 ? std::sqrt(v2 / n) : 0.0;
  const double dt = v_rms > 0.0 ? kRmsDisplacementFactor * a * a * ctx_->long_range->mesh.split().r_s / v_rms
                                : std::numeric_limits<double>::infinity();
  const int bin = std::min(comoving_->bin_for(std::min(dt, config_.integration.dt_max), ti_current_, config_.integration.max_dln_a),
                           TimeLine::largest_aligned_bin(ti_current_));
  if (bin < 0)
    throw InputError(fmt::format("the mesh step at a = {} would be shorter than one tick of the timeline in ln a",
                                 comoving_->scale_factor(now)));
  const double last_mid = m.active() ? m.midpoint() : now;
  m.bin = bin;
  m.ti_begin = ti_current_;
  m.due = true;
  m.close_kick = comoving_->gravity_kick(last_mid, now);
  m.open_kick = comoving_->gravity_kick(now, now + 0.5 * static_cast<double>(TimeLine::step_ticks(bin)));
}

Engine::MeshStepState Engine::mesh_step() const { return {ctx_->mesh_step.bin, ctx_->mesh_step.ti_begin}; }

Engine::MeshShare Engine::mesh_share() const {
  if (!ctx_->long_range) return {};
  const gravity::PeriodicMesh& mesh = ctx_->long_range->mesh;
  return {mesh.cells(), mesh.planes(), mesh.bytes()};
}

// TreePM in a periodic box (docs/gravity.md, "Periodic TreePM"): the mesh is a cube over the
// box, so the box must be one.
void Engine::setup_periodic_gravity() {
  const Vec3 box = config_.space.box_size;
  if (!(box.x == box.y && box.y == box.z))
    throw InputError(fmt::format("gravity in a periodic box needs a cubic box (the TreePM mesh is a cube); "
                                 "/Header/BoxSize is ({}, {}, {})",
                                 box.x, box.y, box.z));
  const int cells = gravity::LongRangeForce::choose_cells(config_.gravity.mesh_cells, gas_total_ + dm_total_);
  const double r_s = config_.gravity.split_cells * box.x / cells;
  if (!(gravity::GravitySplit{r_s}.cutoff_radius() < 0.5 * box.x))
    throw InputError(fmt::format("gravity.split_cells = {} with {} mesh cells puts the short-range cut-off (4.5 r_s = "
                                 "{}) beyond half the box ({}): use more cells or a smaller split",
                                 config_.gravity.split_cells, cells, 4.5 * r_s, 0.5 * box.x));
  // Across ranks each holds a slab of the mesh's planes (collective: every rank is here).
  ctx_->long_range = std::make_unique<gravity::LongRangeForce>(cells, box.x, r_s, config_.gravity.G,
                                                               ranks_ ? gravity::MeshSlabs::world(cells) : nullptr);
  ctx_->long_range->mesh.set_round_bytes(config_.message_bytes);
}

void Engine::register_tasks() {
  const integration::IntegrationTaskTypes step = integration::register_tasks(tasks_, *ctx_);
  const hydro::HydroTaskTypes sph = hydro::register_tasks(tasks_, *ctx_, step.drift, step.kick_close);
  gravity::GravityTaskTypes gravity_types;
  if (config_.gravity.enabled) gravity_types = gravity::register_tasks(tasks_, *ctx_, step.drift);
  if (cooling_) cooling::register_tasks(tasks_, *ctx_);
  int star_formation_done = -1;
  if (sf_) {
    const auto formation = star_formation::register_tasks(tasks_, *ctx_, *sf_, *fb_);
    const auto feedback = feedback::register_tasks(tasks_, *ctx_, *fb_, formation.done);
    star_formation_done = formation.done;
    // In halo mode there are no sites (RunConfig::ranks_hold_shares): nothing to exchange.
    if (ranks_ && !layout_.halo_mode()) add_feedback_exchanges(formation.done, feedback.apply);
  }
  if (ranks_ && gravity_types.mesh >= 0 && star_formation_done >= 0) {
    // The mesh's messages and the end of star formation's are collectives: every rank must
    // reach them in the same order, or each could wait in one for the other.
    tasks_.link([mesh = gravity_types.mesh, done = star_formation_done](GraphBuilder& g) {
      g.depends(g.step_tasks(mesh).front(), g.step_tasks(done).front());
    });
  }
  gravity_tree_type_ = gravity_types.tree;
  if (ctx_->tree_messages && gravity_types.tree >= 0) {
    // The tree's assembly is a collective too: after the mesh's, before star formation's end.
    tasks_.link([types = gravity_types, done = star_formation_done](GraphBuilder& g) {
      const int tree = g.step_tasks(types.tree).front();
      if (types.mesh >= 0) g.depends(g.step_tasks(types.mesh).front(), tree);
      if (done >= 0) g.depends(tree, g.step_tasks(done).front());
    });
  }
  if (ranks_) register_exchange_tasks(step.drift, step.kick_close, sph.ghost, sph.force, star_formation_done);
}


Engine::~Engine() = default;

void Engine::setup_star_formation() {
  const StarFormationParams& p = config_.star_formation;
  sf_ = std::make_unique<star_formation::StarFormationState>();
  sf_->params = p;
  // Thresholds and rates are physical: in a comoving run's h-scaled units the conversions to cgs carry h.
  const Units units = config_.physical_units();
  sf_->law = {p.efficiency, p.density_threshold(units), p.temperature_threshold, config_.gravity.G};
  fb_ = std::make_unique<feedback::FeedbackState>();
  fb_->params = config_.feedback;
  fb_->t_star = p.temperature_threshold;
  fb_->energy_per_mass = config_.feedback.energy_per_mass(units);
  if (cooling_) {
    const cooling::RadiativeCooling* c = cooling_.get();
    sf_->temperature = [c](double u) { return c->temperature(u); };
    fb_->energy_at = [c](double t) { return c->energy_at(t); };
  } else {
    // Fully ionised primordial gas, as the diagnostics assume: T is proportional to u.
    const double factor = ideal_gas_kelvin_per_energy(units, config_.hydro.gamma);
    sf_->temperature = [factor](double u) { return factor * u; };
    fb_->energy_at = [factor](double t) { return t / factor; };
  }
  fb_->temperature = sf_->temperature;
  fb_->cold = {0.1 * sf_->law.rho_threshold, fb_->energy_at(2.0 * p.temperature_threshold)};
  for (auto i : gas_.id) next_id_ = std::max<std::uint64_t>(next_id_, i + 1);
  for (auto i : dm_.id) next_id_ = std::max<std::uint64_t>(next_id_, i + 1);
  if (ranks_ && layout_.halo_mode())  // each rank has read a share of the particles
    for (const auto& theirs : ranks_->allgather_values(std::span<const std::uint64_t>(&next_id_, 1), "largest particle ID"))
      next_id_ = std::max(next_id_, theirs[0]);
}

double Engine::scale_factor() const { return comoving_ ? comoving_->scale_factor(static_cast<double>(ti_current_)) : 1.0; }
double Engine::cosmic_time() const { return comoving_ ? comoving_->cosmic_time(0.0, static_cast<double>(ti_current_)) : time(); }
double Engine::cosmic_step(int bin) const {
  if (!comoving_) return timeline_.step(bin);
  const double now = static_cast<double>(ti_current_);
  return comoving_->cosmic_time(now, now + static_cast<double>(TimeLine::step_ticks(bin)));
}

IntegerTime Engine::to_ticks(double t) const {
  const double ticks = std::round((t - timeline_.t_begin) / timeline_.time_base());
  return static_cast<IntegerTime>(std::clamp(ticks, 0.0, static_cast<double>(TimeLine::ticks)));
}

void Engine::guess_smoothing_lengths() {
  bool missing = false;
  for (double h : gas_.h) missing = missing || !(h > 0.0);
  // Ranks that read shares guess alike, from the extent of every share.
  if (holds_read_share_) missing = ranks_->any(missing);
  if (!missing) return;
  double guess = config_.smoothing_length_guess;
  if (!(guess > 0.0)) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    Vec3 lo{inf, inf, inf}, hi{-inf, -inf, -inf};
    for (const auto& x : gas_.x)
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], x[k]), hi[k] = std::max(hi[k], x[k]);
    if (holds_read_share_) domain::widen_to_every_rank(*ranks_, lo, hi, "extent of the gas");
    Vec3 ext = config_.space.periodic ? config_.space.box_size : hi - lo;
    const double longest = std::max({ext.x, ext.y, ext.z});
    for (int k = 0; k < 3; ++k) ext[k] = std::max(ext[k], 1e-3 * longest);
    const double volume = ext.x * ext.y * ext.z;
    guess = std::cbrt(3.0 * config_.hydro.neighbours * volume / (4.0 * M_PI * static_cast<double>(gas_total_)));
  }
  for (double& h : gas_.h)
    if (!(h > 0.0)) h = guess;
}

void Engine::rebuild() {
  const auto t_rebuild = std::chrono::steady_clock::now();
  // Every particle must sit at the current time before cells are recut.
  drift_current(integration::ForceInputs::Later);
  remove_dissolved();
  // Measured before the recut, while the cells it was measured in still stand.
  const std::vector<std::pair<Vec3, double>> measured = ranks_ ? measured_work() : std::vector<std::pair<Vec3, double>>{};
  const ForEach for_each = [this](std::size_t n, const std::function<void(std::size_t)>& fn) { executor_.for_each(n, fn); };
  const std::uint64_t bytes_before = ranks_ ? ranks_->traffic().bytes : 0;
  // Particles are about to be reordered, so no tree survives the rebuild: dropped before the
  // recut and the holders' copies rather than beside the new one, as they set a rank's peak.
  ctx_->tree.reset();
  ctx_->tree_across.reset();
  // In halo mode each rank holds only some of the particles: the ranks recut together, each
  // top cell built by its owner (EngineHaloRecut.cpp).
  if (layout_.halo_mode()) {
    recut_across_ranks(measured, for_each);
  } else {
    space_.recut(gas_, dm_, for_each);
  }
  ctx_->tree_current = false;
  if (ranks_ && !layout_.halo_mode()) layout_.assign_owners(space_, measured, steps_);
  if (!layout_.halo_mode()) {
    for (int c : space_.leaves()) {
      Cell& cell = space_.cell(c);
      cell.ti_drift = ti_current_;
      IntegerTime end = TimeLine::ticks;
      for (std::size_t i = cell.first; i < cell.first + cell.count; ++i)
        end = std::min(end, due_end(gas_.time_bin[i], gas_.ti_begin[i]));
      for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i)
        end = std::min(end, due_end(dm_.time_bin[i], dm_.ti_begin[i]));
      cell.ti_end_min = end;
    }
  }
  ctx_->cover_exceeded = false;
  if (config_.gravity.enabled && !ctx_->tree_messages) {
    // The new particle order needs a new gravity tree (its build is serial): it is built
    // beside the neighbour lists and the graph, which read only the cells, rather than in
    // the step's tree task, where it would hold up every walk. The lists' exchange across
    // ranks, a collective, waits for the caller's thread.
    executor_.run_beside([this] { gravity::build_tree(*ctx_); },
                         [this, &for_each] {
                           find_neighbour_lists(for_each);
                           if (!ranks_) build_graph();
                         });
    if (ranks_) {
      share_neighbour_lists();
      build_graph();
    }
    ctx_->tree_current = true;
  } else {
    find_neighbour_lists(for_each);
    share_neighbour_lists();
    build_graph();
  }
  if (layout_.halo_mode()) {
    layout_.find_holders(space_);
    hold_leaves();
    recut_bytes_ += ranks_->traffic().bytes - bytes_before;
  }
  // (In halo mode, once each leaf's particles are in place.)
  if (comoving_) set_displacement_limits();
  if (ctx_->tree_messages) {
    // Across ranks the tree's build is a collective: on this thread, after the lists', and in
    // halo mode after the holders' copies, which put each leaf's particles in place.
    gravity::build_tree(*ctx_);
    ctx_->tree_current = true;
  }
  rebuild_pending_ = false;
  rebuild_s_ += seconds_since(t_rebuild);
}

IntegerTime Engine::due_end(TimeBin bin, IntegerTime ti_begin) const {
  // A particle whose step ends now is due; one whose step began now (a rebuild between
  // steps, as for a restart file) is not, though its bin is aligned with the time too.
  const bool due = TimeLine::active(bin, ti_current_) && (!initialised_ || ti_begin != ti_current_);
  return due ? ti_current_ : TimeLine::step_end(bin, ti_current_);
}

void Engine::remove_dissolved() {
  // In halo mode the recut leaves them out (recut_across_ranks), as it reorders every array.
  if (layout_.halo_mode()) return;
  std::vector<std::size_t> keep;
  keep.reserve(gas_.size());
  for (std::size_t i = 0; i < gas_.size(); ++i)
    if (gas_.mass[i] > 0.0) keep.push_back(i);
  if (keep.size() != gas_.size()) gas_.permute(keep);
}

namespace {

// The graph being built, as the modules' linkers see it.
class EngineGraphBuilder final : public GraphBuilder {
 public:
  EngineGraphBuilder(tasks::TaskGraph& graph, const Space& space, const StepTasks& kinds,
                     const std::vector<std::vector<int>>& leaf_tasks, const std::vector<std::vector<int>>& step_tasks,
                     const std::vector<std::pair<int, int>>& cell_tasks)
      : graph_(graph), space_(space), kinds_(kinds), leaf_tasks_(leaf_tasks), step_tasks_(step_tasks),
        cell_tasks_(cell_tasks) {}
  const std::vector<int>& leaves() const override { return space_.leaves(); }
  const std::vector<int>& neighbours(int c) const override { return space_.neighbours(c); }
  int task(int type, int c) const override {
    const auto& per_cell = leaf_tasks_[static_cast<std::size_t>(type)];
    return per_cell.empty() ? -1 : per_cell[static_cast<std::size_t>(c)];
  }
  const std::vector<int>& step_tasks(int type) const override { return step_tasks_[static_cast<std::size_t>(type)]; }
  int first_after(Stage stage, int c) const override {
    const auto [begin, end] = cell_tasks_[static_cast<std::size_t>(c)];
    for (int t = begin; t < end; ++t)
      if (kinds_[graph_.task(t).type].stage > stage) return t;
    return -1;
  }
  void depends(int before, int after) override {
    if (before >= 0 && after >= 0) graph_.depends(before, after);
  }

 private:
  tasks::TaskGraph& graph_;
  const Space& space_;
  const StepTasks& kinds_;
  const std::vector<std::vector<int>>& leaf_tasks_;
  const std::vector<std::vector<int>>& step_tasks_;
  const std::vector<std::pair<int, int>>& cell_tasks_;
};

}  // namespace

void Engine::build_graph() {
  // Keep the graph the last records index into, for timelines written after this rebuild.
  if (!records_.empty() && !records_stale_) {
    records_graph_ = std::move(graph_);
    records_stale_ = true;
  }
  graph_ = tasks::TaskGraph();
  const auto& leaves = space_.leaves();
  const std::size_t ncells = space_.cells().size();
  if (fb_) fb_->cells.assign(ncells, {});
  // Each leaf's tasks in stage order (the order of registration within a stage).
  std::vector<int> leaf_kinds, step_kinds;
  for (int type = 0; type < tasks_.size(); ++type)
    (tasks_[type].scope == TaskKind::Scope::Leaf ? leaf_kinds : step_kinds).push_back(type);
  std::stable_sort(leaf_kinds.begin(), leaf_kinds.end(), [&](int a, int b) { return tasks_[a].stage < tasks_[b].stage; });
  std::size_t npairs = 0, nstep = 0;
  for (int c : leaves) npairs += space_.neighbours(c).size();
  for (int type : step_kinds) nstep += static_cast<std::size_t>(tasks_[type].parts);
  graph_.reserve(leaf_kinds.size() * leaves.size() + nstep, 3 * npairs + (3 + nstep) * leaves.size());
  leaf_tasks_.assign(static_cast<std::size_t>(tasks_.size()), {});
  step_task_ids_.assign(static_cast<std::size_t>(tasks_.size()), {});
  for (int type : step_kinds)
    for (int part = 0; part < tasks_[type].parts; ++part) {
      const int t = graph_.add(type, -1, -1, -1);
      graph_.task(t).part = tasks_[type].parts > 1 ? part : -1;
      step_task_ids_[static_cast<std::size_t>(type)].push_back(t);
    }
  for (int type : leaf_kinds) leaf_tasks_[static_cast<std::size_t>(type)].assign(ncells, -1);
  cell_tasks_.assign(ncells, {-1, -1});
  for (int c : leaves) {
    cell_tasks_[c].first = graph_.size();
    const bool has_gas = space_.cell(c).count > 0;
    for (int type : leaf_kinds) {
      const TaskKind& kind = tasks_[type];
      if (kind.gas_leaves_only && !has_gas) continue;
      leaf_tasks_[static_cast<std::size_t>(type)][static_cast<std::size_t>(c)] =
          graph_.add(type, c, -1, kind.writes_leaf ? c : -1);
    }
    cell_tasks_[c].second = graph_.size();
  }
  EngineGraphBuilder builder(graph_, space_, tasks_, leaf_tasks_, step_task_ids_, cell_tasks_);
  for (const auto& link : tasks_.linkers()) link(builder);
  graph_.finalize();
}

void Engine::drift_current(integration::ForceInputs force_inputs) {
  ctx_->set_time(ti_current_);
  const auto& leaves = space_.leaves();
  if (leaves.empty()) return;  // before the first rebuild: nothing has moved
  StepContext& ctx = *ctx_;
  if (!layout_.halo_mode()) {
    executor_.for_each(leaves.size(), [&](std::size_t l) { integration::drift(ctx, leaves[l], force_inputs); });
    return;
  }
  std::vector<int> held;  // not only this rank's own leaves (`mine`): every leaf it holds
  for (int c : leaves)
    if (layout_.keeps_current(static_cast<std::size_t>(c))) held.push_back(c);
  executor_.for_each(held.size(), [&](std::size_t l) { integration::drift(ctx, held[l], force_inputs); });
}

void Engine::drift_all() {
  drift_current(integration::ForceInputs::Drift);
}

std::size_t Engine::activate(Phase phase) {
  const auto& leaves = space_.leaves();
  const std::size_t ncells = space_.cells().size();
  cell_active_.assign(ncells, 0);
  std::vector<char>& needs_drift = drifted_;
  needs_drift.assign(ncells, 0);
  std::size_t active_particles = 0;
  // A task that reads every particle (gravity's tree) needs every leaf at the current time.
  bool every_leaf = false;
  for (int type = 0; type < tasks_.size(); ++type)
    every_leaf = every_leaf || (tasks_[type].reads_every_leaf && runs_in(tasks_[type].stage, phase));
  for (int c : leaves) {
    if (every_leaf) needs_drift[c] = 1;
    if (space_.cell(c).ti_end_min != ti_current_) continue;
    cell_active_[c] = 1;
    needs_drift[c] = 1;
    for (int n : space_.neighbours(c)) needs_drift[n] = 1;
  }
  // Across ranks, the particles active now are the ones whose state the owner's tasks change
  // (flagged before any bin changes, so every rank flags the same).
  if (ranks_) {
    gas_moved_.assign(gas_.size(), 0);
    dm_moved_.assign(dm_.size(), 0);
  }
  for (int c : leaves)
    if (cell_active_[c] && keeps_current(c)) {
      const Cell& cell = space_.cell(c);
      // In halo mode the holders of a leaf see its particles too: only the owner counts them.
      const bool count = !layout_.halo_mode() || mine(c);
      for (std::size_t i = cell.first; i < cell.first + cell.count; ++i) {
        const bool a = ctx_->is_active(i);
        active_particles += a && count ? 1 : 0;
        if (ranks_) gas_moved_[i] = a;
      }
      if (!holds_collisionless(c)) continue;
      for (std::size_t i = cell.dm_first; i < cell.dm_first + cell.dm_count; ++i) {
        const bool a = ctx_->is_active_dm(i);
        active_particles += a && count ? 1 : 0;
        if (ranks_) dm_moved_[i] = a;
      }
    }
  if (layout_.halo_mode()) active_particles = static_cast<std::size_t>(ranks_->sum(static_cast<long long>(active_particles)));
  // Only the tasks of active cells (and the drifts of their neighbours) are listed for the
  // executor; every ordering between them is a direct dependency or runs through a listed
  // chain (docs/design.md), so nothing else needs to be visited.
  graph_.set_all_active(false);
  step_tasks_.clear();
  for (int type = 0; type < tasks_.size(); ++type) {
    const TaskKind& kind = tasks_[type];
    if (kind.scope != TaskKind::Scope::Step || !runs_in(kind.stage, phase)) continue;
    if (kind.before_phase) kind.before_phase();
    for (int t : step_task_ids_[static_cast<std::size_t>(type)]) {
      graph_.task(t).active = true;
      step_tasks_.push_back(t);
    }
  }
  ghost_exchange_ = ranks_ && phase != Phase::Density;
  if (ghost_exchange_) plan_ghost_exchange();
  for (int c : leaves) {
    if (!needs_drift[c]) continue;
    const auto [begin, end] = cell_tasks_[c];
    for (int t = begin; t < end; ++t) {
      auto& task = graph_.task(t);
      const TaskKind& kind = tasks_[task.type];
      switch (kind.activation) {
        case TaskKind::Activation::DriftedLeaf: task.active = keeps_current(c); break;
        case TaskKind::Activation::Custom: task.active = kind.active_if(c); break;
        case TaskKind::Activation::ActiveLeaf: task.active = cell_active_[c] && mine(c) && runs_in(kind.stage, phase);
      }
      if (task.active) step_tasks_.push_back(t);
    }
  }
  return active_particles;
}

void Engine::prepare_step(IntegerTime ti) {
  ti_current_ = ti;
  ctx_->set_time(ti);
  // How far each leaf's particles will have moved since the rebuild once drifted to ti.
  const auto& leaves = space_.leaves();
  moved_.resize(space_.cells().size());
  double moved_most = 0.0;
  for (int c : leaves) {
    const Cell& cell = space_.cell(c);
    moved_[static_cast<std::size_t>(c)] = cell.dx_max + cell.v_max * std::fabs(ctx_->drift_factor(cell.ti_drift, ti));
    moved_most = std::max(moved_most, moved_[static_cast<std::size_t>(c)]);
  }
  // A gas particle of leaf a misses no neighbour while h + dx_a + dx_b stays within the gap
  // to every leaf b off its list (that gap is at least a's cover). Leaves beyond a's
  // surroundings are at least twice the cover away: while the fastest motion anywhere fits
  // in that, only the surroundings' motion counts (the cover of a dense clump is no longer
  // spent by fast gas elsewhere).
  for (int c : leaves) {
    Cell& cell = space_.cell(c);
    // A leaf without gas has no neighbours to cover (its cover is zero).
    if (cell.count == 0) continue;
    const double dx = moved_[static_cast<std::size_t>(c)];
    double around = moved_most;
    if (1.1 * cell.h_max + dx + moved_most <= Space::surroundings_reach(cell)) {
      around = 0.0;
      for (int b : space_.surroundings(c)) around = std::max(around, moved_[static_cast<std::size_t>(b)]);
    }
    cell.dx_around = around;
    // Allow h to grow by 10% in the step before the cover runs out.
    if (1.1 * cell.h_max + dx + around > cell.r_cover) rebuild_pending_ = true;
  }
  if (rebuild_pending_) rebuild();
}

void Engine::run_graph(StepInfo* info) {
  ctx_->cover_exceeded = false;
  ctx_->h_capped = 0;
  ctx_->h_max_capped = 0;
  ctx_->h_min_held = 0;
  ctx_->msph_decoupled = 0;
  if (sf_) sf_->time = fb_->time = comoving_ ? scale_factor() : time();
  if (ranks_) post_receives();
  const StepTasks& kinds = tasks_;
  auto runner = [&kinds](const tasks::Task& t) { kinds[t.type].run(t); };
  std::vector<tasks::TaskRecord>* records = record_timeline_ ? &records_ : ranks_ ? &mpi_records_ : nullptr;
  tasks::Executor::Gates gates;
  if (ranks_) {
    for (int t : step_tasks_)
      if (graph_.task(t).type == recv_type_) gates.tasks.push_back(t);
    gates.poll = [this](std::span<const int> waiting, std::vector<int>& opened) { poll_receives(waiting, opened); };
    // What other ranks wait for goes first: the sends and what leads to them (the drifts,
    // density loops and ghosts of the cells that feed other ranks), and the gravity tree's
    // assembly, a collective that every rank's walks wait for.
    std::vector<int> sends;
    listed_.assign(static_cast<std::size_t>(graph_.size()), 0);
    for (int t : step_tasks_) {
      listed_[static_cast<std::size_t>(t)] = 1;
      const int type = graph_.task(t).type;
      if (type == send_type_ || (ctx_->tree_messages && type == gravity_tree_type_)) sends.push_back(t);
    }
    if (!sends.empty()) gates.urgent = graph_.ancestors(sends, listed_);
  }
  const auto t_graph = std::chrono::steady_clock::now();
  executor_.run(graph_, runner, records, &step_tasks_, gates.tasks.empty() && gates.urgent.empty() ? nullptr : &gates);
  graph_s_ += seconds_since(t_graph);
  records_stale_ = false;
  if (ctx_->tree_across) {
    const gravity::TreeAcrossRanksCounts& c = ctx_->tree_across->counts();
    ++tree_assembly_.assemblies;
    tree_assembly_.nodes_received += c.nodes_received;
    tree_assembly_.sources_received += c.sources_received;
  }
  if (ranks_) {
    const auto ns_since_graph = [&] {
      return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now() - t_graph).count();
    };
    last_exchange_ns_.first = ns_since_graph();
    finish_exchanges();
    last_exchange_ns_.second = ns_since_graph();
  }
  collect_radiated();
  if (info) {
    info->tasks_wall_s += 1e-9 * static_cast<double>(executor_.last_wall_ns());
    info->tasks_busy_s += 1e-9 * static_cast<double>(executor_.last_busy_ns());
    info->tasks_run += step_tasks_.size();
  }
  if (ctx_->cover_exceeded) rebuild_pending_ = true;
  // Warnings that can recur every few steps: the first ten such steps are printed, then
  // every 1000th; `steps` counts them.
  auto warn_step = [&](long long& steps, const std::string& what) {
    ++steps;
    if (layout_.rank() == 0 && (steps <= 10 || steps % 1000 == 0))
      fmt::print(stderr, "warning: {} ({} such steps{})\n", what, steps,
                 steps == 10 ? "; from here on every 1000th is printed" : "");
  };
  // Harmless: the cells are recut and the next step solves h in full.
  // A comoving run's clock reads ln a: its messages say a.
  const std::string when = comoving_ ? fmt::format("a = {:.6g}", scale_factor()) : fmt::format("t = {}", time());
  if (info && ctx_->h_capped > 0)
    warn_step(h_capped_steps_, fmt::format("{} particles had h capped by their cell's reach at {}; rebuilding",
                                           ctx_->h_capped.load(), when));
  // Not harmless: these particles keep fewer neighbours than hydro.neighbours, so their
  // density is overestimated. Counted for the run's summary too.
  h_min_held_particles_ += ctx_->h_min_held;
  msph_decoupled_ += ctx_->msph_decoupled;
  if (ctx_->h_max_capped > 0) {
    h_max_capped_particles_ += ctx_->h_max_capped;
    warn_step(h_max_capped_steps_,
              fmt::format("{} particles were held at hydro.h_max = {} at {} with fewer than hydro.neighbours = {} "
                          "neighbours, so their densities are too high",
                          ctx_->h_max_capped.load(), config_.hydro.h_max, when, config_.hydro.neighbours));
  }
}

void Engine::initialise() {
  // Every particle is active at t = 0 whatever its bin. The placeholder is the largest bin,
  // so the first timestep is not held down by the limiter comparing with placeholders (the
  // first force loop's wake requests then bring slow neighbours of fast particles down).
  const int dt_max_bin = comoving_ ? comoving_->bin_for(config_.integration.dt_max, 0, config_.integration.max_dln_a)
                                   : timeline_.bin_for(config_.integration.dt_max);
  const TimeBin start = static_cast<TimeBin>(std::max(0, dt_max_bin));
  for (auto& b : gas_.time_bin) b = start;
  for (auto& b : dm_.time_bin) b = start;
  ti_current_ = 0;
  for (auto& t : gas_.ti_begin) t = 0;
  for (auto& t : dm_.ti_begin) t = 0;
  rebuild_pending_ = true;
  // A first density pass gives the MSPH rule real densities to compare; it is repeated
  // (with the cells recut) until every h fits in its cell's reach.
  converge_density(Phase::Density);
  prepare_step(0);
  ctx_->mesh_step = {};
  plan_mesh_step();
  if (config_.gravity.enabled) {
    // The relative opening criterion needs a previous acceleration: a first pass with the
    // Barnes-Hut criterion gives it (as in GADGET-2).
    activate(Phase::Hydro);
    ctx_->first_forces = true;
    run_graph(nullptr);
    ctx_->first_forces = false;
  }
  activate(Phase::Full);
  run_graph(nullptr);
  wake_requested();
  initialised_ = true;
  finish_star_formation();
}

void Engine::rebuild_now() {
  rebuild_pending_ = true;
  prepare_step(ti_current_);
}

void Engine::restore(IntegerTime ti_current, long long steps, IntegerTime ti_step_begin, MeshStepState mesh_step) {
  initialised_ = true;
  ctx_->mesh_step.bin = mesh_step.bin;
  ctx_->mesh_step.ti_begin = mesh_step.ti_begin;
  ti_current_ = ti_current;
  ti_step_begin_ = ti_step_begin;
  steps_ = steps;
  rebuild_now();
  // The file written at the start holds the particles as initialise() left them: the tree
  // their recut built was refit by its force passes, so the first step refits it too, rather
  // than keeping it as if the recut had come at that step's start. (A file written at a later
  // recut is restored to the very point it was written at, tree and all.)
  if (steps == 0) ctx_->tree_current = false;
}

void Engine::wake_requested() {
  if (!config_.hydro.timestep_limiter) return;
  StepContext& ctx = *ctx_;
  const auto& leaves = space_.leaves();
  if (layout_.halo_mode()) {
    // The owners woke their leaves in the exchange after the graph (exchange_halo); what the
    // undone kicks radiated is added here, as one rank adds it.
    for (int c : leaves) space_.cell(c).radiated = wake_radiated_[static_cast<std::size_t>(c)];
  } else {
    executor_.for_each(leaves.size(), [&](std::size_t l) { integration::wake(ctx, leaves[l]); });
  }
  collect_radiated();
}

void Engine::collect_radiated() {
  if (!cooling_) return;
  for (int c : space_.leaves()) {  // in a fixed order, so the total is reproducible
    radiated_ += space_.cell(c).radiated;
    space_.cell(c).radiated = 0.0;
  }
}

void Engine::finish_star_formation() {
  if (!sf_) return;
  star_formation::StarFormationTally step = fb_->step_tally;
  fb_->step_tally = {};
  if (layout_.halo_mode()) gather_leaf_tallies();
  for (int c : space_.leaves()) {  // in a fixed order, so the sums are reproducible
    auto& cf = fb_->cells[static_cast<std::size_t>(c)];
    step += cf.tally;
    cf.tally = {};
  }
  const bool changed = layout_.halo_mode() ? spawn_and_dissolve_across_ranks()
                                           : star_formation::spawn_and_dissolve(*ctx_, *sf_, next_id_);
  step += sf_->step_tally;
  sf_->step_tally = {};
  // New stars must join the cells and dissolved gas leave them before anything else runs;
  // a promoted particle's h may have outgrown its cell.
  if (changed || step.promotions > 0) rebuild_now();
  sf_last_step_ = step;
  sf_total_ += step;
}

void Engine::converge_density(Phase phase) {
  for (int attempt = 0; attempt < 64; ++attempt) {
    prepare_step(ti_current_);
    activate(phase);
    run_graph(nullptr);
    if (!rebuild_pending_) return;
  }
  throw InputError("smoothing lengths still outgrow their cells after 64 rebuilds: are the initial conditions sane?");
}

void Engine::compute_hydro_at(IntegerTime ti) {
  rebuild_pending_ = true;
  ti_current_ = ti_step_begin_ = ti;
  converge_density(Phase::Hydro);
}

StepInfo Engine::step(IntegerTime ti_stop) {
  const auto t0 = std::chrono::steady_clock::now();
  StepInfo info;
  IntegerTime ti_next = std::min(ti_stop, TimeLine::ticks);
  for (int c : space_.leaves()) ti_next = std::min(ti_next, space_.cell(c).ti_end_min);
  if (ti_next <= ti_current_) ti_next = ti_current_;
  // ti_current_ between steps; after a restore from inside a step, that step's start.
  const IntegerTime ti_prev = ti_step_begin_;
  const int rebuilds_before = space_.rebuild_count();
  prepare_step(ti_next);
  if (after_rebuild_ && space_.rebuild_count() != rebuilds_before) after_rebuild_();
  const int rebuilds_after_prepare = space_.rebuild_count();
  plan_mesh_step();
  info.active = activate(Phase::Full);
  if (info.active > 0) {
    run_graph(&info);
    wake_requested();
    finish_star_formation();
  }
  ti_step_begin_ = ti_current_;
  ++steps_;
  info.step = steps_;
  info.time = time();
  info.dt = timeline_.time(ti_next) - timeline_.time(ti_prev);
  info.rebuilt = space_.rebuild_count() != rebuilds_before;
  // Star formation recuts the cells at the end of a step when particles came or went.
  info.recut_at_end = space_.rebuild_count() != rebuilds_after_prepare;
  info.wall_s = seconds_since(t0);
  return info;
}

Totals Engine::totals() const {
  Totals t;
  for (std::size_t i = 0; i < gas_.size(); ++i) {
    const double m = gas_.dynamical_mass(i);
    t.mass += m;
    t.reservoir += gas_.reservoir[i];
    t.momentum += gas_.v[i] * m;
    t.kinetic += 0.5 * m * dot(gas_.v[i], gas_.v[i]);
    t.thermal += gas_.mass[i] * gas_.u[i];
    t.potential += 0.5 * m * gas_.potential[i];
  }
  for (std::size_t i = 0; i < dm_.size(); ++i) {
    const double m = dm_.mass[i];
    t.mass += m;
    t.momentum += dm_.v[i] * m;
    t.kinetic += 0.5 * m * dot(dm_.v[i], dm_.v[i]);
    t.potential += 0.5 * m * dm_.potential[i];
  }
  return t;
}

}  // namespace fountain
