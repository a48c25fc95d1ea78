#include "ics/CosmologicalBox.hpp"

#include <fmt/format.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <utility>

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
  // Unit white noise's transform has <|w_k|^2> = N^3, the modulus a fixed mode takes.
  const double fixed_modulus = std::sqrt(static_cast<double>(n) * n * n);
  const double sign = p.invert_phases ? -1.0 : 1.0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k <= n / 2; ++k) {
        const double kx = delta.wave(i), ky = delta.wave(j), kz = delta.wave(k);
        const double kk = std::sqrt(kx * kx + ky * ky + kz * kz);
        std::complex<double>& mode = delta.values[delta.index(i, j, k)];
        if (p.fix_amplitudes && std::abs(mode) > 0.0) mode *= fixed_modulus / std::abs(mode);
        mode *= kk > 0.0 ? sign * std::sqrt(power(kk) / cell_volume) : 0.0;
      }
  return delta;
}

void lattice_motion(DisplacementFields& fields, const CosmologicalBoxParams& p, double shift, std::span<Vec3> x,
                    std::span<Vec3> v) {
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
  for (int axis = 0; axis < 3; ++axis) {
    // psi1 waits in v while grad phi2 takes the fields' one buffer.
    const std::span<const double> psi1 = fields.first(axis, shift);
    for (std::size_t c = 0; c < psi1.size(); ++c) v[c][axis] = psi1[c];
    const std::span<const double> psi2 = fields.order() >= 2 ? fields.second(axis, shift) : std::span<const double>{};
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        for (int k = 0; k < n; ++k) {
          const std::size_t c = (static_cast<std::size_t>(i) * n + j) * n + k;
          const int q[3] = {i, j, k};
          const double psi = v[c][axis], grad2 = psi2.empty() ? 0.0 : psi2[c];
          x[c][axis] = (q[axis] + 0.5 + shift) * cell + d * psi + d2 * grad2;
          v[c][axis] = v1 * psi + v2 * grad2;
        }
  }
}

LatticeParticles lagrangian_particles(DisplacementFields& fields, const CosmologicalBoxParams& p, double shift) {
  const std::size_t cells = static_cast<std::size_t>(p.cells()) * p.cells() * p.cells();
  LatticeParticles out{std::vector<Vec3>(cells), std::vector<Vec3>(cells)};
  lattice_motion(fields, p, shift, out.x, out.v);
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
  SpectralField delta = linear_density(p);
  if (p.lpt_order >= 2) stage("the second-order displacements' source");
  // The transforms' buffers and phi2's source, made once for both species.
  DisplacementFields fields(std::move(delta), p.lpt_order);
  const double cell_mass = cell_matter(p, p.level, units);
  const double gas_fraction = p.gas ? p.cosmology.omega_b / p.cosmology.omega_m : 0.0;
  const std::size_t cells = static_cast<std::size_t>(p.cells()) * p.cells() * p.cells();
  auto fold = [&](std::vector<Vec3>& x) {
    for (Vec3& y : x)
      for (int axis = 0; axis < 3; ++axis) y[axis] -= p.box * std::floor(y[axis] / p.box);
  };

  CosmologicalBox out;
  out.box = p.box;
  out.a = p.a_start;
  stage(p.lpt_order >= 2 ? "dark matter: Zel'dovich and second-order displacements" : "dark matter: Zel'dovich displacements");
  IcCollisionlessParticles& dm = out.dark_matter;
  dm.resize(cells);  // species DarkMatter
  for (std::size_t c = 0; c < cells; ++c) {
    dm.id[c] = 1 + c;
    dm.mass[c] = (1.0 - gas_fraction) * cell_mass;
  }
  lattice_motion(fields, p, 0.0, dm.x, dm.v);
  fold(dm.x);
  if (p.gas) {
    stage("gas: the same fields half a cell on");
    IcGasParticles& gas = out.gas;
    gas.resize(cells);  // h = 0: for the run to find
    const double kelvin_per_u = ideal_gas_kelvin_per_energy(units, 5.0 / 3.0, cosmology::kNeutralMeanMolecularWeight);
    const double u_comoving = p.a_start * p.a_start * cosmology::initial_gas_temperature(p.cosmology, p.a_start) / kelvin_per_u;
    for (std::size_t c = 0; c < cells; ++c) {
      gas.id[c] = 1 + c + (std::uint64_t{1} << 40);
      gas.mass[c] = gas_fraction * cell_mass;
      gas.u[c] = u_comoving;
    }
    lattice_motion(fields, p, 0.5, gas.x, gas.v);
    fold(gas.x);
  }
  return out;
}

}  // namespace fountain::ics
