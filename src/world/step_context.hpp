// SPDX-License-Identifier: Apache-2.0
// What one step works with, filled at its start (World::prepare_step) and handed to its stages:
// the step size, the one deadline of the step's time budget, the thread pool (null: serial), the
// plan, the dynamic bodies and the tools collision numbered. The solver sees the SolveContext part.
#pragma once
#include <vector>

#include "collision/contact.hpp"
#include "collision/tool.hpp"
#include "solver/velocity_solver.hpp"
#include "world/body.hpp"

namespace mica {

// Which stages the scene calls for (each body also checks its own need inside a stage).
struct Plan {
  bool loads = false, rotations = false, elements = false, damping = false;
  bool constraints = false, solve = false, integrate = false;
  bool collide = false, forces = false;
  bool newton = false;  // a body's step may be re-linearised (co-rotational, neo-Hookean): relinearise.cpp
};

struct StepContext : SolveContext {
  double h = 0;                  // s
  Clock::time_point start;       // when the step began (the budget counts from here)
  Plan plan;
  std::vector<Body*> dynamic;    // the bodies that move; Contact::a.body / b.body index this list
  std::vector<Tool*> tools;      // every tool, in collision's order; Contact::tool indexes it
  std::vector<SurfaceView> views;  // every body's surface as collision sees it
};

}  // namespace mica
