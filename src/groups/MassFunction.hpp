// Halo mass functions of linear theory (Sheth & Tormen 1999, Jenkins et al. 2001) and a catalogue's masses counted against them.
#pragma once
#include <span>
#include <vector>

#include "cosmology/PowerSpectrum.hpp"

namespace fountain::groups {

// The multiplicity functions f(sigma), dn/dln M = (rho_bar / M) f(sigma) dln(1/sigma)/dln M.
// Sheth & Tormen with a = 0.707, p = 0.3, delta_c = 1.686 and A normalising int f dln(1/sigma)
// to one. Jenkins et al.'s FOF (b = 0.2) fit, 0.315 exp(-|ln(1/sigma) + 0.61|^3.8), holds for
// -1.2 <= ln(1/sigma) <= 1.05; outside it the function returns NaN rather than extrapolate.
double sheth_tormen_multiplicity(double sigma);
double jenkins_multiplicity(double sigma);

enum class MassFunctionFit { sheth_tormen, jenkins };

// A mass function from a linear spectrum normalised at z = 0, at the epoch where the linear
// growth has reached `growth` = D(a)/D(1) of today's. Masses in Msun/h, lengths in Mpc/h,
// comoving densities in Msun/h per (Mpc/h)^3, number densities in (h/Mpc)^3 comoving.
class MassFunctionModel {
 public:
  MassFunctionModel(cosmology::LinearPowerSpectrum spectrum, double mean_density, double growth = 1.0);
  double radius(double mass) const;  // of the top hat holding `mass` at the mean density
  double sigma(double mass) const;
  // dln(1/sigma)/dln M by a five-point difference in ln M (step 0.01: error ~1e-10 relative).
  double slope(double mass) const;
  double dn_dln_mass(double mass, MassFunctionFit fit) const;
  // The expected count in a volume between two masses: volume x the integral of dn/dln M over
  // ln M (Simpson, 16 intervals).
  double expected_count(double mass_lo, double mass_hi, double volume, MassFunctionFit fit) const;
  double mean_density() const { return mean_density_; }

 private:
  cosmology::LinearPowerSpectrum spectrum_;
  double mean_density_, growth_;
};

// Groups counted in bins of log10 M, with the counts each fit expects in the same volume
// (NaN where the Jenkins fit does not reach the whole bin).
struct MassFunctionBin {
  double log_lo = 0.0, log_hi = 0.0;
  std::size_t count = 0;
  double sheth_tormen = 0.0, jenkins = 0.0;
};
// Bins [log_min + k width, log_min + (k+1) width) up to log_max; a mass outside them is not
// counted.
std::vector<MassFunctionBin> bin_mass_function(std::span<const double> masses, double volume, const MassFunctionModel& model,
                                               double log_min, double log_max, double width);

}  // namespace fountain::groups
