#include "app/RunSetup.hpp"

#include <fmt/format.h>

#include <cmath>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string_view>
#include <tuple>
#include <vector>

#include <unistd.h>

#include "app/ComovingStart.hpp"
#include "app/Simulation.hpp"
#include "core/Error.hpp"
#include "core/PeriodicWrap.hpp"
#include "domain/BoundsAcrossRanks.hpp"
#include "domain/RankExchange.hpp"
#include "params/ParameterFile.hpp"

namespace fountain {

namespace fs = std::filesystem;

namespace {

// Fails early, before any work, if the output folder cannot be created or written.
void check_output_directory(const ParameterFile& params, const std::string& dir) {
  if (dir.empty()) throw InputError(fmt::format("{} is empty: name the output folder", params.where("output.directory")));
  if (params.text("output.basename").empty())
    throw InputError(fmt::format("{} is empty: snapshots need a name", params.where("output.basename")));
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw InputError(fmt::format("output directory '{}' cannot be created: {}", dir,
                                 ec ? ec.message() : "a file of that name exists"));
  // Named by process, so ranks probing one folder at once do not remove each other's probe.
  const fs::path probe = fs::path(dir) / fmt::format(".fountain_write_test_{}", static_cast<long>(::getpid()));
  {
    std::ofstream out(probe);
    if (!(out << "ok") || !out.flush())
      throw InputError(fmt::format("output directory '{}' is not writable", dir));
  }
  fs::remove(probe, ec);
}

std::string resolve_ic_path(const ParameterFile& params) {
  if (params.text("initial_conditions.file").empty())
    throw InputError(fmt::format("{} is empty: name the initial conditions file",
                                 params.where("initial_conditions.file")));
  fs::path ic = params.text("initial_conditions.file");
  if (ic.is_relative()) ic = fs::path(params.origin()).parent_path() / ic;
  return ic.lexically_normal().string();
}

// Gas particles at one position have no defined density: the smoothing length cannot
// converge. Checked before the run, where the cause can still be named (in a periodic box,
// positions are compared once folded into it: a BoxSize smaller than the particles' extent
// folds them onto each other). Across ranks that read shares of the gas, each position goes
// to one rank by a hash of its bits, so that equal ones meet; every rank then names the same
// pair, the smallest position's first two in the file's order, as one rank does.
void check_distinct_positions(const io::InitialConditions& ic, bool periodic, const std::string& path,
                              const domain::RankExchange* ranks) {
  struct Placed {
    Vec3 x;
    std::uint64_t id, row;
  };
  const std::size_t n = ic.gas.size();
  std::vector<Placed> pool;
  pool.reserve(n);
  std::vector<domain::RankExchange::Buffer> to(ranks ? static_cast<std::size_t>(ranks->size()) : 0);
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 x = periodic ? wrap_into_box(ic.gas.x[i], ic.box_size) : ic.gas.x[i];
    for (int k = 0; k < 3; ++k) x[k] += 0.0;  // -0 is 0: equal positions hash alike
    const Placed p{x, ic.gas.id[i], ic.gas_first + i};
    if (!ranks) {
      pool.push_back(p);
      continue;
    }
    std::uint64_t hash = 0x9e3779b97f4a7c15ULL;
    for (int k = 0; k < 3; ++k) {
      std::uint64_t bits;
      std::memcpy(&bits, &x[k], sizeof bits);
      hash = (hash ^ bits) * 0xff51afd7ed558ccdULL;
      hash ^= hash >> 33;
    }
    const auto q = static_cast<int>(hash % static_cast<std::uint64_t>(ranks->size()));
    if (q == ranks->rank()) {
      pool.push_back(p);
    } else {
      auto& b = to[static_cast<std::size_t>(q)];
      const auto* bytes = reinterpret_cast<const char*>(&p);
      b.insert(b.end(), bytes, bytes + sizeof p);
    }
  }
  if (ranks)
    for (const auto& in : ranks->alltoall(to)) {
      const std::size_t at = pool.size();
      pool.resize(at + in.size() / sizeof(Placed));
      if (!in.empty()) std::memcpy(static_cast<void*>(pool.data() + at), in.data(), in.size());
    }
  auto before = [](const Placed& a, const Placed& b) {
    return std::tie(a.x.x, a.x.y, a.x.z, a.row) < std::tie(b.x.x, b.x.y, b.x.z, b.row);
  };
  std::sort(pool.begin(), pool.end(), before);
  struct Coincidence {
    std::uint64_t found = 0, same = 0;
    Placed a, b;
  };
  Coincidence first{};
  for (std::size_t k = 1; k < pool.size() && !first.found; ++k) {
    if (pool[k].x != pool[k - 1].x) continue;
    first = {1, 2, pool[k - 1], pool[k]};
    while (k + 1 < pool.size() && pool[k + 1].x == pool[k - 1].x) ++k, ++first.same;
  }
  if (ranks)
    for (const auto& theirs : ranks->allgather_values(std::span<const Coincidence>(&first, 1), "coinciding gas"))
      if (theirs[0].found && (!first.found || before(theirs[0].a, first.a))) first = theirs[0];
  if (!first.found) return;
  const Vec3& x = first.a.x;
  throw InputError(fmt::format(
      "{}: gas particles ID {} and ID {}{} lie at the same position ({}, {}, {}){}, where SPH cannot give them a "
      "density{}",
      path, first.a.id, first.b.id, first.same > 2 ? fmt::format(" (and {} more)", first.same - 2) : "", x.x, x.y, x.z,
      periodic ? " once folded into the periodic box" : "",
      periodic ? fmt::format(" (is /Header/BoxSize = ({}, {}, {}) smaller than the particles' extent?)", ic.box_size.x,
                             ic.box_size.y, ic.box_size.z)
               : ""));
}

// A periodic run's particles must fit its box: ones that span more than the box (beyond the
// drift of a snapshot's last steps) mean BoxSize is not the box they were laid in. Across
// ranks that read shares, the span is of every share.
void check_fits_periodic_box(const io::InitialConditions& ic, const std::string& path,
                             const domain::RankExchange* ranks) {
  if (!(ic.box_size.x > 0 && ic.box_size.y > 0 && ic.box_size.z > 0))
    throw InputError(fmt::format("{}: periodic run needs a positive /Header/BoxSize", path));
  constexpr double kSlack = 1.1;
  Vec3 low{1e300, 1e300, 1e300}, high{-1e300, -1e300, -1e300};
  for (const auto* xs : {&ic.gas.x, &ic.dm.x})
    for (const Vec3& p : *xs)
      for (int k = 0; k < 3; ++k) low[k] = std::min(low[k], p[k]), high[k] = std::max(high[k], p[k]);
  if (ranks) domain::widen_to_every_rank(*ranks, low, high, "extent of the particles");
  for (int k = 0; k < 3; ++k) {
    const double lo = low[k], hi = high[k];
    if (hi - lo > kSlack * ic.box_size[k])
      throw InputError(fmt::format("{}: the particles span {} along {} (from {} to {}), more than the periodic box's "
                                   "side /Header/BoxSize = {}: is BoxSize in the particles' units?",
                                   path, hi - lo, "xyz"[k], lo, hi, ic.box_size[k]));
  }
  for (const auto* xs : {&ic.gas.x, &ic.dm.x})
    for (std::size_t i = 0; i < xs->size(); ++i)
      for (int k = 0; k < 3; ++k)
        if ((*xs)[i][k] < -ic.box_size[k] || (*xs)[i][k] > 2 * ic.box_size[k])
          throw InputError(fmt::format("{}: {} particle ID {} lies far outside the periodic box", path,
                                       xs == &ic.gas.x ? "gas" : "dark matter",
                                       xs == &ic.gas.x ? ic.gas.id[i] : ic.dm.id[i]));
}

// How many of the n places 0 .. n - 1 the ranks' `places` hold, together, each counted once:
// by the rank whose range holds it (rank q: [n q / R, n (q + 1) / R)).
std::uint64_t places_held(const std::vector<std::uint64_t>& places, std::uint64_t n, const domain::RankExchange& ranks) {
  if (n == 0) return 0;
  const auto nranks = static_cast<std::uint64_t>(ranks.size());
  auto first_of = [&](std::uint64_t q) { return (q * n + nranks - 1) / nranks; };
  std::vector<domain::RankExchange::Buffer> to(nranks);
  std::vector<std::uint64_t> mine;
  for (std::uint64_t p : places) {
    std::uint64_t q = p * nranks / n;
    while (q + 1 < nranks && first_of(q + 1) <= p) ++q;
    while (q > 0 && first_of(q) > p) --q;
    if (static_cast<int>(q) == ranks.rank()) {
      mine.push_back(p);
    } else {
      const auto* bytes = reinterpret_cast<const char*>(&p);
      to[q].insert(to[q].end(), bytes, bytes + sizeof p);
    }
  }
  for (const auto& in : ranks.alltoall(to)) {
    const std::size_t at = mine.size();
    mine.resize(at + in.size() / sizeof(std::uint64_t));
    if (!in.empty()) std::memcpy(mine.data() + at, in.data(), in.size());
  }
  const std::uint64_t first = first_of(static_cast<std::uint64_t>(ranks.rank()));
  std::vector<char> seen(first_of(static_cast<std::uint64_t>(ranks.rank()) + 1) - first, 0);
  long long once = 0;
  for (std::uint64_t p : mine)
    if (p - first < seen.size() && !seen[p - first]) seen[p - first] = 1, ++once;
  return static_cast<std::uint64_t>(ranks.sum(once));
}

// The pieces of a restart set the ranks read hold, together, each of the run's places once.
void check_pieces_fill_the_run(const io::RestartState& state, const std::string& path,
                               const domain::RankExchange& ranks) {
  const std::uint64_t gas = places_held(state.gas_places, state.gas_total, ranks);
  const std::uint64_t dm = places_held(state.dm_places, state.dm_total, ranks);
  if (gas != state.gas_total || dm != state.dm_total)
    throw InputError(fmt::format("{}: its pieces hold {} of {} gas and {} of {} collisionless particles", path, gas,
                                 state.gas_total, dm, state.dm_total));
}

// A restart must continue the same problem: every parameter must match but the threads
// and their pinning, the output directory (a run folder may be moved or copied and
// continued) and the task-graph and timeline dumps (diagnostics: a slow run may be resumed
// to look at it).
void check_same_parameters(const io::RestartState& state, const ParameterFile& params, const std::string& path) {
  const ParameterFile saved = ParameterFile::parse(state.parameters_yaml, path + ":/Restart/Parameters");
  constexpr std::array<std::string_view, 5> may_change = {"run.threads", "run.pin_threads", "output.directory",
                                                          "output.dump_task_graph", "output.dump_timeline_every"};
  for (const auto& [key, value] : params.values()) {
    if (std::find(may_change.begin(), may_change.end(), key) != may_change.end()) continue;
    const auto it = saved.values().find(key);
    if (it == saved.values().end() || it->second != value)
      throw InputError(fmt::format("{}: restart file was written with {} = {}, but {} says {}", path, key,
                                   it == saved.values().end() ? "(unset)" : it->second, params.origin(), value));
  }
}

}  // namespace

