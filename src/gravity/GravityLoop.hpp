// The gravity tasks: the tree over every particle, and the walks of a cell's active particles.
#pragma once
#include "engine/StepContext.hpp"

namespace fountain::gravity {

// Builds ctx.tree from every particle at its drifted position: gas (its gravitating mass,
// at the gas softening) and dark matter. Sources are numbered gas first, then dark matter.
void build_tree(StepContext& ctx);

// Accelerations and potentials of the active particles of leaf `c` from the tree (gather
// only: writes nothing but c's particles). A particle with no previous acceleration gets the
// Barnes-Hut criterion, the others the relative one.
void walk_cell(StepContext& ctx, int c);

}  // namespace fountain::gravity
