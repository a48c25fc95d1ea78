// Google Benchmark microbenchmarks of the pure SPH pair interactions, the gravity walk and the periodic mesh.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <span>
#include <vector>

#include "gravity/GravityTree.hpp"
#include "gravity/PeriodicMesh.hpp"
#include "hydro/HydroIact.hpp"
#include "ics/Lattice.hpp"
#include "space/Space.hpp"
#include "tasks/Executor.hpp"

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

// The rotating sphere once collapsed (where its runs spend their time): 8000 dark-matter
// particles in a Plummer sphere of scale 20 (kpc) around 8000 gas particles in an exponential
// disc of scale length 3 and height 0.3, softenings 1 and 0.5, G = 1, total mass 1. The
// targets are the disc's particles, in order of x (as cells pass their active particles).
struct CollapsedDisc {
  std::vector<Vec3> pos;
  std::vector<double> mass, eps;
  std::vector<gravity::GravityTarget> targets;

  CollapsedDisc() {
    const int n = 8000;
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    mass.assign(2 * n, 1.0 / (2 * n));
    for (int i = 0; i < n; ++i) {  // Plummer radii by inverting M(<r), capped at 10 scale radii
      const double m = std::min(U(rng), 0.999);
      const double r = 20.0 / std::sqrt(std::pow(m, -2.0 / 3.0) - 1.0);
      const double c = 2.0 * U(rng) - 1.0, phi = 2.0 * M_PI * U(rng), s = std::sqrt(1.0 - c * c);
      pos.push_back({r * s * std::cos(phi), r * s * std::sin(phi), r * c});
      eps.push_back(1.0);
    }
    for (int i = 0; i < n; ++i) {
      const double R = -3.0 * std::log((1.0 - U(rng)) * (1.0 - U(rng))), phi = 2.0 * M_PI * U(rng);
      const double z = 0.3 * std::log(U(rng) / (1.0 - U(rng) + 1e-300)) * 0.5;
      pos.push_back({R * std::cos(phi), R * std::sin(phi), z});
      eps.push_back(0.5);
      targets.push_back({pos.back(), 0.5, gravity::kNoOldAcceleration, n + i});
    }
    std::sort(targets.begin(), targets.end(), [](const auto& a, const auto& b) { return a.position.x < b.position.x; });
  }
};

// Walks of the disc's targets, 128 at a time, with |a_old| from a first Barnes-Hut pass: the
// relative criterion at alpha_force = 0.01, as in the runs. Items are targets; the argument is
// the tree's leaf size.
void BM_GravityCollapsedDisc(benchmark::State& state) {
  CollapsedDisc d;
  auto& targets = d.targets;
  gravity::TreeConfig tree_config;
  tree_config.max_leaf_size = static_cast<int>(state.range(0));
  const gravity::GravityTree tree(d.pos, d.mass, d.eps, tree_config);
  gravity::WalkConfig config;
  std::vector<gravity::GravityResult> results(targets.size());
  auto walk_all = [&] {
    for (std::size_t b = 0; b < targets.size(); b += 128) {
      const std::size_t m = std::min<std::size_t>(128, targets.size() - b);
      tree.accelerate(std::span(targets).subspan(b, m), config, std::span(results).subspan(b, m));
    }
  };
  walk_all();
  for (std::size_t i = 0; i < targets.size(); ++i) targets[i].a_old = norm(results[i].acceleration);
  double near = 0.0;
  for (auto _ : state) {
    walk_all();
    benchmark::DoNotOptimize(results.data());
  }
  for (const auto& r : results) near += static_cast<double>(r.particle_interactions);
  state.counters["particles_per_target"] = near / static_cast<double>(results.size());
  state.SetItemsProcessed(static_cast<long>(state.iterations()) * static_cast<long>(targets.size()));
}
BENCHMARK(BM_GravityCollapsedDisc)->Arg(4)->Arg(8)->Arg(16)->Unit(benchmark::kMillisecond);

