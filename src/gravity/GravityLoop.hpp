// The gravity tasks: the tree over every particle, and the walks of a cell's active particles.
#pragma once
#include "engine/StepContext.hpp"

namespace fountain::gravity {

// Brings ctx.tree to every particle's drifted position: gas (its gravitating mass, at the gas
// softening) and dark matter, numbered gas first, then dark matter. The tree is refitted
// while it has the same sources in the same order (the engine drops it when the cells are
// recut, which reorders particles and adds or removes stars) and has not grown loose;
// otherwise it is built anew.
void update_tree(StepContext& ctx);

// Accelerations and potentials of the active particles of leaf `c` from the tree (gather
// only: writes nothing but c's particles). A particle with no previous acceleration gets the
// Barnes-Hut criterion, the others the relative one.
void walk_cell(StepContext& ctx, int c);

}  // namespace fountain::gravity
