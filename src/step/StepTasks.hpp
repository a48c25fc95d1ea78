// What each module registers with the engine: its task types, where in the step they run, how they depend on others, and the function that runs them.
#pragma once
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "tasks/TaskGraph.hpp"

namespace fountain {

// The stages of a step, in order: the engine's one statement of what follows what. A leaf's
// tasks that write it are chained in stage order (then in the order they were registered),
// so a task that only needs its own leaf's earlier work needs no dependency of its own.
// The graph runs in three phases: the density passes run the stages up to Ghost, the first
// forces those up to Gravity, a full step all of them.
enum class Stage {
  Drift,          // particles to the current time
  Density,
  Ghost,          // h and density solved; force inputs prepared
  Exchange,       // across ranks: ghost results sent and received
  Force,
  Gravity,
  KickClose,      // the step's second half-kick
  Timestep,
  StarFormation,
  Feedback,
  Cooling,
  KickOpen,       // the next step's first half-kick
};

enum class Phase { Density, Hydro, Full };

inline bool runs_in(Stage s, Phase p) {
  if (p == Phase::Density) return s == Stage::Density || s == Stage::Ghost;
  if (p == Phase::Hydro) return s <= Stage::Gravity;
  return true;
}

// What a module registers for one task type.
struct TaskKind {
  using Run = std::function<void(const tasks::Task&)>;
  tasks::TaskTypeInfo type;
  Stage stage = Stage::Drift;
  // Per leaf (its own leaf's state, written in stage order), or a few tasks per step (`parts`
  // of them, Task::part telling them apart) that work on no one leaf.
  enum class Scope { Leaf, Step } scope = Scope::Leaf;
  int parts = 1;
  bool gas_leaves_only = false;   // made only for leaves that hold gas
  bool writes_leaf = true;        // joins its leaf's write chain
  // Which of a leaf's tasks a phase runs: those of the leaves active now on the rank that
  // owns them (the default); of every leaf the step reads (drifts); or as `active_if` says
  // (exchanges across ranks).
  enum class Activation { ActiveLeaf, DriftedLeaf, Custom } activation = Activation::ActiveLeaf;
  std::function<bool(int c)> active_if;
  // Its tasks read every particle (the gravity tree): a phase that runs them drifts every leaf.
  bool reads_every_leaf = false;
  Run run;
  // Before a phase that runs this kind's tasks (say, planning what a tree update does).
  std::function<void()> before_phase;

  static TaskKind leaf(tasks::TaskTypeInfo type, Stage stage, Run run) {
    TaskKind k;
    k.type = std::move(type);
    k.stage = stage;
    k.run = std::move(run);
    return k;
  }
  static TaskKind per_step(tasks::TaskTypeInfo type, Stage stage, Run run, int parts = 1) {
    TaskKind k = leaf(std::move(type), stage, std::move(run));
    k.scope = Scope::Step;
    k.parts = parts;
    k.writes_leaf = false;
    return k;
  }
};

class GraphBuilder;

// The registered kinds, in registration order; ids are the task types of the graph.
class StepTasks {
 public:
  int add(TaskKind kind) {
    kinds_.push_back(std::move(kind));
    return registry_.add(kinds_.back().type);
  }
  // Called once per graph, after every kind's tasks exist: adds the module's dependencies.
  void link(std::function<void(GraphBuilder&)> linker) { linkers_.push_back(std::move(linker)); }

  const TaskKind& operator[](int type) const { return kinds_[static_cast<std::size_t>(type)]; }
  TaskKind& operator[](int type) { return kinds_[static_cast<std::size_t>(type)]; }
  int size() const { return static_cast<int>(kinds_.size()); }
  const tasks::TaskTypeRegistry& registry() const { return registry_; }
  const std::vector<std::function<void(GraphBuilder&)>>& linkers() const { return linkers_; }

 private:
  std::vector<TaskKind> kinds_;
  tasks::TaskTypeRegistry registry_;
  std::vector<std::function<void(GraphBuilder&)>> linkers_;
};

// What a module's linker sees of the graph being built: the tasks by type and leaf, the
// leaves and their neighbour lists, and the means to add a dependency.
class GraphBuilder {
 public:
  virtual ~GraphBuilder() = default;
  virtual const std::vector<int>& leaves() const = 0;
  // The leaves whose particles leaf c's gather loops read (c among them).
  virtual const std::vector<int>& neighbours(int c) const = 0;
  // Leaf c's task of `type`, -1 if it has none.
  virtual int task(int type, int c) const = 0;
  // The tasks of a per-step type, in part order.
  virtual const std::vector<int>& step_tasks(int type) const = 0;
  // Leaf c's first task of a stage after `stage`, -1 if none.
  virtual int first_after(Stage stage, int c) const = 0;
  // `after` waits for `before`. Either being -1 (a leaf without that task: a leaf with no gas
  // has no gas-only task) adds nothing: there is nothing to wait for or to hold back.
  virtual void depends(int before, int after) = 0;
};

}  // namespace fountain
