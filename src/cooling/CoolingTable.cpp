#include "cooling/CoolingTable.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/Error.hpp"

namespace fountain::cooling {

namespace {

constexpr int kRows = 91;  // log T = 4.00 ... 8.50 in 0.05 dex
constexpr double kStep = 0.05;

struct Table {
  std::array<double, kRows> log_lambda{}, ne{}, nt{}, mubar{};
};

// Reads one .cie file; rows that do not hold 12 numbers are skipped. Missing low-T rows
// (m+05 starts at log T = 4.10) take the first tabulated values.
Table read_cie(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(fmt::format("{}: cannot open the cooling table", path));
  Table t;
  std::array<bool, kRows> have{};
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    std::array<double, 12> v{};
    int n = 0;
    while (n < 12 && ss >> v[static_cast<std::size_t>(n)]) ++n;
    if (n != 12) continue;
    const int row = static_cast<int>(std::lround((v[0] - CoolingTable::log_t_min) / kStep));
    if (row < 0 || row >= kRows) continue;
    t.ne[row] = v[1];
    t.nt[row] = v[3];
    t.log_lambda[row] = v[5];
    t.mubar[row] = v[11] * 1e-24;
    have[row] = true;
  }
  int first = 0;
  while (first < kRows && !have[first]) ++first;
  if (first == kRows) throw InputError(fmt::format("{}: no table rows", path));
  for (int r = 0; r < kRows; ++r) {
    if (have[r]) continue;
    if (r > first) throw InputError(fmt::format("{}: row for log T = {:.2f} is missing", path, 4.0 + r * kStep));
    t.ne[r] = t.ne[first], t.nt[r] = t.nt[first], t.log_lambda[r] = t.log_lambda[first], t.mubar[r] = t.mubar[first];
  }
  return t;
}

}  // namespace

CoolingTable::CoolingTable(const std::string& directory, const std::string& metallicity) {
  // [Fe/H] of each file; the primordial table sits below the lowest metal table, and the range of
  // metallicities is the tables' own, [-3, 0.5] (no blend with primordial gas is invented).
  const std::vector<std::pair<double, std::string>> files = {
      {-4.0, "mzero.cie"}, {-3.0, "m-30.cie"}, {-2.0, "m-20.cie"}, {-1.5, "m-15.cie"},
      {-1.0, "m-10.cie"},  {-0.5, "m-05.cie"}, {0.0, "m-00.cie"},  {0.5, "m+05.cie"}};
  double fe_h = -4.0;
  if (metallicity != "primordial") {
    char* end = nullptr;
    fe_h = std::strtod(metallicity.c_str(), &end);
    if (end == metallicity.c_str() || *end != '\0' || !(fe_h >= -3.0 && fe_h <= 0.5))
      throw InputError(fmt::format("key 'cooling.metallicity' must be 'primordial' or [Fe/H] in [-3, 0.5], got '{}'",
                                   metallicity));
  }
  std::size_t k = 0;
  while (k + 2 < files.size() && files[k + 1].first < fe_h) ++k;
  const double w = std::clamp((fe_h - files[k].first) / (files[k + 1].first - files[k].first), 0.0, 1.0);
  const Table a = read_cie(directory + "/" + files[k].second);
  const Table b = w > 0.0 ? read_cie(directory + "/" + files[k + 1].second) : a;
  for (int r = 0; r < kRows; ++r) {
    log_lambda_.push_back((1 - w) * a.log_lambda[r] + w * b.log_lambda[r]);
    ne_.push_back((1 - w) * a.ne[r] + w * b.ne[r]);
    nt_.push_back((1 - w) * a.nt[r] + w * b.nt[r]);
    mubar_.push_back((1 - w) * a.mubar[r] + w * b.mubar[r]);
  }
}

double CoolingTable::interpolate(const std::vector<double>& column, double log_t) const {
  const double x = std::clamp((log_t - log_t_min) / kStep, 0.0, static_cast<double>(kRows - 1));
  const int r = std::min(static_cast<int>(x), kRows - 2);
  const double w = x - r;
  return (1 - w) * column[static_cast<std::size_t>(r)] + w * column[static_cast<std::size_t>(r) + 1];
}

double CoolingTable::log_lambda_norm(double log_t) const { return interpolate(log_lambda_, log_t); }
double CoolingTable::electrons_per_h(double log_t) const { return interpolate(ne_, log_t); }
double CoolingTable::ions_per_h(double log_t) const { return interpolate(nt_, log_t); }
double CoolingTable::mean_particle_mass_g(double log_t) const { return interpolate(mubar_, log_t); }

}  // namespace fountain::cooling
