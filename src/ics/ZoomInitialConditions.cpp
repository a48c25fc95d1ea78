#include "ics/ZoomInitialConditions.hpp"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

#include "core/Error.hpp"
#include "core/IdealGas.hpp"
#include "ics/WhiteNoise.hpp"

namespace fountain::ics {

namespace {

std::size_t cell_index(int n, int i, int j, int k) {
  return (static_cast<std::size_t>(i) * static_cast<std::size_t>(n) + static_cast<std::size_t>(j)) * static_cast<std::size_t>(n) +
         static_cast<std::size_t>(k);
}

// A block of `level`'s grid replaced by one particle: the mean of its fine cells' positions
// (unwrapped about the block's centre) and velocities.
struct Block {
  Vec3 x, v;
};
Block block_mean(const LatticeParticles& fine, int finest, int level, int i, int j, int k, double box) {
  const int n = 1 << finest, r = 1 << (finest - level);
  const double size = box / static_cast<double>(1 << level);
  const Vec3 centre = Vec3{i + 0.5, j + 0.5, k + 0.5} * size;
  Vec3 dx{}, v{};
  for (int a = 0; a < r; ++a)
    for (int b = 0; b < r; ++b)
      for (int c = 0; c < r; ++c) {
        const std::size_t f = cell_index(n, i * r + a, j * r + b, k * r + c);
        Vec3 d = fine.x[f] - centre;
        for (int axis = 0; axis < 3; ++axis) d[axis] -= box * std::nearbyint(d[axis] / box);
        dx += d;
        v += fine.v[f];
      }
  const double inv = 1.0 / (static_cast<double>(r) * r * r);
  Vec3 x = centre + dx * inv;
  for (int axis = 0; axis < 3; ++axis) x[axis] -= box * std::floor(x[axis] / box);
  return {x, v * inv};
}

Vec3 folded(Vec3 x, double box) {
  for (int axis = 0; axis < 3; ++axis) x[axis] -= box * std::floor(x[axis] / box);
  return x;
}

}  // namespace

std::vector<double> nested_noise(std::uint64_t seed, int coarsest, int finest) {
  if (coarsest < 1 || finest < coarsest || finest > 10)
    throw InputError(fmt::format("nested noise needs 1 <= coarsest level <= finest level <= 10, not {} and {}", coarsest,
                                 finest));
  int n = 1 << coarsest;
  std::vector<double> w(static_cast<std::size_t>(n) * n * n);
  for (std::size_t c = 0; c < w.size(); ++c) w[c] = white_noise(seed, coarsest, c);
  for (int level = coarsest; level < finest; ++level) {
    const int m = 2 * n;
    std::vector<double> child(static_cast<std::size_t>(m) * m * m);
    const double scale = 1.0 / std::sqrt(8.0);
    tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& range) {
      for (int i = range.begin(); i != range.end(); ++i)
        for (int j = 0; j < n; ++j)
          for (int k = 0; k < n; ++k) {
            double g[8], mean = 0.0;
            for (int s = 0; s < 8; ++s) {
              g[s] = white_noise(seed, level + 1, cell_index(m, 2 * i + (s >> 2), 2 * j + ((s >> 1) & 1), 2 * k + (s & 1)));
              mean += g[s];
            }
            mean /= 8.0;
            const double parent = w[cell_index(n, i, j, k)] * scale;
            for (int s = 0; s < 8; ++s)
              child[cell_index(m, 2 * i + (s >> 2), 2 * j + ((s >> 1) & 1), 2 * k + (s & 1))] = g[s] - mean + parent;
          }
    });
    w = std::move(child);
    n = m;
  }
  return w;
}

std::vector<std::uint8_t> dilate(const std::vector<std::uint8_t>& marked, int level, int cells) {
  const int n = 1 << level;
  std::vector<std::uint8_t> out(marked.size(), 0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        if (!marked[cell_index(n, i, j, k)]) continue;
        for (int a = -cells; a <= cells; ++a)
          for (int b = -cells; b <= cells; ++b)
            for (int c = -cells; c <= cells; ++c)
              out[cell_index(n, ((i + a) % n + n) % n, ((j + b) % n + n) % n, ((k + c) % n + n) % n)] = 1;
      }
  return out;
}

