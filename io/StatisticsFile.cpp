#include "io/StatisticsFile.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cstring>

#include "core/Error.hpp"

namespace fountain::io {

namespace {
constexpr const char* kColumns =
    "time step mass_gas mass_dark_matter mass_hot mass_warm mass_cold mass_unbound "
    "thermal_energy kinetic_energy potential_energy total_energy radiated_energy "
    "momentum_x momentum_y momentum_z angular_momentum_x angular_momentum_y angular_momentum_z "
    "mass_stars mass_stars_hidden sfr_msun_per_yr mass_promoted_diffuse reservoir_energy "
    "feedback_own feedback_reservoir feedback_hot thermal_locked h_min_gas dt_min promotions";
}

StatisticsFile::StatisticsFile(const std::string& path, bool append, bool comoving) : path_(path) {
  file_ = std::fopen(path.c_str(), append ? "a" : "w");
  if (!file_) throw InputError(fmt::format("{}: cannot open the statistics file: {}", path, std::strerror(errno)));
  if (!append) {
    fmt::print(file_,
               "# Fountain statistics: internal units (time, mass, energy = mass velocity^2, momentum = mass "
               "velocity). Phases as in Marri & White (2003) section 3.2: hot T > 2 T*, cold T <= 2 T* and "
               "rho > 0.1 rho*, warm otherwise; unbound: v^2/2 + potential > 0; mass_promoted_diffuse: "
               "gas promoted by feedback and not cold now. Conserved: total_energy + reservoir_energy + "
               "radiated_energy + thermal_locked - feedback_own - feedback_reservoir - feedback_hot (all since "
               "the start; thermal_locked is the thermal energy of gas turned into stars). h_min_gas: the smallest gas "
               "smoothing length; dt_min: the smallest particle timestep, both at the line's time. promotions: feedback's "
               "promotions of gas into the hot phase since the start (a particle promoted twice counts twice).\n");
    if (comoving)
      fmt::print(file_,
                 "# A comoving run: time is the scale factor a; every quantity is physical (rho'/a^3, u'/a^2, a h'), "
                 "velocities and potentials peculiar (v'/a, Phi'/a), in the run's h-scaled units (masses Msun/h, "
                 "lengths Mpc/h); sfr_msun_per_yr is in Msun per year of cosmic time and dt_min is cosmic time. The "
                 "energies are not conserved: the expansion does work on them.\n");
    fmt::print(file_, "# {}\n", kColumns);
    std::fflush(file_);
  }
}

StatisticsFile::~StatisticsFile() {
  if (file_) std::fclose(file_);
}

void StatisticsFile::write(double time, long long step, const analysis::Diagnostics& d) {
  std::string line = fmt::format("{:.10e} {}", time, step);
  for (double x : {d.mass_gas, d.mass_dark_matter, d.mass_hot, d.mass_warm, d.mass_cold, d.mass_unbound, d.thermal,
                   d.kinetic, d.potential, d.total_energy(), d.radiated, d.momentum.x, d.momentum.y, d.momentum.z,
                   d.angular_momentum.x, d.angular_momentum.y, d.angular_momentum.z, d.mass_stars, d.mass_stars_hidden,
                   d.sfr_msun_per_yr, d.mass_promoted_diffuse, d.reservoir, d.feedback_own, d.feedback_reservoir,
                   d.feedback_hot, d.thermal_locked, d.h_min_gas, d.dt_min})
    line += fmt::format(" {:.10e}", x);
  line += fmt::format(" {}", d.promotions);
  line += '\n';
  const bool ok = std::fputs(line.c_str(), file_) >= 0;
  if (!ok || std::fflush(file_) != 0)
    throw InputError(fmt::format("{}: cannot write the statistics file: {}", path_, std::strerror(errno)));
}

}  // namespace fountain::io
