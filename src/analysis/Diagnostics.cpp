#include "analysis/Diagnostics.hpp"

#include <algorithm>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <utility>

namespace fountain::analysis {

DiagnosticsSum::DiagnosticsSum(TemperatureOf temperature, const FigurePhases& phases, double a)
    : temperature_(std::move(temperature)),
      phases_(phases),
      a_(a),
      h_min_(std::numeric_limits<double>::infinity()),
      bin_min_(std::numeric_limits<int>::max()) {}

void DiagnosticsSum::add_gas(const GasParticles& gas, std::size_t first, std::size_t count) {
  const double a = a_;
  // Plain runs: every factor is 1 and the sums are those of the state itself.
  const double density = 1.0 / (a * a * a), energy = 1.0 / (a * a), speed = 1.0 / a;
  std::array<double, kSums> part{};  // this call's sums, in doubles in the particles' order
  for (std::size_t i = first; i < first + count; ++i) {
    const double m = gas.mass[i];
    h_min_ = std::min(h_min_, a * gas.h[i]);
    bin_min_ = std::min<int>(bin_min_, gas.time_bin[i]);
    const double m_dyn = gas.dynamical_mass(i);  // hidden stars move with the gas
    const Vec3 v = gas.v[i] * speed;
    const double v2 = dot(v, v), u = gas.u[i] * energy, potential = gas.potential[i] * speed;
    part[kMassGas] += m;
    part[kMassStarsHidden] += gas.mass_stars_hidden[i];
    part[kReservoir] += gas.reservoir[i];
    const double t = temperature_(u);
    const bool cold = phases_.cold(t, gas.rho[i] * density);
    part[phases_.hot(t) ? kMassHot : (cold ? kMassCold : kMassWarm)] += m;
    if (gas.promoted[i] && !cold) part[kMassPromotedDiffuse] += m;
    if (0.5 * v2 + potential > 0.0) part[kMassUnbound] += m;
    part[kThermal] += m * u;
    part[kKinetic] += 0.5 * m_dyn * v2;
    part[kPotential] += 0.5 * m_dyn * potential;
    add_vector(part, kMomentum, v * m_dyn);
    add_vector(part, kAngularMomentum, cross(gas.x[i] * a, v) * m_dyn);
  }
  add_part(part);
  gas_ += count;
}

void DiagnosticsSum::add_collisionless(const CollisionlessParticles& p, std::size_t first, std::size_t count) {
  const double a = a_, speed = 1.0 / a;
  std::array<double, kSums> part{};
  for (std::size_t i = first; i < first + count; ++i) {
    const double m = p.mass[i];
    part[p.species[i] == Species::Star ? kMassStars : kMassDarkMatter] += m;
    const Vec3 v = p.v[i] * speed;
    part[kKinetic] += 0.5 * m * dot(v, v);
    part[kPotential] += 0.5 * m * p.potential[i] * speed;
    add_vector(part, kMomentum, v * m);
    add_vector(part, kAngularMomentum, cross(p.x[i] * a, v) * m);
    bin_min_ = std::min<int>(bin_min_, p.time_bin[i]);
  }
  add_part(part);
  collisionless_ += count;
}

void DiagnosticsSum::add_part(const std::array<double, kSums>& part) {
  for (std::size_t s = 0; s < sums_.size(); ++s) sums_[s].add(part[s]);
}

void DiagnosticsSum::add(const DiagnosticsSum& other) {
  for (std::size_t s = 0; s < sums_.size(); ++s) sums_[s].add(other.sums_[s]);
  h_min_ = std::min(h_min_, other.h_min_);
  bin_min_ = std::min(bin_min_, other.bin_min_);
  gas_ += other.gas_;
  collisionless_ += other.collisionless_;
}

std::vector<char> DiagnosticsSum::pack() const {
  std::vector<char> out;
  auto put = [&](const void* p, std::size_t n) {
    const auto* c = static_cast<const char*>(p);
    out.insert(out.end(), c, c + n);
  };
  for (const ExactSum& s : sums_) {
    const auto words = s.words();
    put(words.data(), sizeof words);
  }
  put(&h_min_, sizeof h_min_);
  put(&bin_min_, sizeof bin_min_);
  put(&gas_, sizeof gas_);
  put(&collisionless_, sizeof collisionless_);
  return out;
}

void DiagnosticsSum::add_packed(std::span<const char> packed) {
  DiagnosticsSum other(temperature_, phases_, a_);
  std::size_t at = 0;
  auto get = [&](void* p, std::size_t n) {
    if (at + n > packed.size()) throw std::logic_error("a packed diagnostics sum is too short");
    std::memcpy(p, packed.data() + at, n);
    at += n;
  };
  std::array<std::int64_t, ExactSum::kWords> words{};
  for (ExactSum& s : other.sums_) {
    get(words.data(), sizeof words);
    s = ExactSum::from_words(words.data());
  }
  get(&other.h_min_, sizeof other.h_min_);
  get(&other.bin_min_, sizeof other.bin_min_);
  get(&other.gas_, sizeof other.gas_);
  get(&other.collisionless_, sizeof other.collisionless_);
  if (at != packed.size()) throw std::logic_error("a packed diagnostics sum is too long");
  add(other);
}

Diagnostics DiagnosticsSum::result() const {
  static constexpr std::pair<int, double Diagnostics::*> kScalars[] = {
      {kMassGas, &Diagnostics::mass_gas},
      {kMassDarkMatter, &Diagnostics::mass_dark_matter},
      {kMassHot, &Diagnostics::mass_hot},
      {kMassWarm, &Diagnostics::mass_warm},
      {kMassCold, &Diagnostics::mass_cold},
      {kMassUnbound, &Diagnostics::mass_unbound},
      {kThermal, &Diagnostics::thermal},
      {kKinetic, &Diagnostics::kinetic},
      {kPotential, &Diagnostics::potential},
      {kMassStars, &Diagnostics::mass_stars},
      {kMassStarsHidden, &Diagnostics::mass_stars_hidden},
      {kMassPromotedDiffuse, &Diagnostics::mass_promoted_diffuse},
      {kReservoir, &Diagnostics::reservoir}};
  Diagnostics d;
  for (const auto& [sum, field] : kScalars) d.*field = sums_[static_cast<std::size_t>(sum)].value();
  for (int k = 0; k < 3; ++k) {
    d.momentum[k] = sums_[static_cast<std::size_t>(kMomentum + k)].value();
    d.angular_momentum[k] = sums_[static_cast<std::size_t>(kAngularMomentum + k)].value();
  }
  d.h_min_gas = gas_ > 0 ? h_min_ : 0.0;
  d.time_bin_min = gas_ + collisionless_ > 0 ? bin_min_ : 0;
  return d;
}

}  // namespace fountain::analysis
