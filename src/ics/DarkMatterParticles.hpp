// Collisionless (dark matter) particles as written to /PartType1 of GADGET-layout files.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/Vec3.hpp"

namespace fountain::ics {

// Structure of arrays, one entry per particle: only what initial conditions need.
struct DarkMatterParticles {
  std::vector<std::uint64_t> id;
  std::vector<double> mass;
  std::vector<Vec3> x;  // position
  std::vector<Vec3> v;  // velocity

  std::size_t size() const { return id.size(); }
  void resize(std::size_t n) {
    id.resize(n);
    mass.resize(n);
    x.resize(n);
    v.resize(n);
  }
};

}  // namespace fountain::ics
