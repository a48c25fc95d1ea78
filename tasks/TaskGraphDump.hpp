// Writes task graphs (DOT, SWIFT-style dependency CSV) and per-task timelines (CSV).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "Executor.hpp"
#include "TaskGraph.hpp"

namespace fountain::tasks {

// Graphviz DOT of the dependencies between task types (one node per type, edge counts).
void write_dot(const TaskGraph& graph, const TaskTypeRegistry& types, const std::string& path);

// One row per type-to-type dependency with the columns of SWIFT's dependency_graph_*.csv,
// so SWIFT's plot_task_dependencies.py reads it.
void write_dependency_csv(const TaskGraph& graph, const TaskTypeRegistry& types, const std::string& path);

// Time spent outside the tasks that belongs on a timeline (the exchanges between ranks after
// a graph), written as a row of thread -1.
struct TimelineInterval {
  std::string type, subtype, category;
  std::int64_t start_ns = 0, end_ns = 0;
};

// One row per task that ran: type, subtype, category, ci, cj, rank, thread, start and end
// (ns since the step began), then the extra intervals. Inactive tasks are left out.
void write_timeline_csv(const TaskGraph& graph, const TaskTypeRegistry& types,
                        const std::vector<TaskRecord>& records, int rank, long long step,
                        const std::string& path, const std::vector<TimelineInterval>& extra = {});

}  // namespace fountain::tasks
