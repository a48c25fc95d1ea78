#include "ics/CosmologicalBox.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "core/Error.hpp"
#include "core/IdealGas.hpp"
#include "cosmology/PowerSpectrum.hpp"
#include "ics/LagrangianPerturbation.hpp"
#include "ics/WhiteNoise.hpp"

namespace fountain::ics {

SpectralField linear_density(const CosmologicalBoxParams& p) {
  const int n = p.cells();
  const std::size_t cells = static_cast<std::size_t>(n) * n * n;
  std::vector<double> noise(cells);
  for (std::size_t c = 0; c < cells; ++c) noise[c] = white_noise(p.seed, p.level, c);
  return linear_density_of(noise, p);
}

SpectralField linear_density_of(const std::vector<double>& noise, const CosmologicalBoxParams& p) {
  const int n = p.cells();
  SpectralField delta = forward_transform(noise, n, p.box);
  const cosmology::LinearPowerSpectrum power(cosmology::EisensteinHu(p.cosmology, p.transfer), p.n_s, p.sigma_8);
  const double cell_volume = std::pow(p.box / n, 3);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k <= n / 2; ++k) {
        const double kx = delta.wave(i), ky = delta.wave(j), kz = delta.wave(k);
        const double kk = std::sqrt(kx * kx + ky * ky + kz * kz);
        delta.values[delta.index(i, j, k)] *= kk > 0.0 ? std::sqrt(power(kk) / cell_volume) : 0.0;
      }
  return delta;
}

LatticeParticles lagrangian_particles(const SpectralField& delta, const CosmologicalBoxParams& p, double shift) {
  const int n = p.cells();
  const double cell = p.box / n;
  const cosmology::Background background(p.cosmology);
  const double d1 = background.growth(1.0);
  const double a = p.a_start;
  const double d = background.growth(a) / d1;
  const double d2 = background.second_order_growth(a).d2 / (d1 * d1);
  const double f = background.growth_rate(a), f2 = background.second_order_growth(a).f2;
  const double hubble = background.hubble(a);
  // v' = a v_pec = a^2 H [f D psi1 + f2 D2 grad phi2].
  const double v1 = a * a * hubble * f * d, v2 = a * a * hubble * f2 * d2;
  const Displacements disp = lagrangian_displacements(delta, p.lpt_order, shift);
  const std::size_t cells = static_cast<std::size_t>(n) * n * n;
  LatticeParticles out;
  out.x.resize(cells);
  out.v.resize(cells);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const std::size_t c = (static_cast<std::size_t>(i) * n + j) * n + k;
        const Vec3 psi{disp.first[0][c], disp.first[1][c], disp.first[2][c]};
        Vec3 psi2{};
        if (p.lpt_order >= 2) psi2 = {disp.second[0][c], disp.second[1][c], disp.second[2][c]};
        out.x[c] = Vec3{i + 0.5 + shift, j + 0.5 + shift, k + 0.5 + shift} * cell + d * psi + d2 * psi2;
        out.v[c] = v1 * psi + v2 * psi2;
      }
  return out;
}

double cell_matter(const CosmologicalBoxParams& p, int level, const Units& units) {
  const cosmology::Background background(p.cosmology);
  const double rho_crit = 3.0 * background.hubble0() * background.hubble0() /
                          (8.0 * std::numbers::pi * units.gravitational_constant());
  const double cell = p.box / static_cast<double>(1 << level);
  return p.cosmology.omega_m * rho_crit * cell * cell * cell;
}

CosmologicalBox make_cosmological_box(const CosmologicalBoxParams& p, const Units& units, const IcProgress& progress) {
  auto stage = [&](const char* what) {
    if (progress) progress(what);
  };
  if (p.level < 1 || p.level > 12)
    throw InputError(fmt::format("a cosmological box needs 2^level particles per side with level in [1, 12], not {}",
                                 p.level));
  if (!(p.a_start > 0.0 && p.a_start < 1.0)) throw InputError(fmt::format("starting scale factor {} is not in (0, 1)", p.a_start));
  stage("white noise and the linear density");
  const SpectralField delta = linear_density(p);
  const double cell_mass = cell_matter(p, p.level, units);
  const double gas_fraction = p.gas ? p.cosmology.omega_b / p.cosmology.omega_m : 0.0;

  CosmologicalBox out;
  out.box = p.box;
  out.a = p.a_start;
  auto fold = [&](Vec3 x) {
    for (int axis = 0; axis < 3; ++axis) x[axis] -= p.box * std::floor(x[axis] / p.box);
    return x;
  };
  {
    stage(p.lpt_order >= 2 ? "dark matter: Zel'dovich and second-order displacements" : "dark matter: Zel'dovich displacements");
    const LatticeParticles lattice = lagrangian_particles(delta, p, 0.0);
    CollisionlessParticles& dm = out.dark_matter;
    dm.resize(lattice.x.size());
    for (std::size_t c = 0; c < lattice.x.size(); ++c) {
      dm.id[c] = 1 + c;
      dm.species[c] = Species::DarkMatter;
      dm.mass[c] = (1.0 - gas_fraction) * cell_mass;
      dm.x[c] = fold(lattice.x[c]);
      dm.v[c] = dm.v_full[c] = lattice.v[c];
    }
  }
  if (p.gas) {
    stage("gas: the same fields half a cell on");
    const LatticeParticles lattice = lagrangian_particles(delta, p, 0.5);
    GasParticles& gas = out.gas;
    gas.resize(lattice.x.size());
    const double kelvin_per_u = ideal_gas_kelvin_per_energy(units, 5.0 / 3.0, cosmology::kNeutralMeanMolecularWeight);
    const double u_comoving = p.a_start * p.a_start * cosmology::initial_gas_temperature(p.cosmology, p.a_start) / kelvin_per_u;
    for (std::size_t c = 0; c < lattice.x.size(); ++c) {
      gas.id[c] = 1 + c + (std::uint64_t{1} << 40);
      gas.mass[c] = gas_fraction * cell_mass;
      gas.x[c] = fold(lattice.x[c]);
      gas.v[c] = gas.v_full[c] = lattice.v[c];
      gas.u[c] = gas.u_full[c] = u_comoving;
      gas.h[c] = 0.0;
    }
  }
  return out;
}

}  // namespace fountain::ics
