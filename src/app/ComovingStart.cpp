#include "app/ComovingStart.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/Error.hpp"
#include "core/IdealGas.hpp"
#include "params/ParameterFile.hpp"

namespace fountain {

namespace {

// GADGET's file units where neither the parameters nor the file say: Mpc/h, 1e10 Msun/h, km/s.
constexpr Units kMpcMsunKms{};

bool agrees(double a, double b) { return std::fabs(a - b) <= 1e-6 * std::max(std::fabs(a), std::fabs(b)); }

// The run's and the file's cosmologies must be one: positions and velocities were made for it.
void check_file_cosmology(const io::InitialConditions& ic, const cosmology::CosmologyParams& c,
                          const ParameterFile& params, const std::string& path) {
  if (!ic.cosmology.present) return;
  const struct {
    const char* field;
    double file;
    const char* key;
    double run;
  } pairs[] = {{"Omega0", ic.cosmology.omega0, "cosmology.omega_m", c.omega_m},
               {"OmegaLambda", ic.cosmology.omega_lambda, "cosmology.omega_lambda", c.omega_lambda},
               {"HubbleParam", ic.cosmology.hubble_param, "cosmology.hubble_param", c.hubble_param}};
  for (const auto& p : pairs)
    if (!agrees(p.file, p.run))
      throw InputError(fmt::format("{}: the header's {} = {} differs from {} = {}: the initial conditions were made "
                                   "for another cosmology",
                                   path, p.field, p.file, params.where(p.key), p.run));
}

}  // namespace

void to_comoving_variables(io::InitialConditions& ic, RunConfig& config, const ParameterFile& params,
                           const std::string& path) {
  ComovingConfig& cc = config.comoving;
  const double a_file = ic.time;
  if (cc.a_begin == 0.0) {
    if (!(a_file > 0.0 && a_file <= 1.0))
      throw InputError(fmt::format("{}: /Header/Time = {} is not a scale factor in (0, 1]; give the start as {}", path,
                                   a_file, params.where("cosmology.a_begin")));
    cc.a_begin = a_file;
  } else if (!agrees(a_file, cc.a_begin)) {
    throw InputError(fmt::format("{}: /Header/Time = {} (the file's scale factor) differs from {} = {}", path, a_file,
                                 params.where("cosmology.a_begin"), cc.a_begin));
  }
  config.set_comoving_times();
  config.check_times(params, fmt::format("/Header/Time of {}", path));
  check_file_cosmology(ic, cc.cosmology, params, path);

  // Unit conversion factors from the file's (h-scaled) units to the run's.
  const ComovingFileConventions& f = cc.files;
  const Units& units = config.units;
  auto pick = [](double given, double in_file, double fallback) {
    return given > 0.0 ? given : in_file > 0.0 ? in_file : fallback;
  };
  const double h = cc.files.h_scaled ? 1.0 : cc.cosmology.hubble_param;
  const double length = pick(f.length_cgs, ic.units.length_cgs, kMpcMsunKms.length_cgs) * h / units.length_cgs;
  const double mass = pick(f.mass_cgs, ic.units.mass_cgs, 1e10 * kMpcMsunKms.mass_cgs) * h / units.mass_cgs;
  const double velocity = pick(f.velocity_cgs, ic.units.velocity_cgs, kMpcMsunKms.velocity_cgs) / units.velocity_cgs;
  const double a = cc.a_begin;
  // v' = a^2 dx/dt = a v_pec: GADGET's files hold v_pec / sqrt(a).
  const double v_factor = velocity * (f.gadget_velocities ? a * std::sqrt(a) : a);
  // u' = a^(3 (gamma - 1)) u = a^2 u for gamma = 5/3 (the engine refuses any other gamma).
  const double u_factor = velocity * velocity * a * a;
  double u_initial = 0.0;
  if (!ic.has_internal_energy) {
    const double kelvin_per_u =
        ideal_gas_kelvin_per_energy(units, config.hydro.gamma, cosmology::kNeutralMeanMolecularWeight);
    u_initial = a * a * cosmology::initial_gas_temperature(cc.cosmology, a) / kelvin_per_u;
  }
  ic.box_size = ic.box_size * length;
  ic.time = a;
  GasParticles& gas = ic.gas;
  for (std::size_t i = 0; i < gas.size(); ++i) {
    gas.x[i] = gas.x[i] * length;
    gas.h[i] *= length;
    gas.mass[i] *= mass;
    gas.v[i] = gas.v_full[i] = gas.v_full[i] * v_factor;
    gas.u[i] = gas.u_full[i] = ic.has_internal_energy ? gas.u_full[i] * u_factor : u_initial;
  }
  CollisionlessParticles& dm = ic.dm;
  for (std::size_t i = 0; i < dm.size(); ++i) {
    dm.x[i] = dm.x[i] * length;
    dm.mass[i] *= mass;
    dm.v[i] = dm.v_full[i] = dm.v_full[i] * v_factor;
  }
}

}  // namespace fountain
