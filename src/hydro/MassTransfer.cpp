#include "hydro/MassTransfer.hpp"

namespace fountain::hydro {

double absorb(GasParticles& gas, std::size_t j, double dm_gas, double dm_hidden, const Vec3& v_src, double u_src,
              double heat) {
  const double m_j = gas.dynamical_mass(j), dm = dm_gas + dm_hidden;
  const Vec3 v_new = (gas.v[j] * m_j + v_src * dm) * (1.0 / (m_j + dm));
  const double lost = 0.5 * m_j * dot(gas.v[j], gas.v[j]) + 0.5 * dm * dot(v_src, v_src) -
                      0.5 * (m_j + dm) * dot(v_new, v_new);
  const double thermal = gas.mass[j] * gas.u[j] + dm_gas * u_src + heat + lost;
  gas.mass[j] += dm_gas;
  gas.mass_stars_hidden[j] += dm_hidden;
  const double u_new = thermal / gas.mass[j];
  if (u_new >= gas.u[j]) {
    // Heated: the predicted and the integrated state move together.
    const double du = u_new - gas.u[j];
    gas.u[j] += du;
    gas.u_full[j] += du;
  } else {
    // Cooled by mixing with colder gas, part-way through its step: scale the integrated
    // energy and the cooling rate with the predicted energy. Subtracting instead could take
    // the integrated energy, or the energy the rest of the step cools to, below zero (the
    // cooling task's implicit rate was solved from the old energy).
    const double f = u_new / gas.u[j];
    gas.u[j] = u_new;
    gas.u_full[j] *= f;
    gas.du_dt[j] += (f - 1.0) * gas.du_dt_cool[j];
    gas.du_dt_cool[j] *= f;
  }
  const Vec3 dv = v_new - gas.v[j];
  gas.v[j] += dv;
  gas.v_full[j] += dv;
  return lost;
}

}  // namespace fountain::hydro
