#include "TaskGraphDump.hpp"

#include <fmt/format.h>

#include <array>
#include <cstddef>
#include <fstream>
#include <iterator>
#include <map>
#include <stdexcept>
#include <utility>

#include "core/Error.hpp"

// The first line of the dependency CSV names the code version, as SWIFT's does (its
// plot_task_dependencies.py reads it back and puts it in the graph's title). The build may
// define FOUNTAIN_VERSION; without it the line reads "# Fountain dev".
#ifndef FOUNTAIN_VERSION
#define FOUNTAIN_VERSION "dev"
#endif

namespace fountain::tasks {

namespace {

// Writes `buf` to `path` in one go; throws InputError naming the path on any failure.
void write_file(const std::string& path, const fmt::memory_buffer& buf) {
  std::ofstream out(path, std::ios::out | std::ios::binary | std::ios::trunc);
  if (!out.is_open()) throw InputError(fmt::format("cannot open '{}' for writing", path));
  out.write(buf.data(), static_cast<std::streamsize>(buf.size()));
  out.close();
  if (!out) throw InputError(fmt::format("error while writing '{}'", path));
}

void check_type(const Task& t, int index, const TaskTypeRegistry& types) {
  if (t.type < 0 || t.type >= types.size())
    throw std::out_of_range(fmt::format("task {} has type {}, but only {} task types are registered",
                                        index, t.type, types.size()));
}

// A bare word for CSV fields that SWIFT's tool also uses as DOT identifiers: anything but
// letters, digits and '_' becomes '_'; an empty string becomes `empty`.
std::string token(const std::string& s, const char* empty) {
  if (s.empty()) return empty;
  std::string r = s;
  for (char& c : r) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) c = '_';
  }
  return r;
}

// A CSV field without separators, quotes or line breaks (they become '_').
std::string csv_field(const std::string& s) {
  std::string r = s;
  for (char& c : r)
    if (c == ',' || c == '"' || c == '\n' || c == '\r') c = '_';
  return r;
}

// A DOT double-quoted string body.
std::string dot_escape(const std::string& s) {
  std::string r;
  r.reserve(s.size());
  for (char c : s) {
    if (c == '"' || c == '\\') r.push_back('\\');
    if (c == '\n') {
      r += "\\n";
      continue;
    }
    r.push_back(c);
  }
  return r;
}

// Per task type: how many tasks; per (type before, type after): how many dependencies.
struct TypeGraph {
  std::vector<std::size_t> tasks_of_type;
  std::map<std::pair<int, int>, std::size_t> links;
};

TypeGraph type_graph(const TaskGraph& graph, const TaskTypeRegistry& types) {
  TypeGraph g;
  g.tasks_of_type.assign(static_cast<std::size_t>(types.size()), 0);
  for (int i = 0; i < graph.size(); ++i) {
    const Task& t = graph.task(i);
    check_type(t, i, types);
    ++g.tasks_of_type[static_cast<std::size_t>(t.type)];
  }
  for (int i = 0; i < graph.size(); ++i) {
    const Task& t = graph.task(i);
    for (int u : graph.unlocks(i)) {
      if (u < 0 || u >= graph.size())
        throw std::out_of_range(fmt::format("task {} unlocks task {}, which does not exist", i, u));
      ++g.links[{t.type, graph.task(u).type}];
    }
  }
  return g;
}

}  // namespace

void write_dependency_csv(const TaskGraph& graph, const TaskTypeRegistry& types, const std::string& path) {
  const TypeGraph g = type_graph(graph, types);

  // Columns as in SWIFT's scheduler_write_dependencies (src/scheduler.c). Ours has no
  // implicit or MPI tasks (0), one rank (number_rank 1), no cell levels (level flags 0),
  // and the category as SWIFT's cluster (group) name, "None" when it has none.
  fmt::memory_buffer buf;
  auto out = std::back_inserter(buf);
  fmt::format_to(out, "# Fountain {}\n", FOUNTAIN_VERSION);
  fmt::format_to(out,
                 "task_in,task_out,implicit_in,implicit_out,mpi_in,mpi_out,cluster_in,cluster_out,"
                 "number_link,number_rank,task_in_is_top,task_in_is_hydro_super,task_in_is_grav_super,"
                 "task_out_is_top,task_out_is_hydro_super,task_out_is_grav_super,cell_has_active_task\n");

  std::vector<bool> linked(static_cast<std::size_t>(types.size()), false);
  for (const auto& [key, count] : g.links) {
    const auto [a, b] = key;
    linked[static_cast<std::size_t>(a)] = true;
    linked[static_cast<std::size_t>(b)] = true;
    fmt::format_to(out, "{},{},0,0,0,0,{},{},{},1,0,0,0,0,0,0,1\n", token(types.full_name(a), "unnamed"),
                   token(types.full_name(b), "unnamed"), token(types[a].category, "None"),
                   token(types[b].category, "None"), count);
  }
  // Like SWIFT, a type whose tasks neither unlock nor wait for anything still gets a row,
  // pointing at the pseudo task "task_unlocks_nothing", so that it shows in the graph.
  for (int t = 0; t < types.size(); ++t) {
    if (g.tasks_of_type[static_cast<std::size_t>(t)] == 0 || linked[static_cast<std::size_t>(t)]) continue;
    fmt::format_to(out, "{},task_unlocks_nothing,0,0,0,0,{},None,0,1,0,0,0,-1,-1,-1,1\n",
                   token(types.full_name(t), "unnamed"), token(types[t].category, "None"));
  }
  write_file(path, buf);
}