RunStart prepare_run(const ParameterFile& params, const RunOptions& options) {
  RunStart start;
  RunConfig& config = start.config;
  config = RunConfig::from(params);
  if (options.threads)
    config.threads = static_cast<int>(
        std::stoll(ParameterFile::check("run.threads", std::to_string(*options.threads), "option -t,--threads")));
  const std::string ic_path = resolve_ic_path(params);
  check_output_directory(params, config.output.directory);
  // Rank 0 holds the folder for the whole run; it alone writes snapshots and the master files.
  if (options.rank == 0) {
    start.lock = std::make_unique<OutputFolderLock>(config.output.directory);
    if (!start.lock->unsupported().empty()) fmt::print(stderr, "warning: {}\n", start.lock->unsupported());
    if (!start.lock->stale_holder().empty())
      fmt::print(stderr, "note: took over the lock of {} left by a run that did not end ({})\n",
                 config.output.directory, start.lock->stale_holder());
    guard_output_folder(config.output.directory, config.output.basename, {ic_path, params.origin()}, options.restart,
                        options.overwrite);
  }
  io::IcReadOptions read_options;
  read_options.cosmological = config.comoving.enabled;
  // Across ranks that each hold their own particles, each reads a share of the gas, and of a
  // restart set some of its pieces.
  std::unique_ptr<domain::RankExchange> ranks;
  if (options.ranks > 1 && config.ranks_hold_shares()) {
    ranks = domain::RankExchange::world();
    if (!ranks) throw std::logic_error("a run of several ranks found no ranks");
    read_options.share_rank = ranks->rank();
    read_options.share_ranks = ranks->size();
  }
  start.ic = io::read_initial_conditions(ic_path, read_options);
  if (ranks && config.comoving.enabled && start.ic.gas_total > 0) {
    // Each share says whether its rows give internal energies (0 is "not given"): all must,
    // or none.
    const bool rows = start.ic.gas.size() > 0;
    const long long shares = ranks->sum(rows ? 1 : 0);
    const long long given = ranks->sum(rows && start.ic.has_internal_energy ? 1 : 0);
    if (given != 0 && given != shares)
      throw InputError(fmt::format("{}: some gas particles have an internal energy and some have 0; give all or none",
                                   ic_path));
    start.ic.has_internal_energy = given > 0;
  }
  if (ranks)
    start.share = Engine::GasShare{start.ic.gas_first, start.ic.gas_total, {}, true, start.ic.dm_total, {}, start.ic.dm_first};
  io::InitialConditions& ic = start.ic;
  // A snapshot used as initial conditions carries its time: the run goes on from there.
  if (config.comoving.enabled) {
    to_comoving_variables(ic, config, params, ic_path);
  } else if (!params.was_given("run.t_begin")) {
    config.t_begin = ic.time;
    config.check_times(params, fmt::format("/Header/Time of {}", ic_path));
  } else if (ic.time != config.t_begin && options.rank == 0) {
    fmt::print(stderr, "warning: {} = {} differs from /Header/Time = {} of {}; the run starts at {}\n",
               params.where("run.t_begin"), config.t_begin, ic.time, ic_path, config.t_begin);
  }
  if (config.space.periodic) check_fits_periodic_box(ic, ic_path, ranks.get());
  check_distinct_positions(ic, config.space.periodic, ic_path, ranks.get());
  if (options.restart) {
    // The restart's particles replace those of the initial conditions, which are checked by
    // now: dropped first, so that the two never stand in memory together.
    ic.gas = GasParticles{};
    ic.dm = CollisionlessParticles{};
    io::RestartState& state = start.restart;
    state = ranks ? io::read_restart(restart_path(params), io::RestartShare{ranks->rank(), ranks->size()})
                  : io::read_restart(restart_path(params));
    check_same_parameters(state, params, restart_path(params));
    // A set is read in shares of its pieces, a file written by one rank in shares of its rows.
    start.share.reset();
    if (state.gas_shared) {
      if (!state.read_as_rows) check_pieces_fill_the_run(state, restart_path(params), *ranks);
      start.share = Engine::GasShare{state.gas_first, state.gas_total, std::move(state.gas_places), true,
                                     state.dm_total, std::move(state.dm_places), state.dm_first};
    }
    // Stars, which star formation spawns, are not in the initial conditions (a share's are
    // counted over every rank).
    const auto stars_here = static_cast<long long>(state.dm.count(Species::Star));
    const auto stars = static_cast<std::size_t>(state.gas_shared ? ranks->sum(stars_here) : stars_here);
    const std::size_t state_dm = (state.gas_shared ? state.dm_total : state.dm.size()) - stars;
    if (state_dm != ic.dm_total)
      throw InputError(fmt::format("{}: restart file holds {} dark matter particles, but the initial conditions {} "
                                   "have {}",
                                   restart_path(params), state_dm, ic_path, ic.dm_total));
    ic.gas = std::move(state.gas);
    ic.dm = std::move(state.dm);
  }
  config.space.box_size = ic.box_size;
  return start;
}

void start_engine(Engine& engine, const RunStart& start, const ParameterFile& params, const RunOptions& options,
                  bool quiet) {
  if (!options.restart) {
    engine.initialise();
    return;
  }
  const io::RestartState& state = start.restart;
  engine.restore(state.ti_current, state.steps, state.ti_step_begin, {state.mesh_step_bin, state.mesh_step_begin});
  engine.set_radiated_energy(state.radiated_energy);
  engine.set_star_formation_total(state.star_formation);
  if (state.next_particle_id > 0) engine.set_next_particle_id(state.next_particle_id);
  // A file written inside a step holds its end; the run goes on from the step's start.
  // (A comoving run's timeline reads ln a: it says a.)
  const double begin = engine.timeline().time(state.ti_step_begin);
  if (!quiet)
    fmt::print(stderr, "restarted from {} at {} = {:.6g}, step {}\n", restart_path(params),
               engine.config().comoving.enabled ? "a" : "t", engine.config().comoving.enabled ? std::exp(begin) : begin,
               engine.steps());
}

}  // namespace fountain