// The tree over the disc's 16,000 particles built anew (argument 0) or refitted to positions
// moved by a small step (argument 1), as the engine's tree task does after a rebuild and in
// the steps between. Items are particles.
void BM_GravityTreeUpdate(benchmark::State& state) {
  CollapsedDisc d;
  const bool refit = state.range(0) == 1;
  gravity::GravityTree tree(d.pos, d.mass, d.eps);
  std::vector<Vec3> moved = d.pos;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> U(-1e-3, 1e-3);
  for (Vec3& x : moved) x += Vec3{U(rng), U(rng), U(rng)};
  for (auto _ : state) {
    if (refit) tree.refit(moved, d.mass, d.eps);
    else tree = gravity::GravityTree(moved, d.mass, d.eps);
    benchmark::DoNotOptimize(tree.nodes().data());
  }
  state.SetItemsProcessed(static_cast<long>(state.iterations()) * static_cast<long>(moved.size()));
}
BENCHMARK(BM_GravityTreeUpdate)->ArgName("refit")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The recut of the cells alone (Space::recut: top-level sort, octree split, each leaf's
// particle order, the permutation of every field) over a 250,000-particle BCC lattice in a
// periodic box, nudged between recuts as particles are between the engine's rebuilds, on 1
// or 2 executor threads (the argument). Items are particles.
// The Space benchmarks' set-up: a 250,000-particle BCC lattice (h = 0.025) in a periodic
// unit box, recut once, on `threads` executor threads.
struct RecutLattice {
  tasks::Executor executor;
  ForEach for_each;
  GasParticles gas;
  CollisionlessParticles dm;
  Space space;
  explicit RecutLattice(int threads) : executor(threads), space(periodic_unit_box()) {
    for_each = [this](std::size_t n, const std::function<void(std::size_t)>& fn) { executor.for_each(n, fn); };
    const std::vector<Vec3> lattice = ics::bcc_lattice({0.0, 0.0, 0.0}, {1.0, 1.0, 1.0}, 50, 50, 50);
    gas.resize(lattice.size());
    gas.x = lattice;
    for (std::size_t i = 0; i < gas.size(); ++i) {
      gas.h[i] = 0.025;
      gas.id[i] = i;
    }
    space.recut(gas, dm, for_each);
  }
  static SpaceConfig periodic_unit_box() {
    SpaceConfig config;
    config.periodic = true;
    config.box_size = {1.0, 1.0, 1.0};
    return config;
  }
};

void BM_SpaceRecut(benchmark::State& state) {
  RecutLattice l(static_cast<int>(state.range(0)));
  GasParticles& gas = l.gas;
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> U(-2e-3, 2e-3);
  for (auto _ : state) {
    state.PauseTiming();
    for (Vec3& x : gas.x) x += Vec3{U(rng), U(rng), U(rng)};
    state.ResumeTiming();
    l.space.recut(gas, l.dm, l.for_each);
    benchmark::DoNotOptimize(gas.x.data());
  }
  state.SetItemsProcessed(static_cast<long>(state.iterations()) * static_cast<long>(gas.size()));
}
BENCHMARK(BM_SpaceRecut)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// The neighbour lists of the leaves alone (Space::find_neighbours) over the recut lattice of
// BM_SpaceRecut (250,000 particles, periodic, split size 256), on 1 or 2 executor threads.
// Items are leaves.
void BM_SpaceFindNeighbours(benchmark::State& state) {
  RecutLattice l(static_cast<int>(state.range(0)));
  const Space& space = l.space;
  for (auto _ : state) {
    l.space.find_neighbours(l.for_each);
    benchmark::DoNotOptimize(space.neighbours(space.leaves().front()).data());
  }
  state.counters["leaves"] = static_cast<double>(space.leaves().size());
  state.counters["top_cells"] = static_cast<double>(space.top_grid()[0] * space.top_grid()[1] * space.top_grid()[2]);
  state.SetItemsProcessed(static_cast<long>(state.iterations()) * static_cast<long>(space.leaves().size()));
}
BENCHMARK(BM_SpaceFindNeighbours)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// Periodic TreePM's two halves over 64^3 = 262,144 particles placed at random in a unit box
// (a cosmological box's early state), on `threads` executor threads. BM_PeriodicMesh: one
// long-range force computation on a mesh of the first argument's cells per side (assignment,
// two FFTs, gradient and interpolation). BM_PeriodicTreeShortRange: the tree's short range
// (build excluded) at r_s = 1.25 cells of a 128^3 mesh, relative criterion alpha_force 0.01
// with |a_old| from a first walk. Items are particles.
struct PeriodicBox {
  tasks::Executor executor;
  ForEach for_each;
  std::vector<Vec3> x;
  std::vector<double> m, eps;
  explicit PeriodicBox(int threads) : executor(threads) {
    for_each = [this](std::size_t n, const std::function<void(std::size_t)>& fn) { executor.for_each(n, fn); };
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    const std::size_t n = 64 * 64 * 64;
    x.resize(n);
    for (Vec3& p : x) p = {U(rng), U(rng), U(rng)};
    m.assign(n, 1.0 / static_cast<double>(n));
    eps.assign(n, 1.0 / 64 / 30);
  }
};

void BM_PeriodicMesh(benchmark::State& state) {
  const int cells = static_cast<int>(state.range(0));
  PeriodicBox box(static_cast<int>(state.range(1)));
  gravity::PeriodicMesh mesh(cells, 1.0, gravity::PeriodicMesh::default_split_scale(cells, 1.0), 1.0);
  std::vector<Vec3> acc(box.x.size());
  std::vector<double> pot(box.x.size());
  for (auto _ : state) {
    mesh.compute(box.x, box.m, acc, pot, box.for_each);
    benchmark::DoNotOptimize(acc.data());
  }
  state.SetItemsProcessed(static_cast<long>(state.iterations()) * static_cast<long>(box.x.size()));
}
BENCHMARK(BM_PeriodicMesh)->ArgNames({"cells", "threads"})->Args({64, 1})->Args({128, 1})->Args({128, 2})->Unit(benchmark::kMillisecond);

void BM_PeriodicTreeShortRange(benchmark::State& state) {
  PeriodicBox box(static_cast<int>(state.range(0)));
  gravity::TreeConfig tree_config;
  tree_config.periodic = true;
  tree_config.box_size = 1.0;
  const gravity::GravityTree tree(box.x, box.m, box.eps, tree_config);
  gravity::WalkConfig config;
  config.split = gravity::GravitySplit{gravity::PeriodicMesh::default_split_scale(128, 1.0)};
  std::vector<gravity::GravityTarget> targets(box.x.size());
  for (std::size_t i = 0; i < targets.size(); ++i)
    targets[i] = {box.x[i], box.eps[i], gravity::kNoOldAcceleration, static_cast<std::int64_t>(i)};
  std::vector<gravity::GravityResult> results(targets.size());
  tree.accelerate(targets, config, results, box.for_each);
  for (std::size_t i = 0; i < targets.size(); ++i) targets[i].a_old = norm(results[i].acceleration);
  for (auto _ : state) {
    tree.accelerate(targets, config, results, box.for_each);
    benchmark::DoNotOptimize(results.data());
  }
  double interactions = 0.0;
  for (const auto& r : results) interactions += static_cast<double>(r.interactions());
  state.counters["interactions_per_target"] = interactions / static_cast<double>(results.size());
  state.SetItemsProcessed(static_cast<long>(state.iterations()) * static_cast<long>(box.x.size()));
}
BENCHMARK(BM_PeriodicTreeShortRange)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