void write_dot(const TaskGraph& graph, const TaskTypeRegistry& types, const std::string& path) {
  const TypeGraph g = type_graph(graph, types);

  // Colours: fixed ones for the usual categories, then a palette in order of appearance.
  static const std::map<std::string, std::string> known = {
      {"hydro", "lightskyblue"}, {"gravity", "salmon"},  {"integration", "palegreen"},
      {"io", "khaki"},           {"tree", "plum"},       {"feedback", "orange"},
  };
  static const std::array<const char*, 8> palette = {"thistle",    "aquamarine", "peachpuff", "lightpink",
                                                     "wheat",      "lightcyan",  "gold",      "lightgrey"};
  std::map<std::string, std::string> colour_of;
  std::vector<std::string> categories;  // in order of first appearance among used types
  std::size_t next_colour = 0;
  for (int t = 0; t < types.size(); ++t) {
    if (g.tasks_of_type[static_cast<std::size_t>(t)] == 0) continue;
    const std::string& c = types[t].category;
    if (colour_of.count(c)) continue;
    categories.push_back(c);
    const auto k = known.find(c);
    colour_of[c] = k != known.end() ? k->second : palette[next_colour++ % palette.size()];
  }

  fmt::memory_buffer buf;
  auto out = std::back_inserter(buf);
  fmt::format_to(out, "digraph fountain_tasks {{\n");
  fmt::format_to(out, "  label=\"Fountain task dependencies ({} tasks, {} dependencies)\";\n", graph.size(),
                 graph.num_dependencies());
  fmt::format_to(out, "  node [shape=box, style=\"rounded,filled\", fontname=\"Helvetica\"];\n");
  fmt::format_to(out, "  edge [fontname=\"Helvetica\", fontsize=10];\n");
  for (std::size_t ci = 0; ci < categories.size(); ++ci) {
    const std::string& c = categories[ci];
    fmt::format_to(out, "  subgraph \"cluster_{}\" {{\n", dot_escape(c.empty() ? std::string("none") : c));
    fmt::format_to(out, "    label=\"{}\"; style=dashed; color=grey60;\n", dot_escape(c));
    for (int t = 0; t < types.size(); ++t) {
      const std::size_t n = g.tasks_of_type[static_cast<std::size_t>(t)];
      if (n == 0 || types[t].category != c) continue;
      const std::string name = dot_escape(types.full_name(t));
      fmt::format_to(out, "    \"{}\" [label=\"{}\\n{} tasks\", fillcolor=\"{}\"];\n", name, name, n,
                     colour_of[c]);
    }
    fmt::format_to(out, "  }}\n");
  }
  for (const auto& [key, count] : g.links)
    fmt::format_to(out, "  \"{}\" -> \"{}\" [label=\"{}\"];\n", dot_escape(types.full_name(key.first)),
                   dot_escape(types.full_name(key.second)), count);
  fmt::format_to(out, "}}\n");
  write_file(path, buf);
}

void write_timeline_csv(const TaskGraph& graph, const TaskTypeRegistry& types,
                        const std::vector<TaskRecord>& records, int rank, long long step,
                        const std::string& path, const std::vector<TimelineInterval>& extra) {
  if (records.size() != static_cast<std::size_t>(graph.size()))
    throw std::invalid_argument(fmt::format("write_timeline_csv: {} records for a graph of {} tasks",
                                            records.size(), graph.size()));
  fmt::memory_buffer buf;
  auto out = std::back_inserter(buf);
  fmt::format_to(out, "# fountain task timeline: step={} rank={}\n", step, rank);
  fmt::format_to(out, "type,subtype,category,ci,cj,rank,thread,start_ns,end_ns\n");
  for (int i = 0; i < graph.size(); ++i) {
    const TaskRecord& r = records[static_cast<std::size_t>(i)];
    if (r.thread < 0) continue;  // inactive: never ran
    const Task& t = graph.task(i);
    check_type(t, i, types);
    const TaskTypeInfo& info = types[t.type];
    fmt::format_to(out, "{},{},{},{},{},{},{},{},{}\n", csv_field(info.name), csv_field(info.subtype),
                   csv_field(info.category), t.ci, t.cj, rank, r.thread, r.start_ns, r.end_ns);
  }
  for (const TimelineInterval& x : extra)
    fmt::format_to(out, "{},{},{},-1,-1,{},-1,{},{}\n", csv_field(x.type), csv_field(x.subtype), csv_field(x.category),
                   rank, x.start_ns, x.end_ns);
  write_file(path, buf);
}

}  // namespace fountain::tasks
