// Measures of hydro test runs against their exact solutions (Sod, Sedov, Gresho).
#pragma once
#include <string>
#include <vector>

#include "particles/GasParticles.hpp"

namespace fountain::analysis {

// The exact Sod density profile of a shipped table (x relative to the interface).
class SodExact {
 public:
  explicit SodExact(const std::string& table_path);
  double density(double x) const;

 private:
  std::vector<double> x_, rho_;
};

// Mean |rho - rho_exact| per particle with |x - x0| < half_width (interface at x0).
double sod_density_l1(const GasParticles& gas, const SodExact& exact, double x0 = 1.0, double half_width = 0.5);

// Shock radius of a Sedov blast centred in a periodic box: where the radially binned density,
// outside its peak, falls half way from the peak to the ambient density rho0.
double sedov_shock_radius(const GasParticles& gas, const Vec3& centre, const Vec3& box, double rho0 = 1.0,
                          double r_max = 0.5, int bins = 100);

// The Sedov-Taylor shock radius for gamma = 5/3 (xi0 = 1.15167).
double sedov_exact_radius(double energy, double rho0, double t);

// Mean |v_phi - v_phi,exact| per particle of a Gresho vortex centred at (0.5, 0.5).
double gresho_velocity_l1(const GasParticles& gas);

}  // namespace fountain::analysis
