// The one place where the engine's task types are registered.
#pragma once
#include "tasks/TaskGraph.hpp"

namespace fountain {

struct TaskTypes {
  int drift, density_self, density_pair, ghost, force_self, force_pair, gravity_tree, gravity, kick_close, timestep,
      cooling, kick_open, star_formation, star_formation_done, feedback_search, feedback_apply, send, recv;
  tasks::TaskTypeRegistry registry;

  TaskTypes() {
    drift = registry.add({"drift", "", "integration"});
    density_self = registry.add({"density", "self", "hydro"});
    density_pair = registry.add({"density", "pair", "hydro"});
    ghost = registry.add({"ghost", "", "hydro"});
    force_self = registry.add({"force", "self", "hydro"});
    force_pair = registry.add({"force", "pair", "hydro"});
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