CosmologicalBox make_zoom(const CosmologicalBoxParams& p, const ZoomLevels& levels, const std::vector<std::uint8_t>& region,
                          const Units& units) {
  const int l0 = levels.coarsest, lp = levels.parent, lmax = levels.finest;
  if (!(l0 == lp || l0 == lp - 1) || lmax < lp || l0 < 1 || lmax > 10)
    throw InputError(fmt::format("zoom levels {}, {}, {} (coarsest, parent, finest): the coarsest must be the parent level "
                                 "or one below it, the finest at least the parent and at most 10",
                                 l0, lp, lmax));
  const int np = 1 << lp;
  const std::size_t parent_cells = static_cast<std::size_t>(np) * np * np;
  bool zoom = false;
  for (std::uint8_t m : region) zoom = zoom || m;
  if (!region.empty() && region.size() != parent_cells)
    throw InputError(fmt::format("a zoom region of {} cells for a parent level of {}^3", region.size(), np));
  if (!(p.a_start > 0.0 && p.a_start < 1.0)) throw InputError(fmt::format("starting scale factor {} is not in (0, 1)", p.a_start));

  CosmologicalBoxParams fine_params = p;
  fine_params.level = lmax;
  // One set of fields (and phi2's source) for the dark matter and, half a cell on, the gas.
  DisplacementFields fields(linear_density_of(nested_noise(p.seed, l0, lmax), fine_params), p.lpt_order);
  const LatticeParticles fine = lagrangian_particles(fields, fine_params, 0.0);
  const double m_fine = cell_matter(fine_params, lmax, units);
  const int nf = 1 << lmax, r = 1 << (lmax - lp);
  CosmologicalBox out;
  out.box = p.box;
  out.a = p.a_start;
  IcCollisionlessParticles& dm = out.dark_matter;
  const double block_mass_parent = m_fine * static_cast<double>(r) * r * r;

  if (!zoom) {
    // The parent run: every parent-level cell one dark matter particle, the zoom's own blocks.
    for (int i = 0; i < np; ++i)
      for (int j = 0; j < np; ++j)
        for (int k = 0; k < np; ++k) {
          const Block b = block_mean(fine, lmax, lp, i, j, k, p.box);
          dm.push_back(1 + cell_index(np, i, j, k), Species::DarkMatter, block_mass_parent, b.x, b.v);
        }
    return out;
  }

  const double gas_fraction = p.gas ? p.cosmology.omega_b / p.cosmology.omega_m : 0.0;
  // High resolution: every finest-level cell of the region's parent-level cells.
  for (int i = 0; i < nf; ++i)
    for (int j = 0; j < nf; ++j)
      for (int k = 0; k < nf; ++k) {
        if (!region[cell_index(np, i / r, j / r, k / r)]) continue;
        const std::size_t f = cell_index(nf, i, j, k);
        dm.push_back(1 + f, Species::DarkMatter, (1.0 - gas_fraction) * m_fine, folded(fine.x[f], p.box), fine.v[f]);
      }
  if (p.gas) {
    const LatticeParticles shifted = lagrangian_particles(fields, fine_params, 0.5);
    const double kelvin_per_u = ideal_gas_kelvin_per_energy(units, 5.0 / 3.0, cosmology::kNeutralMeanMolecularWeight);
    const double u_comoving = p.a_start * p.a_start * cosmology::initial_gas_temperature(p.cosmology, p.a_start) / kelvin_per_u;
    IcGasParticles& gas = out.gas;
    for (int i = 0; i < nf; ++i)
      for (int j = 0; j < nf; ++j)
        for (int k = 0; k < nf; ++k) {
          if (!region[cell_index(np, i / r, j / r, k / r)]) continue;
          const std::size_t f = cell_index(nf, i, j, k);
          gas.push_back(1 + f + (std::uint64_t{1} << 40), gas_fraction * m_fine, folded(shifted.x[f], p.box), shifted.v[f],
                        u_comoving, 0.0);
        }
  }
  // The parent level: the region's surroundings within two cells, and (with a coarsest level
  // below it) every parent-level cell of a coarsest cell that holds any of those.
  const std::vector<std::uint8_t> near = dilate(region, lp, 2);
  std::vector<std::uint8_t> at_parent(parent_cells, 0);
  const int n0 = 1 << l0, s = 1 << (lp - l0);
  std::vector<std::uint8_t> split(static_cast<std::size_t>(n0) * n0 * n0, 0);
  for (int i = 0; i < np; ++i)
    for (int j = 0; j < np; ++j)
      for (int k = 0; k < np; ++k)
        if (near[cell_index(np, i, j, k)]) split[cell_index(n0, i / s, j / s, k / s)] = 1;
  for (int i = 0; i < np; ++i)
    for (int j = 0; j < np; ++j)
      for (int k = 0; k < np; ++k) {
        const std::size_t c = cell_index(np, i, j, k);
        at_parent[c] = !region[c] && (l0 == lp || split[cell_index(n0, i / s, j / s, k / s)]);
      }
  for (int i = 0; i < np; ++i)
    for (int j = 0; j < np; ++j)
      for (int k = 0; k < np; ++k) {
        const std::size_t c = cell_index(np, i, j, k);
        if (!at_parent[c]) continue;
        const Block b = block_mean(fine, lmax, lp, i, j, k, p.box);
        dm.push_back(1 + c + (std::uint64_t{1} << 41), Species::LowResDarkMatter, block_mass_parent, b.x, b.v);
      }
  if (l0 < lp) {
    const double block_mass_coarse = block_mass_parent * static_cast<double>(s) * s * s;
    for (int i = 0; i < n0; ++i)
      for (int j = 0; j < n0; ++j)
        for (int k = 0; k < n0; ++k) {
          const std::size_t c = cell_index(n0, i, j, k);
          if (split[c]) continue;
          const Block b = block_mean(fine, lmax, l0, i, j, k, p.box);
          dm.push_back(1 + c + (std::uint64_t{1} << 42), Species::LowResDarkMatter, block_mass_coarse, b.x, b.v);
        }
  }
  return out;
}

}  // namespace fountain::ics
