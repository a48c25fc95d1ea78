// `fountain mass-function`: a friends-of-friends catalogue's halo counts against the Jenkins et al. and Sheth & Tormen mass functions.
#pragma once
#include <string>

namespace fountain {

struct MassFunctionRequest {
  std::string catalogue;            // from `fountain fof`
  std::string output;               // the table (text)
  double sigma_8 = 0.9, n_s = 1.0;  // the initial conditions' spectrum (not in the catalogue)
  double omega_b = -1.0;            // >= 0: instead of the catalogue's OmegaBaryon (default 0.04 without one)
  std::string transfer = "full";    // full | no_wiggle | zero_baryon, as `fountain ic cosmo --transfer`
  double log_min = 12.1, log_max = 15.1, width = 0.25;  // bins of log10(M / (Msun/h))
};

// Counts the catalogue's groups by FOF mass in the bins, writes each bin's count beside the
// counts both fits expect in the box at the catalogue's epoch, and returns the summary line.
std::string write_mass_function(const MassFunctionRequest& request);

}  // namespace fountain
