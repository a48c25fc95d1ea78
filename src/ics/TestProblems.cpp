#include "ics/TestProblems.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/Error.hpp"
#include "ics/Lattice.hpp"

namespace fountain::ics {

namespace {

void fill(ProblemIC& ic, const std::vector<Vec3>& points, double mass) {
  GasParticles& g = ic.gas;
  g.resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    g.id[i] = i + 1;
    g.mass[i] = mass;
    g.x[i] = points[i];
    g.h[i] = 0.0;
    g.time_bin[i] = 0;
  }
}

void set_energy(GasParticles& g, std::size_t i, double u) { g.u[i] = g.u_full[i] = u; }
void set_velocity(GasParticles& g, std::size_t i, const Vec3& v) { g.v[i] = g.v_full[i] = v; }

}  // namespace

ProblemIC sod_shock(int cells_left, double gamma) {
  ProblemIC ic;
  ic.box_size = {2.0, 0.5, 0.5};
  const int cl = cells_left, cr = std::max(1, cells_left / 2);
  auto left = bcc_lattice({0, 0, 0}, {1.0, 0.5, 0.5}, cl, cl / 2, cl / 2);
  auto right = bcc_lattice({1.0, 0, 0}, {1.0, 0.5, 0.5}, cr, std::max(1, cr / 2), std::max(1, cr / 2));
  const double mass = 1.0 * 0.5 * 0.5 / static_cast<double>(left.size());
  const std::size_t n_left = left.size();
  left.insert(left.end(), right.begin(), right.end());
  fill(ic, left, mass);
  for (std::size_t i = 0; i < ic.gas.size(); ++i) {
    const bool is_left = i < n_left;
    const double rho = is_left ? 1.0 : 0.125, p = is_left ? 1.0 : 0.1;
    set_energy(ic.gas, i, p / ((gamma - 1.0) * rho));
  }
  return ic;
}

ProblemIC sedov_blast(int cells, double gamma, double energy, double p0, int hot_particles) {
  ProblemIC ic;
  ic.box_size = {1.0, 1.0, 1.0};
  const auto points = bcc_lattice({0, 0, 0}, ic.box_size, cells, cells, cells);
  fill(ic, points, 1.0 / static_cast<double>(points.size()));
  const Vec3 centre{0.5, 0.5, 0.5};
  std::vector<std::size_t> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  const auto dist2 = [&](std::size_t i) { const Vec3 d = points[i] - centre; return dot(d, d); };
  const std::size_t nhot = std::min<std::size_t>(static_cast<std::size_t>(hot_particles), points.size());
  std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(nhot), order.end(),
                    [&](std::size_t a, std::size_t b) { return dist2(a) != dist2(b) ? dist2(a) < dist2(b) : a < b; });
  for (std::size_t i = 0; i < points.size(); ++i) set_energy(ic.gas, i, p0 / ((gamma - 1.0) * 1.0));
  for (std::size_t k = 0; k < nhot; ++k) {
    const std::size_t i = order[k];
    set_energy(ic.gas, i, ic.gas.u[i] + energy / (static_cast<double>(nhot) * ic.gas.mass[i]));
  }
  return ic;
}

double gresho_velocity(double r) {
  if (r < 0.2) return 5.0 * r;
  if (r < 0.4) return 2.0 - 5.0 * r;
  return 0.0;
}

double gresho_pressure(double r) {
  if (r < 0.2) return 5.0 + 12.5 * r * r;
  if (r < 0.4) return 9.0 + 12.5 * r * r - 20.0 * r + 4.0 * std::log(5.0 * r);
  return 3.0 + 4.0 * std::log(2.0);
}

ProblemIC gresho_vortex(int cells, double gamma, int depth_cells) {
  if (depth_cells <= 0) depth_cells = std::max(1, cells / 2);
  ProblemIC ic;
  const double depth = static_cast<double>(depth_cells) / cells;
  ic.box_size = {1.0, 1.0, depth};
  const auto points = bcc_lattice({0, 0, 0}, ic.box_size, cells, cells, depth_cells);
  fill(ic, points, depth / static_cast<double>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double dx = points[i].x - 0.5, dy = points[i].y - 0.5;
    const double r = std::sqrt(dx * dx + dy * dy);
    const double vphi = gresho_velocity(r);
    set_velocity(ic.gas, i, r > 0.0 ? Vec3{-vphi * dy / r, vphi * dx / r, 0.0} : Vec3{});
    set_energy(ic.gas, i, gresho_pressure(r) / ((gamma - 1.0) * 1.0));
  }
  return ic;
}

ProblemIC evrard_sphere(int cells_per_radius) {
  if (cells_per_radius < 2) throw InputError("Evrard sphere: need at least 2 lattice cells per radius");
  const double d = 1.0 / cells_per_radius;
  std::vector<Vec3> points;
  for (int a = -cells_per_radius; a < cells_per_radius; ++a)
    for (int b = -cells_per_radius; b < cells_per_radius; ++b)
      for (int c = -cells_per_radius; c < cells_per_radius; ++c) {
        const Vec3 x{(a + 0.5) * d, (b + 0.5) * d, (c + 0.5) * d};
        const double r = norm(x);
        // M(<r) = r^2 from a uniform ball's M(<r0) = r0^3: r = r0^(3/2).
        if (r < 1.0) points.push_back(x * std::sqrt(r));
      }
  ProblemIC ic;
  ic.periodic = false;
  ic.box_size = {2.0, 2.0, 2.0};
  const std::size_t n = points.size();
  ic.gas.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    ic.gas.id[i] = i + 1;
    ic.gas.mass[i] = 1.0 / static_cast<double>(n);
    ic.gas.x[i] = points[i];
    ic.gas.u[i] = ic.gas.u_full[i] = 0.05;
  }
  return ic;
}

}  // namespace fountain::ics
