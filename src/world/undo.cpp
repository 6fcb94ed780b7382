// SPDX-License-Identifier: Apache-2.0
// A failed step: the stages write only into the step's own buffers (StepResults, the bodies' and
// tools' scratch) until World::commit, so what a failed step must put back is what it took from
// outside: the poses the devices gave their tools and grasp handles (follow_devices), and the
// solver's refresh schedules (VelocitySolver::begin_step, rollback_step).
#include "world/world.hpp"

namespace mica {

void World::save_undo() {
  saved_poses_.clear();  // keeps its capacity: no allocation once the device count is reached
  devices_.for_each([&](Id, const DeviceLink& link) {
    const Id target = link.settings().tool ? link.settings().tool : link.settings().lpc;
    if (const Tool* t = id_kind(target) == IdKind::Tool ? tools_.find(target) : nullptr)
      saved_poses_.push_back({target, t->position, t->orientation});
    else if (const Lpc* c = id_kind(target) == IdKind::Lpc ? lpcs_.find(target) : nullptr; c && c->handle)
      saved_poses_.push_back({target, c->handle->position, c->handle->orientation});
  });
  solver_->begin_step();
}

void World::undo() {
  for (const SavedPose& p : saved_poses_) {
    if (id_kind(p.target) == IdKind::Tool) {
      Tool& t = tool(p.target);
      t.position = p.position;
      t.orientation = p.orientation;
    } else {
      Handle& h = *lpcs_.get(p.target, "constraint").handle;
      h.position = p.position;
      h.orientation = p.orientation;
    }
  }
  solver_->rollback_step();
}

}  // namespace mica
