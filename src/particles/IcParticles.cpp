#include "particles/IcParticles.hpp"

#include <utility>

namespace fountain {

void IcGasParticles::resize(std::size_t n) {
  id.resize(n);
  mass.resize(n);
  x.resize(n);
  v.resize(n);
  u.resize(n);
  h.resize(n);
}

void IcGasParticles::push_back(std::uint64_t new_id, double m, const Vec3& pos, const Vec3& vel, double energy,
                               double smoothing) {
  id.push_back(new_id);
  mass.push_back(m);
  x.push_back(pos);
  v.push_back(vel);
  u.push_back(energy);
  h.push_back(smoothing);
}

void IcCollisionlessParticles::resize(std::size_t n) {
  id.resize(n);
  species.resize(n, Species::DarkMatter);
  mass.resize(n);
  x.resize(n);
  v.resize(n);
}

void IcCollisionlessParticles::push_back(std::uint64_t new_id, Species s, double m, const Vec3& pos, const Vec3& vel) {
  id.push_back(new_id);
  species.push_back(s);
  mass.push_back(m);
  x.push_back(pos);
  v.push_back(vel);
}

GasParticles to_run_particles(IcGasParticles gas) {
  GasParticles out;
  out.resize(gas.size());  // the table's initial values, then the file's fields over them
  out.mass_initial = gas.mass;
  out.v_full = gas.v;
  out.u_full = gas.u;
  out.id = std::move(gas.id);
  out.mass = std::move(gas.mass);
  out.x = std::move(gas.x);
  out.v = std::move(gas.v);
  out.u = std::move(gas.u);
  out.h = std::move(gas.h);
  return out;
}

CollisionlessParticles to_run_particles(IcCollisionlessParticles dm) {
  CollisionlessParticles out;
  out.resize(dm.size());
  out.v_full = dm.v;
  out.id = std::move(dm.id);
  out.species = std::move(dm.species);
  out.mass = std::move(dm.mass);
  out.x = std::move(dm.x);
  out.v = std::move(dm.v);
  return out;
}

}  // namespace fountain
