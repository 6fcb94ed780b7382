// SPDX-License-Identifier: Apache-2.0
// What a step leaves for the host to read and the next step to start from, beyond the bodies'
// positions and velocities: the contacts readout, the statistics, the energy debt. The world keeps
// two sets: the published one (the last good step's) and the one the running step writes into;
// World::commit swaps them, so a step that fails leaves the published set as it was, and both sets
// keep their capacity (a step allocates nothing for them once the contact count is reached).
#pragma once
#include <vector>

#include "collision/contact.hpp"
#include "solver/contact_rows.hpp"
#include "world/stats.hpp"

namespace mica {

struct StepResults {
  std::vector<Contact> contacts;
  ContactRows rows;                  // the rows of G
  std::vector<double> lambda;        // impulse per row, N s
  Vec3List curvature_impulse;        // per contact: its curvature term's impulse, N s
  std::vector<Id> bodies, tools;     // the step's dynamic bodies and tools: what Contact indices name
  WorldStats stats;
  double debt = 0;                   // J, world/relinearise.cpp: the energy the steps since it last went down added
};

}  // namespace mica
