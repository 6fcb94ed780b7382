// SPDX-License-Identifier: Apache-2.0
// Undoing a failed step: World::step saves what the step writes before it can fail and puts it
// back when it fails (issue 16: a device-driven tool stayed at the device's new pose and the
// factored sweep's refresh schedule shifted, so a failed step left traces in later ones).
#include "world/world.hpp"

namespace mica {

void World::save_undo() {
  saved_stats_ = stats_;
  saved_debt_ = debt_;
  saved_tools_.clear();  // keeps its capacity: no allocation once the tool count is reached
  tools_.for_each([&](Id, Tool& t) {
    saved_tools_.push_back({&t, t.state(), t.scratch()});
  });
  saved_reactions_.clear();
  lpcs_.for_each([&](Id, Lpc& c) { saved_reactions_.push_back(c.reaction); });
  solver_->begin_step();
}

void World::undo() {
  stats_ = saved_stats_;
  debt_ = saved_debt_;
  for (const SavedTool& s : saved_tools_) {
    static_cast<ToolState&>(*s.tool) = s.state;  // the pose (follow_devices moved it) and the results
    static_cast<ToolScratch&>(*s.tool) = s.scratch;
  }
  size_t k = 0;
  lpcs_.for_each([&](Id, Lpc& c) { c.reaction = saved_reactions_[k++]; });
  solver_->rollback_step();
}

}  // namespace mica
