#include "app/OutputSchedule.hpp"

#include "app/GroupCommand.hpp"

#include <fmt/format.h>

#include <cmath>
#include <memory>

#include "app/Simulation.hpp"
#include "core/Collectives.hpp"
#include "core/Error.hpp"

namespace fountain {

OutputSchedule::OutputSchedule(const RunConfig& config, const Engine& engine, int next_output)
    : config_(config), engine_(engine), next_(next_output) {
  ti_out_ = ticks_of(next_);
  skip_past();
}

IntegerTime OutputSchedule::ticks_of(int output) const {
  if (config_.comoving.enabled) {
    // The listed scale factors (output 1 is the first); the run's end has its own snapshot.
    const std::vector<double>& a = config_.output.scale_factors;
    if (output < 1 || static_cast<std::size_t>(output) > a.size()) return TimeLine::ticks;
    const double a_out = a[static_cast<std::size_t>(output - 1)];
    return a_out >= config_.comoving.a_end ? TimeLine::ticks : engine_.to_ticks(std::log(a_out));
  }
  const double dt_out = config_.output.delta_time;
  if (dt_out <= 0.0) return TimeLine::ticks;
  const double t = config_.t_begin + output * dt_out;
  return t >= config_.t_end ? TimeLine::ticks : engine_.to_ticks(t);
}

void OutputSchedule::skip_past() {
  while (ti_out_ <= engine_.ti_step_begin() && ti_out_ < TimeLine::ticks) ti_out_ = ticks_of(++next_);
}

void OutputSchedule::advance() {
  ti_out_ = ticks_of(++next_);
  skip_past();
}

SnapshotSeries::SnapshotSeries(const RunConfig& config, Engine& engine, TemperatureOf temperature, int written,
                               bool quiet)
    : config_(config), engine_(engine), written_(written), quiet_(quiet) {
  info_.box_size = config.space.box_size;
  info_.periodic = config.space.periodic;
  info_.units = config.units;
  info_.gamma = config.hydro.gamma;
  info_.parameters_yaml = config.parameters_yaml;
  info_.git_revision = git_revision();
  info_.build_options = build_options();
  info_.temperature = std::move(temperature);
  info_.star_formation = config.star_formation.enabled;
  if (config.comoving.enabled) info_.cosmology = config.comoving.cosmology;
}

groups::ParticleSet SnapshotSeries::own_particles() const {
  // As the snapshot stores them and `fountain fof` reads them back: velocities v' a^-3/2
  // (GADGET's v_pec / sqrt(a)), then times sqrt(a).
  const double stored = info_.cosmology ? std::pow(info_.time, -1.5) : 1.0;
  const double read = info_.cosmology ? std::sqrt(info_.time) : 1.0;
  const auto [gas, collisionless] = engine_.owned_particles();
  const GasParticles& g = engine_.gas();
  const CollisionlessParticles& c = engine_.dark_matter();
  groups::ParticleSet set;
  for (std::size_t i : gas) set.push_back(g.x[i], g.v[i] * stored * read, g.mass[i], g.id[i], 0);
  for (std::size_t i : collisionless)
    set.push_back(c.x[i], c.v[i] * stored * read, c.mass[i], c.id[i], static_cast<int>(c.species[i]));
  return set;
}

void SnapshotSeries::own_baryons(groups::ParticleSet& baryons, std::vector<double>& hidden) const {
  const groups::ParticleSet all = own_particles();
  const auto [gas, collisionless] = engine_.owned_particles();
  const GasParticles& g = engine_.gas();
  // Gas first, as own_particles() lists it; hidden stars only where a snapshot writes them.
  for (std::size_t k = 0; k < all.size(); ++k)
    if (all.type[k] == 0 || all.type[k] == 4) {
      baryons.push_back(all.x[k], all.v[k], all.mass[k], all.id[k], all.type[k]);
      hidden.push_back(k < gas.size() && info_.star_formation ? g.mass_stars_hidden[gas[k]] : 0.0);
    }
}

io::GroupInput SnapshotSeries::group_header() const {
  io::GroupInput h;
  const Vec3& box = info_.box_size;
  if (box.y != box.x || box.z != box.x)
    throw InputError("output.fof_groups: the group finders need a cubic box (space.box_size)");
  h.box = box.x;
  h.time = info_.time;
  h.units = info_.units;
  if (info_.cosmology) {
    h.omega_m = info_.cosmology->omega_m;
    h.omega_lambda = info_.cosmology->omega_lambda;
    h.hubble_param = info_.cosmology->hubble_param;
    h.omega_b = info_.cosmology->omega_b;
  }
  h.cosmological = h.omega_m > 0.0 && h.time > 0.0;
  return h;
}

void SnapshotSeries::write() {
  engine_.drift_all();
  info_.time = engine_.time();
  // A comoving run's clock reads ln a; its snapshots give a (the first and last exactly as
  // the parameters give them: exp(ln a) may differ from a in the last bit).
  if (info_.cosmology) {
    const IntegerTime ti = engine_.ti_current();
    info_.time = ti == 0                 ? config_.comoving.a_begin
                 : ti == TimeLine::ticks ? config_.comoving.a_end
                                         : std::exp(info_.time);
  }
  info_.step = engine_.steps();
  const std::string path =
      fmt::format("{}/{}_{:04d}.hdf5", config_.output.directory, config_.output.basename, written_);
  // Rank 0 writes what the particles' owners send it (its own arrays, when they are current).
  std::unique_ptr<io::SnapshotWriter> writer;
  const io::SnapshotCounts counts{engine_.gas_count(), engine_.collisionless_count(Species::DarkMatter),
                                  engine_.collisionless_count(Species::LowResDarkMatter),
                                  engine_.collisionless_count(Species::Star)};
  if (engine_.rank() == 0) writer = std::make_unique<io::SnapshotWriter>(path, info_, counts);
  engine_.stream_state([&](const GasParticles& p, std::size_t first, std::size_t n) { writer->add_gas(p, first, n); },
                       [&](const CollisionlessParticles& p, std::size_t first, std::size_t n) {
                         writer->add_collisionless(p, first, n);
                       });
  if (writer) writer->close();
  if (!quiet_) {
    if (info_.cosmology) {
      fmt::print(stderr, "snapshot {} at a = {:.6g} (z = {:.6g})\n", path, info_.time, 1.0 / info_.time - 1.0);
    } else {
      fmt::print(stderr, "snapshot {} at t = {:.6g}\n", path, info_.time);
    }
  }
  // Groups of the particles just written, as `fountain fof` and `fountain hop` would find
  // them in the snapshot, each rank with its own particles.
  const OutputConfig& out = config_.output;
  if (out.fof_groups) {
    FofRequest fof;
    fof.snapshot = path;
    fof.output = fmt::format("{}/fof_{:04d}.hdf5", out.directory, written_);
    fof.threads = config_.threads;
    const std::string line = find_groups(fof, own_particles(), group_header(), engine_.collectives());
    if (!quiet_ && engine_.rank() == 0) fmt::print(stderr, "{}\n", line);
  }
  if (out.hop_groups && counts.gas + counts.stars > 0) {
    HopRequest hop;
    hop.snapshot = path;
    hop.output = fmt::format("{}/hop_{:04d}.hdf5", out.directory, written_);
    hop.omega_b = config_.comoving.cosmology.omega_b;
    hop.threads = config_.threads;
    groups::ParticleSet baryons;
    std::vector<double> hidden;
    own_baryons(baryons, hidden);
    const std::string line = find_hop_groups(hop, baryons, hidden, group_header(), engine_.collectives());
    if (!quiet_ && engine_.rank() == 0) fmt::print(stderr, "{}\n", line);
  }
  ++written_;
}

StatisticsSeries::StatisticsSeries(const RunConfig& config, Engine& engine, TemperatureOf temperature, bool append)
    : config_(config),
      engine_(engine),
      temperature_(std::move(temperature)),
      phases_(analysis::FigurePhases::paper(config.physical_units())),
      sf_mass_before_(engine.star_formation_total().mass_formed),
      sf_time_before_(engine.cosmic_time()) {
  if (enabled() && engine.rank() == 0)
    file_ = std::make_unique<io::StatisticsFile>(config.output.directory + "/statistics.txt", append,
                                                 config.comoving.enabled);
}

void StatisticsSeries::write() {
  // Every rank sums its own particles and the sums go to rank 0, which writes: the sums are
  // exact until rounded, so the line is one rank's whatever the ranks.
  analysis::DiagnosticsSum sum(temperature_, phases_, engine_.scale_factor());
  engine_.visit_own_state([&](const GasParticles& p, std::size_t first, std::size_t n) { sum.add_gas(p, first, n); },
                          [&](const CollisionlessParticles& p, std::size_t first, std::size_t n) {
                            sum.add_collisionless(p, first, n);
                          });
  if (Collectives* ranks = engine_.collectives()) {
    const std::vector<char> mine = sum.pack();
    const std::vector<std::vector<char>> all = ranks->allgather(mine);
    if (engine_.rank() == 0)
      for (std::size_t r = 1; r < all.size(); ++r) sum.add_packed(all[r]);
  }
  if (!file_) return;
  // Physical units: a comoving run's h-scaled units divided by h (h cancels in the rate).
  const Units units = config_.physical_units();
  const double msun_per_mass = units.mass_cgs / 1.988409870698051e33;
  const double years_per_time = units.time_cgs() / 3.15576e7;
  analysis::Diagnostics d = sum.result();
  d.radiated = engine_.radiated_energy();
  const auto& sf = engine_.star_formation_total();
  const double elapsed = engine_.cosmic_time() - sf_time_before_;
  if (elapsed > 0.0)
    d.sfr_msun_per_yr = (sf.mass_formed - sf_mass_before_) * msun_per_mass / (elapsed * years_per_time);
  sf_mass_before_ = sf.mass_formed;
  sf_time_before_ = engine_.cosmic_time();
  d.feedback_own = sf.energy_own;
  d.feedback_reservoir = sf.energy_reservoir;
  d.feedback_hot = sf.energy_hot;
  d.thermal_locked = sf.thermal_locked;
  d.promotions = sf.promotions;
  d.dt_min = engine_.cosmic_step(d.time_bin_min);
  file_->write(config_.comoving.enabled ? engine_.scale_factor() : engine_.time(), engine_.steps(), d);
}

}  // namespace fountain
