#include "app/IcCommand.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "core/Error.hpp"
#include "ics/TestProblems.hpp"
#include "io/InitialConditions.hpp"
#include "particles/GasParticles.hpp"

namespace fountain {

namespace {

int default_resolution(const std::string& problem) {
  if (problem == "sod") return 32;
  if (problem == "sedov") return 24;
  if (problem == "evrard") return 8;
  if (problem == "gresho") return 32;
  if (problem == "cosmo") return 64;
  return 4000;  // sphere: particles per species
}

int resolution_of(const IcRequest& r) { return r.resolution_given ? r.resolution : default_resolution(r.problem); }

std::string bytes_text(double b) {
  const char* unit[] = {"B", "kB", "MB", "GB", "TB", "PB"};
  int k = 0;
  while (b >= 1000.0 && k < 5) b /= 1000.0, ++k;
  return fmt::format("{:.3g} {}", b, unit[k]);
}

}  // namespace

double ic_particle_count(const IcRequest& r) {
  const double n = resolution_of(r);
  // Two points per BCC cell; cells along each side as the generators lay them.
  if (r.problem == "sod") return 2.0 * (n * (n / 2) * (n / 2)) + 2.0 * ((n / 2) * (n / 4) * (n / 4));
  if (r.problem == "sedov") return 2.0 * n * n * n;
  if (r.problem == "gresho") return 2.0 * n * n * (n / 2);
  if (r.problem == "evrard") return (4.0 / 3.0) * M_PI * n * n * n;  // the cube of side 2n cut to the ball
  if (r.problem == "cosmo") return (r.cosmo.gas ? 2.0 : 1.0) * n * n * n;
  if (r.problem == "zoom") return 2.0 * std::pow(8.0, r.zoom.levels.finest);  // the finest level's fields, a cell each
  return 2.0 * n;                                                    // sphere: gas + dark matter
}

std::size_t ic_bytes_per_particle(const std::string& problem) {
  if (problem == "cosmo" || problem == "zoom") {
    // Lean stores (IcParticles.hpp; the gas's fields, the wider), and about 32 bytes a cell of
    // grids: the linear density's and phi2's source's coefficients and FFTW's two buffers.
    constexpr std::size_t lean = sizeof(std::uint64_t) + 3 * sizeof(double) + 2 * sizeof(Vec3);
    // A zoom keeps its finest lattice's positions and velocities at both shifts to average.
    return lean + 32 + (problem == "zoom" ? 2 * sizeof(Vec3) : 0);
  }
  std::size_t bytes = 0;
  GasParticles one;
  one.for_each_field([&](auto& field) { bytes += sizeof(typename std::decay_t<decltype(field)>::value_type); });
  // The lattice point (and its stretched copy) and the writer's gathered datasets.
  return bytes + 2 * sizeof(Vec3) + 64;
}

double available_memory_bytes() {
  std::ifstream meminfo("/proc/meminfo");
  std::string line;
  while (std::getline(meminfo, line)) {
    std::istringstream in(line);
    std::string key;
    double kb = 0;
    if (in >> key >> kb && key == "MemAvailable:") return kb * 1024.0;
  }
  return static_cast<double>(::sysconf(_SC_PHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGESIZE));
}

void check_ic_request(const IcRequest& r, double memory_bytes) {
  if (r.resolution_given && r.resolution <= 0)
    throw InputError(fmt::format("option -n,--resolution = {} must be a positive number of lattice cells{}",
                                 r.resolution, r.problem == "sphere" ? " (sphere: particles per species)" : ""));
  if (r.problem == "evrard" && r.resolution_given && r.resolution < 2)
    throw InputError(fmt::format("option -n,--resolution = {}: the Evrard sphere needs at least 2 cells per radius",
                                 r.resolution));
  if (r.problem == "cosmo" && (resolution_of(r) < 2 || (resolution_of(r) & (resolution_of(r) - 1)) != 0 ||
                               resolution_of(r) > 4096))
    throw InputError(fmt::format("option -n,--resolution = {}: a cosmological box needs a power of two particles per "
                                 "side, from 2 to 4096",
                                 resolution_of(r)));
  if (r.problem == "zoom") {
    const ics::ZoomLevels& z = r.zoom.levels;
    if (!((z.coarsest == z.parent || z.coarsest == z.parent - 1) && z.parent <= z.finest && z.coarsest >= 1 && z.finest <= 10))
      throw InputError(fmt::format("option --levels = {},{},{}: coarsest, parent and finest levels need coarsest = parent "
                                   "or parent - 1, parent <= finest <= 10",
                                   z.coarsest, z.parent, z.finest));
    if (r.resolution_given) throw InputError("option -n,--resolution does not apply to zoom: --levels sets its grids");
    // Fixed amplitudes on the finest grid would break the nesting: a fine block's mean would no
    // longer be its coarse cell's noise.
    if (r.cosmo.fix_amplitudes)
      throw InputError("option --fix-amplitudes does not apply to zoom: its levels' noise must nest");
  }
  if (r.problem == "cosmo" || r.problem == "zoom") {
    const ics::CosmologicalBoxParams& c = r.cosmo;
    if (!(c.box > 0.0 && std::isfinite(c.box))) throw InputError(fmt::format("option --box = {} must be positive", c.box));
    if (!(c.a_start > 0.0 && c.a_start < 1.0))
      throw InputError(fmt::format("option --z-start = {} must be positive", 1.0 / c.a_start - 1.0));
    if (!(c.sigma_8 > 0.0)) throw InputError(fmt::format("option --sigma-8 = {} must be positive", c.sigma_8));
    if (!(c.cosmology.omega_m > 0.0 && c.cosmology.omega_b >= 0.0 && c.cosmology.omega_b <= c.cosmology.omega_m))
      throw InputError(fmt::format("options --omega-m = {} and --omega-b = {}: need 0 <= omega_b <= omega_m, omega_m > 0",
                                   c.cosmology.omega_m, c.cosmology.omega_b));
    if (!(c.cosmology.hubble_param > 0.0))
      throw InputError(fmt::format("option --hubble = {} must be positive", c.cosmology.hubble_param));
  }
  if (r.problem == "sphere" && r.resolution_given && r.resolution < 8)
    throw InputError(fmt::format("option -n,--resolution = {}: the sphere needs at least 8 particles per species",
                                 r.resolution));
  if (!(std::isfinite(r.gamma) && r.gamma > 1.0 && r.gamma <= 3.0))
    throw InputError(fmt::format("option --gamma = {} must be a finite adiabatic index in (1, 3] "
                                 "(the parameter file's hydro.gamma takes the same range)",
                                 r.gamma));
  const double count = ic_particle_count(r);
  const double need = count * static_cast<double>(ic_bytes_per_particle(r.problem));
  if (!(need <= memory_bytes))
    throw InputError(fmt::format("ic {} -n {} would make about {:.3g} particles, needing about {} of memory; "
                                 "this machine has {} available: choose a smaller -n",
                                 r.problem, resolution_of(r), count, bytes_text(need), bytes_text(memory_bytes)));
}

io::CosmologicalIcInfo cosmological_ic_info(const IcRequest& r, const ics::CosmologicalBoxParams& c, double a,
                                            const Units& units) {
  io::CosmologicalIcInfo info{c.cosmology, a, units, {}, {}, {}};
  info.generator_words = {{"Generator", "fountain ic " + r.problem},
                          {"Seed", std::to_string(c.seed)},
                          {"Transfer", cosmology::kTransferKindNames[static_cast<int>(c.transfer)]}};
  info.generator_numbers = {{"Sigma8", c.sigma_8}, {"n_s", c.n_s}, {"RedshiftStart", 1.0 / c.a_start - 1.0}};
  info.generator_integers = {{"LPTOrder", c.lpt_order},
                             {"InvertPhases", c.invert_phases ? 1 : 0},
                             {"FixAmplitudes", c.fix_amplitudes ? 1 : 0}};
  if (r.problem == "zoom") {
    const ics::ZoomLevels& z = r.zoom.levels;
    info.generator_integers.insert(info.generator_integers.end(),
                                   {{"LevelCoarsest", z.coarsest}, {"LevelParent", z.parent}, {"LevelFinest", z.finest}});
    info.generator_numbers.emplace_back("MassScale", r.zoom.mass_scale);
  } else {
    info.generator_integers.emplace_back("Level", c.level);
  }
  return info;
}

std::string write_ic(const IcRequest& r) {
  check_ic_request(r, available_memory_bytes());
  if (r.problem == "zoom") return write_zoom_ic(r);
  const int n = resolution_of(r);
  if (r.problem == "cosmo") {
    ics::CosmologicalBoxParams c = r.cosmo;
    c.level = static_cast<int>(std::lround(std::log2(n)));
    const Units units;  // h-scaled: Mpc/h, Msun/h, km/s
    // Progress on stderr for boxes that take more than a moment.
    const auto start = std::chrono::steady_clock::now();
    auto progress = [&](const std::string& stage) {
      if (n >= 128)
        fmt::print(stderr, "[{:6.1f} s] {}\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                   stage);
    };
    const ics::CosmologicalBox box = ics::make_cosmological_box(c, units, progress);
    progress("writing " + r.output);
    io::write_initial_conditions(r.output, box.gas, box.dark_matter, box.box, cosmological_ic_info(r, c, box.a, units));
    progress("done");
    double rms = 0.0;
    for (std::size_t i = 0; i < box.dark_matter.size(); ++i) {
      const std::size_t cells = static_cast<std::size_t>(n);
      const std::size_t ii = i / (cells * cells), jj = (i / cells) % cells, kk = i % cells;
      Vec3 d = box.dark_matter.x[i] - Vec3{ii + 0.5, jj + 0.5, kk + 0.5} * (c.box / n);
      for (int axis = 0; axis < 3; ++axis) d[axis] -= c.box * std::round(d[axis] / c.box);
      rms += dot(d, d);
    }
    rms = std::sqrt(rms / static_cast<double>(box.dark_matter.size())) / (c.box / n);
    return fmt::format("wrote {} ({}^3 dark matter{} particles of {:.4g} Msun/h{}, box {} Mpc/h, z = {}, "
                       "rms displacement {:.3g} of the spacing)",
                       r.output, n, c.gas ? " and gas" : "", box.dark_matter.mass[0],
                       c.gas ? fmt::format(" and {:.4g}", box.gas.mass[0]) : "", c.box, 1.0 / c.a_start - 1.0, rms);
  }
  if (r.problem == "sphere") {
    ics::RotatingSphereParams sphere = r.sphere;
    sphere.particles_per_species = n;
    const ics::RotatingSphereIC s = ics::rotating_sphere(sphere);
    // Isolated: centred on the origin; BoxSize is the enclosing cube's side (informative).
    const double side = 2.0 * sphere.radius;
    io::write_initial_conditions(r.output, s.gas, s.dm, {side, side, side}, false);
    return fmt::format("wrote {} ({} gas + {} dark matter particles; omega = {:.6g} km/s per Mpc/h, u = {:.6g} "
                       "(km/s)^2, W = {:.6g}, spin = {:.6g})",
                       r.output, s.gas.size(), s.dm.size(), s.omega, s.u, s.potential_energy, s.spin);
  }
  ics::ProblemIC p;
  if (r.problem == "sod") p = ics::sod_shock(n, r.gamma);
  else if (r.problem == "sedov") p = ics::sedov_blast(n, r.gamma);
  else if (r.problem == "evrard") p = ics::evrard_sphere(n);
  else p = ics::gresho_vortex(n, r.gamma);
  io::write_initial_conditions(r.output, p.gas, p.box_size, p.periodic);
  return fmt::format("wrote {} ({} gas particles, box {} x {} x {})", r.output, p.gas.size(), p.box_size.x,
                     p.box_size.y, p.box_size.z);
}

}  // namespace fountain
