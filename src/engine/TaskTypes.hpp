// The one place where the engine's task types are registered.
#pragma once
#include "tasks/TaskGraph.hpp"

namespace fountain {

struct TaskTypes {
  int drift, density, ghost, force, gravity_refit, gravity_tree, gravity, kick_close, timestep,
      cooling, kick_open, star_formation, star_formation_done, feedback_search, feedback_apply, send, recv;
  tasks::TaskTypeRegistry registry;

  TaskTypes() {
    drift = registry.add({"drift", "", "integration"});
    // A cell's density and force tasks gather over the cell and all its neighbour cells.
    density = registry.add({"density", "", "hydro"});
    ghost = registry.add({"ghost", "", "hydro"});
    force = registry.add({"force", "", "hydro"});
    // The tree is refitted in parts (Task::part: a group of its subtrees), then finished
    // above them (or built, when a refit will not do).
    gravity_refit = registry.add({"gravity", "refit", "gravity"});
    gravity_tree = registry.add({"gravity", "tree", "gravity"});
    gravity = registry.add({"gravity", "walk", "gravity"});
    kick_close = registry.add({"kick", "close", "integration"});
    timestep = registry.add({"timestep", "", "integration"});
    cooling = registry.add({"cooling", "", "cooling"});
    kick_open = registry.add({"kick", "open", "integration"});
    star_formation = registry.add({"star_formation", "", "star_formation"});
    star_formation_done = registry.add({"star_formation", "done", "star_formation"});
    feedback_search = registry.add({"feedback", "search", "feedback"});
    feedback_apply = registry.add({"feedback", "apply", "feedback"});
    // Across MPI ranks: a cell's ghost results go to the ranks whose force loops read them.
    send = registry.add({"send", "ghost", "mpi"});
    recv = registry.add({"recv", "ghost", "mpi"});
  }
};

}  // namespace fountain
