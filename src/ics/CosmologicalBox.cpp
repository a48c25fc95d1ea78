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

CosmologicalBox make_cosmological_box(const CosmologicalBoxParams& p, const Units& units) {
  if (p.level < 1 || p.level > 12)
    throw InputError(fmt::format("a cosmological box needs 2^level particles per side with level in [1, 12], not {}",
                                 p.level));
  if (!(p.a_start > 0.0 && p.a_start < 1.0)) throw InputError(fmt::format("starting scale factor {} is not in (0, 1)", p.a_start));
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

  const SpectralField delta = linear_density(p);
  const double rho_crit = 3.0 * background.hubble0() * background.hubble0() /
                          (8.0 * std::numbers::pi * units.gravitational_constant());
  const double cell_mass = p.cosmology.omega_m * rho_crit * cell * cell * cell;
  const double gas_fraction = p.gas ? p.cosmology.omega_b / p.cosmology.omega_m : 0.0;

  CosmologicalBox out;
  out.box = p.box;
  out.a = a;
  const std::size_t cells = static_cast<std::size_t>(n) * n * n;
  auto place = [&](const Displacements& disp, double shift, auto&& set) {
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k) {
          const std::size_t c = (static_cast<std::size_t>(i) * n + j) * n + k;
          Vec3 psi{disp.first[0][c], disp.first[1][c], disp.first[2][c]};
          Vec3 psi2{};
          if (p.lpt_order >= 2) psi2 = {disp.second[0][c], disp.second[1][c], disp.second[2][c]};
          Vec3 x = Vec3{i + 0.5 + shift, j + 0.5 + shift, k + 0.5 + shift} * cell + d * psi + d2 * psi2;
          for (int axis = 0; axis < 3; ++axis) x[axis] -= p.box * std::floor(x[axis] / p.box);
          set(c, x, v1 * psi + v2 * psi2);
        }
  };
  {
    CollisionlessParticles& dm = out.dark_matter;
    dm.resize(cells);
    place(lagrangian_displacements(delta, p.lpt_order, 0.0), 0.0, [&](std::size_t c, const Vec3& x, const Vec3& v) {
      dm.id[c] = 1 + c;
      dm.species[c] = Species::DarkMatter;
      dm.mass[c] = (1.0 - gas_fraction) * cell_mass;
      dm.x[c] = x;
      dm.v[c] = dm.v_full[c] = v;
    });
  }
  if (p.gas) {
    GasParticles& gas = out.gas;
    gas.resize(cells);
    const double kelvin_per_u = ideal_gas_kelvin_per_energy(units, 5.0 / 3.0, cosmology::kNeutralMeanMolecularWeight);
    const double u_comoving = a * a * cosmology::initial_gas_temperature(p.cosmology, a) / kelvin_per_u;
    place(lagrangian_displacements(delta, p.lpt_order, 0.5), 0.5, [&](std::size_t c, const Vec3& x, const Vec3& v) {
      gas.id[c] = 1 + c + (std::uint64_t{1} << 40);
      gas.mass[c] = gas_fraction * cell_mass;
      gas.x[c] = x;
      gas.v[c] = gas.v_full[c] = v;
      gas.u[c] = gas.u_full[c] = u_comoving;
      gas.h[c] = 0.0;
    });
  }
  return out;
}

}  // namespace fountain::ics
