// Google Benchmark microbenchmarks of the pure SPH pair interactions.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "hydro/HydroIact.hpp"

using namespace fountain;

namespace {

struct Pairs {
  std::vector<Vec3> dx, dv;
  Pairs() {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> U(-0.5, 0.5);
    for (int k = 0; k < 1024; ++k) {
      dx.push_back({U(rng), U(rng), U(rng)});
      dv.push_back({U(rng), U(rng), U(rng)});
    }
  }
};

void BM_DensityInteraction(benchmark::State& state) {
  const Pairs p;
  for (auto _ : state) {
    hydro::DensitySums s;
    for (std::size_t k = 0; k < p.dx.size(); ++k)
      hydro::iact_density(p.dx[k], p.dv[k], dot(p.dx[k], p.dx[k]), 1.0, 1.0, s);
    benchmark::DoNotOptimize(s);
  }
  state.SetItemsProcessed(static_cast<long>(state.iterations()) * 1024);
}
BENCHMARK(BM_DensityInteraction);

void BM_ForceInteraction(benchmark::State& state) {
  const Pairs p;
  HydroParams hp;
  const auto a = hydro::make_force_state({0, 0, 0}, 1.0, 1.0, 1.0, 1.0, -0.1, {0.1, 0, 0}, hp);
  for (auto _ : state) {
    hydro::ForceSums s;
    for (std::size_t k = 0; k < p.dx.size(); ++k) {
      auto b = a;
      b.v = p.dv[k];
      hydro::iact_force(a, b, p.dx[k], dot(p.dx[k], p.dx[k]), hp, s);
    }
    benchmark::DoNotOptimize(s);
  }
  state.SetItemsProcessed(static_cast<long>(state.iterations()) * 1024);
}
BENCHMARK(BM_ForceInteraction);

}  // namespace

BENCHMARK_MAIN();
