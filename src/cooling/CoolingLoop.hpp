// The cooling task: each active gas particle's energy change over its new step, solved implicitly.
#pragma once
#include "step/StepContext.hpp"

namespace fountain::cooling {

// For the active particles of leaf `c`, whose steps were just set: replaces du/dt by the
// rate that takes u from the step's start to the implicit solution of
// u_new = u_old + dt (du/dt_hydro + du/dt_cool(u_new)), so both half-kicks and every drift
// in between follow it, and the step ends exactly at u_new (docs/physics.md section 4).
void cool_cell(StepContext& ctx, int c);

}  // namespace fountain::cooling
