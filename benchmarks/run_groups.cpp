// Friends-of-friends and HOP on a clustered set of 2 x N^3 particles (dark matter and gas): wall
// time of each finder, groups found, and peak memory, written as JSON. The set stands in for a
// z = 0 box: half the dark matter in Hernquist halos whose particle counts follow dn/dn ~ n^-1.9
// from 32 to 10^5 (a concentration of 7 within the radius of 200 times the mean density), the
// rest uniform; each gas particle sits near a dark matter one (a tenth of the spacing away).
// Under mpirun each rank keeps every R-th particle and both finders run across the ranks;
// the peak memory is the largest rank's. Usage: [mpirun -np R] fountain_group_bench [-n 128] [--threads N] [--json FILE].
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <random>

#include "BenchMain.hpp"
#include "domain/RankExchange.hpp"
#include "engine/CollectivesOverRanks.hpp"
#include "groups/FofAcrossRanks.hpp"
#include "groups/FofCatalogue.hpp"
#include "groups/Hop.hpp"
#include "groups/HopAcrossRanks.hpp"

namespace {

using fountain::Vec3;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

fountain::groups::ParticleSet clustered_box(int n, double box, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  const std::size_t total = static_cast<std::size_t>(n) * n * n;
  const double spacing = box / n;
  std::vector<Vec3> dm;
  dm.reserve(total);
  // Halos: n_h from a power law n^-1.9 in [32, 1e5] by inverse transform, until half are placed.
  while (dm.size() < total / 2) {
    const double lo = std::pow(32.0, -0.9), hi = std::pow(1e5, -0.9);
    const auto members = static_cast<std::size_t>(std::pow(lo + u(rng) * (hi - lo), -1.0 / 0.9));
    const double r200 = spacing * std::cbrt(3.0 * static_cast<double>(members) / (800.0 * std::numbers::pi));
    const double a = r200 / 7.0, cut = r200 / (r200 + a);
    const Vec3 centre{u(rng) * box, u(rng) * box, u(rng) * box};
    for (std::size_t k = 0; k < members && dm.size() < total / 2; ++k) {
      // Hernquist: M(<r) / M(<r200) = (r / (r + a))^2 / cut^2.
      const double s = std::sqrt(u(rng)) * cut, r = a * s / (1.0 - s);
      Vec3 d{g(rng), g(rng), g(rng)};
      Vec3 x = centre + d * (r / norm(d));
      for (int c = 0; c < 3; ++c) x[c] -= box * std::floor(x[c] / box);
      dm.push_back(x);
    }
  }
  while (dm.size() < total) dm.push_back({u(rng) * box, u(rng) * box, u(rng) * box});
  fountain::groups::ParticleSet set;
  const double m_dm = 0.85, m_gas = 0.15;
  for (std::size_t i = 0; i < total; ++i) set.push_back(dm[i], {}, m_dm, i + 1, 1);
  for (std::size_t i = 0; i < total; ++i) {
    Vec3 x = dm[i] + Vec3{g(rng), g(rng), g(rng)} * (0.1 * spacing);
    for (int c = 0; c < 3; ++c) x[c] -= box * std::floor(x[c] / box);
    set.push_back(x, {}, m_gas, total + i + 1, 0);
  }
  return set;
}

}  // namespace

int main(int argc, char** argv) {
  return fountain::bench::main_reporting_errors(argc, argv, [](int argc, char** argv, const auto& mpi) {
    CLI::App app{"Friends-of-friends and HOP on a clustered 2 x N^3 set"};
    int n = 128, threads = 0;
    std::string json_path;
    app.add_option("-n", n);
    app.add_option("-t,--threads", threads);
    app.add_option("--json", json_path);
    CLI11_PARSE(app, argc, argv);
    std::unique_ptr<tbb::global_control> limit;
    if (threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    const double box = 100.0;
    fountain::groups::ParticleSet set = clustered_box(n, box, 1);
    const std::size_t total = set.size() / 2;
    const double spacing = box / n;
    const std::unique_ptr<fountain::domain::RankExchange> exchange = fountain::domain::RankExchange::world();
    std::unique_ptr<fountain::CollectivesOverRanks> ranks;
    if (exchange) {
      ranks = std::make_unique<fountain::CollectivesOverRanks>(*exchange);
      fountain::groups::ParticleSet mine;
      for (std::size_t i = static_cast<std::size_t>(exchange->rank()); i < set.size(); i += static_cast<std::size_t>(exchange->size()))
        mine.push_back(set.x[i], set.v[i], set.mass[i], set.id[i], set.type[i]);
      set = std::move(mine);
    }

    auto t0 = std::chrono::steady_clock::now();
    fountain::groups::FofParameters fof;
    fof.linking_length = 0.2 * spacing;
    fof.box = box;
    fof.G = 1.0;
    fof.softening = 0.04 * spacing;
    fof.overdensity = 200.0 * static_cast<double>(total) / (box * box * box);  // 200 times the mean
    const fountain::groups::GroupCatalogue found = fountain::groups::find_fof_groups_across_ranks(set, fof, ranks.get());
    const auto& fof_groups = found.groups;
    const double fof_s = seconds_since(t0);

    fountain::groups::ParticleSet gas;
    for (std::size_t i = 0; i < set.size(); ++i)
      if (set.type[i] == 0) gas.push_back(set.x[i], set.v[i], set.mass[i], set.id[i], 0);
    const std::vector<double> hidden(gas.size(), 0.0);
    const double mean = 0.15 * static_cast<double>(total) / (box * box * box);
    fountain::groups::HopParameters hop;
    hop.box = box;
    hop.delta_outer = 80.0 * mean;
    hop.delta_saddle = 2.5 * hop.delta_outer;
    hop.delta_peak = 3.0 * hop.delta_outer;
    t0 = std::chrono::steady_clock::now();
    const fountain::groups::HopCatalogue hop_groups = fountain::groups::find_hop_groups_across_ranks(gas, hidden, hop, ranks.get());
    const double hop_s = seconds_since(t0);
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    double peak_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;
    if (exchange)
      for (const auto& theirs : exchange->allgather_values(std::span<const double>(&peak_mb, 1), "peak memory"))
        peak_mb = std::max(peak_mb, theirs[0]);
    const std::string json = fmt::format(
        "{{\"benchmark\": \"groups\", \"particles\": {}, \"ranks\": {}, \"threads\": {}, \"fof_s\": {:.3f}, "
        "\"fof_groups\": {}, \"fof_largest\": {}, \"hop_particles\": {}, \"hop_s\": {:.3f}, \"hop_groups\": {}, "
        "\"hop_largest\": {}, \"peak_rss_mb\": {:.1f}}}\n",
        2 * total, exchange ? exchange->size() : 1, threads, fof_s, fof_groups.size(),
        fof_groups.empty() ? 0 : fof_groups[0].members.size(), total, hop_s, hop_groups.groups.size(),
        hop_groups.groups.empty() ? 0 : hop_groups.groups[0].members.size(), peak_mb);
    fountain::bench::report_json(mpi, json, json_path);
    return 0;
  });
}
