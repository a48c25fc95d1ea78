#include "particles/GasParticles.hpp"
#include "particles/CollisionlessParticles.hpp"

namespace fountain {

namespace {
template <class T>
void apply(std::vector<T>& field, const std::vector<std::size_t>& order, std::vector<T>& scratch) {
  scratch.resize(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) scratch[k] = field[order[k]];
  field.swap(scratch);
}
}  // namespace

void GasParticles::permute(const std::vector<std::size_t>& order) {
  std::vector<double> sd;
  std::vector<Vec3> sv;
  std::vector<std::uint64_t> si;
  std::vector<TimeBin> sb;
  apply(id, order, si);
  for (auto* f : {&mass, &mass_initial, &mass_stars_hidden, &reservoir, &promotion_time, &feedback_hot_energy,
                  &u_full, &u, &h, &rho, &rho_msph, &h_msph, &wcount, &wcount_dh, &div_v,
                  &balsara, &soundspeed, &p_over_rho_a, &inv_rho_2ma, &du_dt, &du_dt_cool, &potential})
    apply(*f, order, sd);
  for (auto* f : {&x, &v_full, &v, &curl_v, &a_hydro, &a_grav}) apply(*f, order, sv);
  apply(time_bin, order, sb);
  apply(limit_bin, order, sb);
  apply(courant_bin, order, sb);
  apply(wake_bin, order, sb);
  std::vector<std::uint8_t> s8;
  apply(promoted, order, s8);
  std::vector<std::int64_t> st;
  apply(ti_begin, order, st);
}

void CollisionlessParticles::permute(const std::vector<std::size_t>& order) {
  std::vector<double> sd;
  std::vector<Vec3> sv;
  std::vector<std::uint64_t> si;
  std::vector<TimeBin> sb;
  std::vector<std::int64_t> st;
  apply(id, order, si);
  apply(parent_id, order, si);
  std::vector<Species> ss;
  apply(species, order, ss);
  for (auto* f : {&mass, &potential, &birth_time}) apply(*f, order, sd);
  for (auto* f : {&x, &v_full, &v, &a_grav}) apply(*f, order, sv);
  apply(time_bin, order, sb);
  apply(ti_begin, order, st);
}

}  // namespace fountain
