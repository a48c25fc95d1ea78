// Whether METIS would share a run's work among ranks better than the Hilbert-curve cut: both
// partition every step's measured task times per leaf, and the ranks' work and the ghost bytes
// between them are compared, written as JSON. Usage:
//   fountain_partition_bench PARAMS.yml [-t 2] [--ranks 2,4,8] [--json F]
// The run is the parameter file's, to its end, in one process (writing its outputs, over an
// earlier run's); the ranks are modelled, not started.
#include <metis.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numeric>
#include <string>
#include <vector>

#include "BenchMain.hpp"
#include "app/RunSetup.hpp"
#include "domain/RankLayout.hpp"
#include "engine/CellMessages.hpp"
#include "params/ParameterFile.hpp"

namespace fountain {
namespace {

// One step's leaves: their measured task time, their neighbours (slots) and the bytes of
// their ghost results, which a rank owning a neighbour must receive.
struct StepGraph {
  std::vector<int> leaves;
  std::vector<double> work;                 // ns
  std::vector<std::vector<int>> neighbours;  // slots, without the leaf itself
  std::vector<double> bytes;                // per ghost message of the leaf
};

// What a partition gives one step: the busiest rank's work and the ghost bytes sent.
struct Outcome {
  double max_work = 0.0, mean_work = 0.0, bytes = 0.0;
};

Outcome evaluate(const StepGraph& g, const std::vector<int>& owner, int ranks) {
  Outcome o;
  std::vector<double> work(static_cast<std::size_t>(ranks), 0.0);
  for (std::size_t l = 0; l < g.leaves.size(); ++l) work[static_cast<std::size_t>(owner[l])] += g.work[l];
  o.max_work = *std::max_element(work.begin(), work.end());
  o.mean_work = std::accumulate(work.begin(), work.end(), 0.0) / ranks;
  // A leaf's results go once to each other rank that owns one of its neighbours (active ones:
  // a leaf with no measured work ran no task and sends nothing).
  for (std::size_t l = 0; l < g.leaves.size(); ++l) {
    if (g.work[l] <= 0.0) continue;
    std::vector<int> readers;
    for (const int n : g.neighbours[l])
      if (owner[static_cast<std::size_t>(n)] != owner[l]) readers.push_back(owner[static_cast<std::size_t>(n)]);
    std::sort(readers.begin(), readers.end());
    o.bytes += g.bytes[l] * static_cast<double>(std::unique(readers.begin(), readers.end()) - readers.begin());
  }
  return o;
}

std::vector<int> curve_owners(const Space& space, const StepGraph& g, int ranks) {
  // The engine's own cut (domain::RankLayout), from these costs, as a fresh cut.
  domain::RankLayout layout(0, ranks, false, 0.0, 0);
  std::vector<std::pair<Vec3, double>> measured;
  measured.reserve(g.leaves.size());
  for (std::size_t l = 0; l < g.leaves.size(); ++l) measured.emplace_back(space.cell(g.leaves[l]).centre(), g.work[l]);
  layout.assign_owners(space, measured, 0);
  std::vector<int> owner(g.leaves.size());
  for (std::size_t l = 0; l < g.leaves.size(); ++l) owner[l] = layout.owner(g.leaves[l]);
  return owner;
}

// METIS's k-way partition with the work as vertex weights (us, at least 1) and the bytes a
// cut edge would cost as edge weights; ufactor: METIS's load tolerance, in thousandths.
std::vector<int> metis_owners(const StepGraph& g, int ranks, int ufactor) {
  const auto n = static_cast<idx_t>(g.leaves.size());
  std::vector<idx_t> xadj{0}, adjncy, adjwgt, vwgt;
  for (std::size_t l = 0; l < g.leaves.size(); ++l) {
    vwgt.push_back(static_cast<idx_t>(std::llround(g.work[l] * 1e-3)) + 1);
    for (const int m : g.neighbours[l]) {
      adjncy.push_back(m);
      adjwgt.push_back(static_cast<idx_t>(std::llround(g.bytes[l] + g.bytes[static_cast<std::size_t>(m)])) + 1);
    }
    xadj.push_back(static_cast<idx_t>(adjncy.size()));
  }
  idx_t ncon = 1, nparts = ranks, objval = 0;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;
  options[METIS_OPTION_UFACTOR] = ufactor;
  std::vector<idx_t> part(g.leaves.size(), 0);
  idx_t nv = n;
  if (ranks > 1 && n > 0) {
    const int rc = METIS_PartGraphKway(&nv, &ncon, xadj.data(), adjncy.data(), vwgt.data(), nullptr, adjwgt.data(),
                                       &nparts, nullptr, nullptr, options, &objval, part.data());
    if (rc != METIS_OK) throw std::runtime_error(fmt::format("METIS_PartGraphKway failed ({})", rc));
  }
  return {part.begin(), part.end()};
}

int run(int argc, char** argv, const tasks::MpiSession& mpi) {
  CLI::App app{"Fountain: METIS against the Hilbert-curve cut on a run's measured costs"};
  std::string params_path, json_path, ranks_list = "2,4,8";
  long long threads = 2;
  app.add_option("params", params_path)->required();
  app.add_option("-t,--threads", threads);
  app.add_option("--ranks", ranks_list, "rank counts modelled, comma-separated");
  app.add_option("--json", json_path);
  CLI11_PARSE(app, argc, argv);
  std::vector<int> rank_counts;
  for (std::size_t at = 0; at < ranks_list.size();) {
    const std::size_t comma = std::min(ranks_list.find(',', at), ranks_list.size());
    rank_counts.push_back(std::stoi(ranks_list.substr(at, comma - at)));
    at = comma + 1;
  }

  const ParameterFile params = ParameterFile::load(params_path);
  RunOptions options;
  options.quiet = true;
  options.threads = threads;
  options.overwrite = true;
  RunStart start = prepare_run(params, options);
  Engine e(start.config, std::move(start.ic.gas), std::move(start.ic.dm));
  start_engine(e, start, params, options, true);
  e.set_record_timeline(true);

  // Per rank count and method: summed over steps, the busiest rank's work, the mean, and bytes.
  const std::vector<std::pair<std::string, int>> methods = {{"curve", 0}, {"metis", 30}, {"metis_tight", 1}};
  std::map<std::pair<int, std::string>, Outcome> total;
  long long steps = 0, skipped = 0;
  while (!e.finished()) {
    e.step();
    if (&e.records_graph() != &e.graph()) {  // recut after the graph ran: its leaves are gone
      ++skipped;
      continue;
    }
    const Space& space = e.space();
    StepGraph g;
    g.leaves = space.leaves();
    std::vector<int> slot(space.cells().size(), -1);
    for (std::size_t l = 0; l < g.leaves.size(); ++l) slot[static_cast<std::size_t>(g.leaves[l])] = static_cast<int>(l);
    g.work.assign(g.leaves.size(), 0.0);
    const auto& records = e.last_records();
    for (std::size_t t = 0; t < records.size(); ++t) {
      const tasks::Task& task = e.graph().task(static_cast<int>(t));
      if (task.ci < 0 || records[t].end_ns <= records[t].start_ns) continue;
      const int l = slot[static_cast<std::size_t>(task.ci)];
      if (l >= 0) g.work[static_cast<std::size_t>(l)] += static_cast<double>(records[t].end_ns - records[t].start_ns);
    }
    g.neighbours.resize(g.leaves.size());
    g.bytes.resize(g.leaves.size());
    for (std::size_t l = 0; l < g.leaves.size(); ++l) {
      for (const int c : space.neighbours(g.leaves[l]))
        if (c != g.leaves[l] && slot[static_cast<std::size_t>(c)] >= 0) g.neighbours[l].push_back(slot[static_cast<std::size_t>(c)]);
      g.bytes[l] = static_cast<double>(ghost_results_bytes(space, g.leaves[l]));
    }
    // METIS wants a symmetric graph: a pair listed one way only is added the other way.
    for (std::size_t l = 0; l < g.leaves.size(); ++l)
      for (const int m : std::vector<int>(g.neighbours[l])) {
        auto& back = g.neighbours[static_cast<std::size_t>(m)];
        if (std::find(back.begin(), back.end(), static_cast<int>(l)) == back.end()) back.push_back(static_cast<int>(l));
      }
    for (const int ranks : rank_counts)
      for (const auto& [name, ufactor] : methods) {
        const std::vector<int> owner = name == "curve" ? curve_owners(space, g, ranks) : metis_owners(g, ranks, ufactor);
        const Outcome o = evaluate(g, owner, ranks);
        Outcome& sum = total[{ranks, name}];
        sum.max_work += o.max_work;
        sum.mean_work += o.mean_work;
        sum.bytes += o.bytes;
      }
    ++steps;
  }
  std::string rows;
  for (const auto& [key, o] : total) {
    if (!rows.empty()) rows += ", ";
    rows += fmt::format(
        "{{\"ranks\": {}, \"method\": \"{}\", \"imbalance\": {:.4f}, \"ghost_bytes_per_step\": {:.4g}}}", key.first,
        key.second, o.max_work / o.mean_work - 1.0, o.bytes / static_cast<double>(std::max(1LL, steps)));
  }
  const std::string json =
      fmt::format("{{\"problem\": \"{}\", \"leaves_last\": {}, \"steps\": {}, \"steps_skipped\": {}, \"threads\": {}, "
                  "\"partitions\": [{}]}}\n",
                  params_path, e.space().leaves().size(), steps, skipped, threads, rows);
  bench::report_json(mpi, json, json_path);
  return 0;
}

}  // namespace
}  // namespace fountain

int main(int argc, char** argv) { return fountain::bench::main_reporting_errors(argc, argv, fountain::run); }
