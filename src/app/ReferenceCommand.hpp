// `fountain reference`: tables of the background cosmology and of Ewald's periodic field, as the validation plots them.
#pragma once
#include <string>

namespace fountain {

struct BackgroundTableRequest {
  double omega_m = 0.3, omega_lambda = 0.7;
  double a_begin = 0.01, a_end = 1.0;  // the integration factors are cumulative from a_begin
  int points = 200;                    // equal steps in ln a
  std::string output;
};

// One row per a: z, E, cosmic time, D, f, D2, f2 and the drift, gravity-kick, hydro-kick and
// time factors from a_begin (internal units: H0 = 100, times in (Mpc/h) / (km/s)). Returns the
// summary line.
std::string write_background_table(const BackgroundTableRequest& request);

struct EwaldTableRequest {
  int points = 1000;        // random points in the box for the convergence table
  int line_points = 101;    // samples along each line through the box
  unsigned long seed = 1;
  std::string output_dir;   // writes lines.txt, published.txt, convergence.txt
};

// The correction field of a unit mass in a unit box (G = 1) along three lines, at the
// published reference points, and the largest error over random points of sums cut at image
// cubes |n_d| <= N and Fourier shells h^2 <= H, against a far wider sum.
std::string write_ewald_tables(const EwaldTableRequest& request);

}  // namespace fountain
