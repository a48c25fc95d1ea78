// Sutherland & Dopita (1993) CIE cooling tables, interpolated in log T and [Fe/H].
#pragma once
#include <string>
#include <vector>

namespace fountain::cooling {

// One composition interpolated from the SD93 tables: the normalised cooling function
// Lambda_N = Lambda_net / (n_e n_t), n_e/n_H, n_t/n_H and the mean particle mass, against T.
class CoolingTable {
 public:
  // Reads the eight .cie files of `directory` and fixes the composition: `metallicity` is
  // "primordial" or a number [Fe/H] in [-3, 0.5] (interpolated linearly between tables;
  // below -3 towards the primordial table, which sits at [Fe/H] = -4 for that purpose).
  CoolingTable(const std::string& directory, const std::string& metallicity);

  static constexpr double log_t_min = 4.0;
  static constexpr double log_t_max = 8.5;

  // Interpolated in log T (clamped to the table), all at the chosen metallicity.
  double log_lambda_norm(double log_t) const;  // log10 erg cm^3 s^-1
  double electrons_per_h(double log_t) const;
  double ions_per_h(double log_t) const;
  double mean_particle_mass_g(double log_t) const;  // rho / (n_e + n_t)

 private:
  double interpolate(const std::vector<double>& column, double log_t) const;
  std::vector<double> log_lambda_, ne_, nt_, mubar_;  // on the grid log T = 4.00, 4.05, ..., 8.50
};

}  // namespace fountain::cooling
