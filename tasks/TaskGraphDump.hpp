// Writes task graphs (DOT, SWIFT-style dependency CSV) and per-task timelines (CSV).
#pragma once
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

// One row per task that ran: type, subtype, category, ci, cj, rank, thread, start and end
// (ns since the step began). Inactive tasks are left out.
void write_timeline_csv(const TaskGraph& graph, const TaskTypeRegistry& types,
                        const std::vector<TaskRecord>& records, int rank, long long step,
                        const std::string& path);

}  // namespace fountain::tasks
