#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "app/IcCommand.hpp"
#include "core/Error.hpp"
#include "io/GroupFiles.hpp"
#include "io/InitialConditions.hpp"

namespace fountain {

namespace {

double periodic_distance(const Vec3& a, const Vec3& b, double box) {
  Vec3 d = b - a;
  for (int k = 0; k < 3; ++k) d[k] -= box * std::nearbyint(d[k] / box);
  return norm(d);
}

// The halo to zoom on (COSMOLOGY.md C8.1): the given group, or among the groups with M_200 in
// range and no other group of more than half their M_200 within `isolation`, the one nearest
// 1e12 Msun/h in ln M (ties: the lower index).
std::size_t choose_halo(const io::FofHalos& h, const IcRequest::Zoom& z, const std::string& path) {
  if (z.halo >= 0) {
    if (static_cast<std::size_t>(z.halo) >= h.centre.size())
      throw InputError(fmt::format("option --halo = {}: {} has {} groups", z.halo, path, h.centre.size()));
    return static_cast<std::size_t>(z.halo);
  }
  std::size_t best = h.centre.size();
  double best_distance = std::numeric_limits<double>::infinity();
  for (std::size_t g = 0; g < h.centre.size(); ++g) {
    if (!(h.m200[g] >= z.mass_min && h.m200[g] <= z.mass_max)) continue;
    bool isolated = true;
    for (std::size_t o = 0; o < h.centre.size() && isolated; ++o)
      isolated = o == g || !(h.m200[o] > 0.5 * h.m200[g] && periodic_distance(h.centre[g], h.centre[o], h.box) < z.isolation);
    if (!isolated) continue;
    const double d = std::fabs(std::log(h.m200[g] / 1e12));
    if (d < best_distance) best_distance = d, best = g;
  }
  if (best == h.centre.size())
    throw InputError(fmt::format("{}: no isolated group with M_200 in [{:g}, {:g}] Msun/h (no group of half its mass within "
                                 "{:g} Mpc/h); widen --mass-min/--mass-max or choose one with --halo",
                                 path, z.mass_min, z.mass_max, z.isolation));
  return best;
}

// The same initial conditions at masses x `scale` (COSMOLOGY.md C11.3, the paper's MFB/100):
// lengths, the box and velocities x s = scale^(1/3), energies x s^2, so that densities and
// free-fall times are kept and characteristic temperatures fall by s^2.
void scale_box(ics::CosmologicalBox& box, double scale) {
  const double s = std::cbrt(scale);
  box.box *= s;
  IcCollisionlessParticles& dm = box.dark_matter;
  for (std::size_t i = 0; i < dm.size(); ++i) {
    dm.x[i] *= s;
    dm.v[i] *= s;
    dm.mass[i] *= scale;
  }
  IcGasParticles& gas = box.gas;
  for (std::size_t i = 0; i < gas.size(); ++i) {
    gas.x[i] *= s;
    gas.v[i] *= s;
    gas.mass[i] *= scale;
    gas.u[i] *= s * s;
  }
}

}  // namespace

std::string write_zoom_ic(const IcRequest& r) {
  const IcRequest::Zoom& z = r.zoom;
  const ics::ZoomLevels& levels = z.levels;
  const Units units;  // h-scaled: Mpc/h, Msun/h, km/s
  ics::CosmologicalBoxParams c = r.cosmo;
  const int np = 1 << levels.parent;
  const std::size_t parent_cells = static_cast<std::size_t>(np) * np * np;
  if (z.parent.empty() != z.groups.empty())
    throw InputError("options --parent and --groups go together: the parent run's snapshot at z = 0 and its catalogue");
  if (z.parent.empty()) {
    if (z.mass_scale != 1.0) throw InputError("option --mass-scale scales a zoom: give --parent and --groups too");
    // The parent run: dark matter only, one particle per parent-level cell.
    c.gas = false;
    const ics::CosmologicalBox box = ics::make_zoom(c, levels, {}, units);
    io::write_initial_conditions(r.output, box.gas, box.dark_matter, box.box, cosmological_ic_info(r, c, box.a, units));
    return fmt::format("wrote {} (the parent run of zoom levels {}, {}, {}: {}^3 dark matter particles of {:.4g} Msun/h, "
                       "box {} Mpc/h, z = {})",
                       r.output, levels.coarsest, levels.parent, levels.finest, np, box.dark_matter.mass[0], c.box,
                       1.0 / c.a_start - 1.0);
  }
  const io::FofHalos halos = io::read_fof_halos(z.groups);
  const std::size_t halo = choose_halo(halos, z, z.groups);
  const io::GroupInput parent = io::read_group_input(z.parent);
  if (std::fabs(parent.box / c.box - 1.0) > 1e-6)
    throw InputError(fmt::format("{}: BoxSize = {} differs from --box = {}", z.parent, parent.box, c.box));
  // The parent's particle of cell n has ID 1 + n: its Lagrangian cell.
  const Vec3 centre = halos.centre[halo];
  const double r200 = halos.r200[halo];
  const double per_cell = std::pow(8.0, levels.finest - levels.parent);
  std::vector<std::uint8_t> region;
  double factor = 0.0, n_high = 0.0;
  for (double f : {2.0, 2.5, 3.0, 3.5, 4.0, 5.0}) {
    std::vector<std::uint8_t> traced(parent_cells, 0);
    for (std::size_t i = 0; i < parent.particles.size(); ++i) {
      if (parent.particles.type[i] != 1) continue;
      const std::uint64_t id = parent.particles.id[i];
      if (id < 1 || id > parent_cells)
        throw InputError(fmt::format("{}: particle ID {} is not a cell of the parent level {} ({}^3 cells): not the parent "
                                     "run of these levels",
                                     z.parent, id, levels.parent, np));
      if (periodic_distance(centre, parent.particles.x[i], c.box) < f * r200) traced[id - 1] = 1;
    }
    region = ics::dilate(traced, levels.parent, 1);
    factor = f;
    n_high = per_cell * static_cast<double>(std::count(region.begin(), region.end(), std::uint8_t{1}));
    if (n_high >= z.target) break;
  }
  ics::CosmologicalBox box = ics::make_zoom(c, levels, region, units);
  if (z.mass_scale != 1.0) scale_box(box, z.mass_scale);
  io::write_initial_conditions(r.output, box.gas, box.dark_matter, box.box, cosmological_ic_info(r, c, box.a, units));
  std::size_t high = 0;
  for (Species s : box.dark_matter.species) high += s == Species::DarkMatter;
  return fmt::format("wrote {} (zoom on group {} of {}: M_200 = {:.4g} Msun/h, R_200 = {:.4g} Mpc/h; the particles within "
                     "{} R_200 traced back; {} high-resolution dark matter{} particles, {} low-resolution; z = {}{}){}",
                     r.output, halo, z.groups, halos.m200[halo], r200, factor, high, c.gas ? " and gas" : "",
                     box.dark_matter.size() - high, 1.0 / c.a_start - 1.0,
                     z.mass_scale != 1.0 ? fmt::format("; scaled to masses x {:g}, box {:.5g} Mpc/h", z.mass_scale, box.box)
                                         : std::string(),
                     n_high < z.target ? fmt::format("\nwarning: {:.0f} high-resolution particles per species, under the "
                                                     "{:.0f} wanted even at 5 R_200",
                                                     n_high, z.target)
                                       : std::string());
}

}  // namespace fountain
