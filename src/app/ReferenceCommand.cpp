// The reference tables behind the validation's background and Ewald figures (docs/validation.md).
#include "app/ReferenceCommand.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <utility>
#include <vector>

#include "app/TextFile.hpp"
#include "core/Error.hpp"
#include "cosmology/Background.hpp"
#include "cosmology/IntegrationFactors.hpp"
#include "gravity/EwaldSummation.hpp"

namespace fountain {

std::string write_background_table(const BackgroundTableRequest& r) {
  // Beyond these a^-3 and a^3 leave double's range in E(a)^2 (and radiation, omitted, would
  // rule long before the lower one).
  if (!(r.a_begin >= 1e-8) || !(r.a_end > r.a_begin) || !(r.a_end <= 1e4))
    throw InputError(fmt::format("--a-begin ({}) and --a-end ({}) must satisfy 1e-8 <= a_begin < a_end <= 1e4",
                                 r.a_begin, r.a_end));
  if (r.points < 2 || r.points > 1000000)
    throw InputError(fmt::format("--points ({}) must be from 2 to 1000000", r.points));
  cosmology::CosmologyParams c;
  c.omega_m = r.omega_m;
  c.omega_lambda = r.omega_lambda;
  const cosmology::Background background(c);
  using Factors = cosmology::IntegrationFactors;
  const Factors factors(background, 5.0 / 3.0, r.a_begin, r.a_end);
  std::string text = fmt::format(
      "# background of Omega_m {}, Omega_Lambda {} (Omega_k {}), internal units: H0 = {}, time in (Mpc/h)/(km/s)\n"
      "# drift, gravity_kick, hydro_kick (gamma 5/3) and time factors integrate from a = {}\n"
      "# a z E t D f D2 f2 drift gravity_kick hydro_kick time\n",
      r.omega_m, r.omega_lambda, c.omega_k(), background.hubble0(), r.a_begin);
  const double ln_begin = std::log(r.a_begin), ln_step = (std::log(r.a_end) - ln_begin) / (r.points - 1);
  for (int i = 0; i < r.points; ++i) {
    const double a = i == r.points - 1 ? r.a_end : std::exp(ln_begin + i * ln_step);
    const cosmology::SecondOrderGrowth g2 = background.second_order_growth(a);
    text += fmt::format("{:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g}\n", a,
                        1.0 / a - 1.0, background.E(a), background.cosmic_time(a), background.growth(a),
                        background.growth_rate(a), g2.d2, g2.f2, factors.cumulative(Factors::drift, a),
                        factors.cumulative(Factors::gravity_kick, a), factors.cumulative(Factors::hydro_kick, a),
                        factors.cumulative(Factors::time, a));
  }
  write_text_file(r.output, text);
  return fmt::format("wrote {} ({} rows, a = {} to {})", r.output, r.points, r.a_begin, r.a_end);
}

namespace {

// For a point with components in (-1/2, 1/2), a reach of N + 1/2 keeps the images n with
// |n_d| <= N and |x - n| <= N + 1/2 (the sum bounds each component, then the distance): the
// image cube of published convergence tables, less far corners whose terms are below 1e-10
// for N >= 2.
gravity::EwaldSettings cut(int images, int fourier_h2, double alpha) {
  gravity::EwaldSettings s;
  s.alpha = alpha;
  s.real_reach = images + 0.5;
  s.fourier_h2 = fourier_h2;
  return s;
}

std::string field_row(const Vec3& x, const gravity::EwaldField& f) {
  return fmt::format("{:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g}\n", x.x, x.y, x.z, f.acceleration.x,
                     f.acceleration.y, f.acceleration.z, f.potential);
}

}  // namespace

std::string write_ewald_tables(const EwaldTableRequest& r) {
  if (r.points < 1 || r.line_points < 2)
    throw InputError(fmt::format("--points ({}) must be positive and --line-points ({}) at least 2", r.points,
                                 r.line_points));
  std::error_code ec;
  std::filesystem::create_directories(r.output_dir, ec);
  if (ec) throw InputError(fmt::format("{}: cannot be created ({})", r.output_dir, ec.message()));
  const std::filesystem::path dir(r.output_dir);

  // Along the x axis, the diagonal and a line through a published point, x from 0 to 1/2.
  std::string lines = "# correction field a_c = a + x/|x|^3 and potential phi + 1/|x| of a unit mass in a unit box "
                      "(G = 1), default sums\n# line x y z acx acy acz phi_c  (lines: 0 (s,0,0), 1 (s,s,s), 2 (s,0.3,0.2))\n";
  for (int line = 0; line < 3; ++line)
    for (int i = 0; i < r.line_points; ++i) {
      const double s = 0.5 * i / (r.line_points - 1);
      const Vec3 x = line == 0 ? Vec3{s, 0.0, 0.0} : line == 1 ? Vec3{s, s, s} : Vec3{s, 0.3, 0.2};
      lines += fmt::format("{} ", line) + field_row(x, gravity::ewald_correction(x, 1.0));
    }
  write_text_file((dir / "lines.txt").string(), lines);

  std::string published = "# the correction field at the published reference points, default sums\n# x y z acx acy acz phi_c\n";
  for (const Vec3& x : {Vec3{0.0, 0.0, 0.0}, Vec3{0.25, 0.0, 0.0}, Vec3{0.1, 0.2, 0.3}, Vec3{0.4, 0.3, 0.2},
                        Vec3{0.5, 0.0, 0.0}, Vec3{0.5, 0.5, 0.5}})
    published += field_row(x, gravity::ewald_correction(x, 1.0));
  write_text_file((dir / "published.txt").string(), published);

  // Random points in the box around the mass; 53-bit doubles from the engine's raw output,
  // so the points are the same with any standard library.
  std::mt19937_64 engine(r.seed);
  std::vector<Vec3> points(static_cast<std::size_t>(r.points));
  for (Vec3& p : points)
    for (int d = 0; d < 3; ++d) p[d] = static_cast<double>(engine() >> 11) * 0x1.0p-53 - 0.5;
  const int wide_images = 8, wide_h2 = 64;
  std::vector<Vec3> reference;
  reference.reserve(points.size());
  for (const Vec3& p : points) reference.push_back(gravity::ewald_correction(p, 1.0, cut(wide_images, wide_h2, 2.0)).acceleration);
  auto largest_difference = [&](const gravity::EwaldSettings& s) {
    double worst = 0.0;
    for (std::size_t i = 0; i < points.size(); ++i)
      worst = std::max(worst, norm(gravity::ewald_correction(points[i], 1.0, s).acceleration - reference[i]));
    return worst;
  };
  struct Row {
    int images;  // -1: Fountain's default sums, cut by distance alone
    gravity::EwaldSettings settings;
  };
  std::vector<Row> rows;
  for (int n = 0; n <= 6; ++n) rows.push_back({n, cut(n, wide_h2, 2.0)});
  for (int h2 : {1, 2, 3, 4, 5, 6, 8, 9, 10, 11, 12, 14, 16}) rows.push_back({wide_images, cut(wide_images, h2, 2.0)});
  for (const auto& [n, h2] : {std::pair{2, 4}, std::pair{3, 8}, std::pair{4, 10}}) rows.push_back({n, cut(n, h2, 2.0)});
  rows.push_back({wide_images, cut(wide_images, wide_h2, 1.5)});
  rows.push_back({-1, gravity::EwaldSettings{}});
  std::string convergence = fmt::format(
      "# largest |a - a_reference| over {} random points (G m / L^2); reference: images |n_d| <= {}, h^2 <= {}, "
      "alpha 2/L\n# images fourier_h2 alpha max_error  (images -1: Fountain's default sums, reach 2.9 L)\n",
      r.points, wide_images, wide_h2);
  for (const Row& row : rows)
    convergence += fmt::format("{} {} {} {:.6e}\n", row.images, row.settings.fourier_h2, row.settings.alpha,
                               largest_difference(row.settings));
  write_text_file((dir / "convergence.txt").string(), convergence);
  return fmt::format("wrote lines.txt, published.txt and convergence.txt in {}", r.output_dir);
}

}  // namespace fountain
