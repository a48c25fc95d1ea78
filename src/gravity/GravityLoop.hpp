// The gravity tasks: the tree over every particle, and the walks of a cell's active particles.
#pragma once
#include "step/StepContext.hpp"

namespace fountain::gravity {

class GravityTree;

// The tree's sources are every particle at its drifted position: gas (its gravitating mass,
// at the gas softening) and dark matter, numbered gas first, then dark matter.

// Builds ctx.tree anew from every particle (across ranks: ctx.tree_across, from this rank's).
void build_tree(StepContext& ctx);
// The tree the step's walks read: ctx.tree, or across ranks the one the tree task assembled.
const GravityTree& walk_tree(const StepContext& ctx);

// Chooses, before a graph run, what its tree tasks do (ctx.tree_update): nothing when the
// tree was built at this step's rebuild; a refit while the tree has the same sources in the
// same order (the engine drops it when the cells are recut, which reorders particles and adds
// or removes stars) and has not grown loose; otherwise a build.
void plan_tree_update(StepContext& ctx);
// The tree tasks: the refit of group g of the tree's subtrees (after every drift), then the
// finish (after every group: the nodes above them, or the whole build).
void refit_tree_group(StepContext& ctx, int g);
void finish_tree(StepContext& ctx);

// Periodic boxes: the long-range accelerations and potentials of every particle at its
// drifted position (ctx.long_range), into its a_mesh and potential_mesh, which the walks add
// to the tree's short range. With a mesh step (ctx.mesh_step), only at its start.
void compute_long_range(StepContext& ctx);

// Accelerations and potentials of the active particles of leaf `c` from the tree (gather
// only: writes nothing but c's particles). A particle with no previous acceleration gets the
// Barnes-Hut criterion, the others the relative one.
void walk_cell(StepContext& ctx, int c);

}  // namespace fountain::gravity
