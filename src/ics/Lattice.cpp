#include "ics/Lattice.hpp"

namespace fountain::ics {

std::vector<Vec3> bcc_lattice(const Vec3& lo, const Vec3& size, int nx, int ny, int nz) {
  std::vector<Vec3> points;
  points.reserve(2 * static_cast<std::size_t>(nx) * ny * nz);
  const Vec3 d{size.x / nx, size.y / ny, size.z / nz};
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j)
      for (int k = 0; k < nz; ++k) {
        const Vec3 corner = lo + Vec3{i * d.x, j * d.y, k * d.z};
        points.push_back(corner);
        points.push_back(corner + d * 0.5);
      }
  return points;
}

}  // namespace fountain::ics
