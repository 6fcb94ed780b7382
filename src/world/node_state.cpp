// SPDX-License-Identifier: Apache-2.0
// The host sets a body's node positions or velocities (checking a simulation, starting from a
// computed state). What the world derived from the old positions goes with them:
//  - the end-of-step rotations kept for the next step (end: recomputed from x);
//  - the surface tree (refitted here: a static body's is not refitted by the step);
//  - the warm-start impulses of the body's contacts (their features may no longer touch, and a
//    remembered force would stiffen the next step's contact rows, add_contact_stiffness);
//  - the re-linearisation's energy debt (the host's change is no work of the step).
// The solvers' factors are not dropped: a co-rotational body's lagged factor is warped by the
// rotations of the new positions (lagged_factor.hpp), and the system matrices are rebuilt from
// x by every step (a linear body's does not depend on x).
#include <cmath>

#include "world/recording.hpp"
#include "world/world.hpp"

namespace mica {

namespace {

void check_values(const Body& b, const Vec3List& values, const char* what) {
  if (values.size() != size_t(b.fem.node_count()))
    fail(Errc::InvalidArgument, b.name + " has " + std::to_string(b.fem.node_count()) + " nodes, got " +
                                    std::to_string(values.size()) + " " + what);
  for (size_t i = 0; i < values.size(); ++i)
    if (!values[i].allFinite())
      fail(Errc::InvalidArgument, std::string(what) + " of node " + std::to_string(i) + " is not finite");
}

}  // namespace

std::vector<uint64_t> World::contact_row_keys(Id id) const {
  std::vector<uint64_t> keys;
  int32_t index = -1;  // the body's index in the last step
  for (size_t k = 0; k < last_.bodies.size(); ++k)
    if (last_.bodies[k] == id) index = int32_t(k);
  for (size_t r = 0; r < last_.rows.size(); ++r) {
    const Contact& c = last_.contacts[size_t(last_.rows.contact[r])];
    const bool ours = (index >= 0 && (c.a.body == index || (c.b.count > 0 && c.b.body == index))) || c.other == id;
    if (ours) keys.push_back(last_.rows.key[r]);
  }
  return keys;
}

void World::set_positions(Id id, const Vec3List& x) {
  Body& b = body(id);
  check_values(b, x, "positions");
  const std::vector<uint64_t> stale = contact_row_keys(id);
  b.x = x;  // the same size: no allocation, nothing thrown from here on
  b.end.x.clear();
  b.bvh.refit(b.x);
  for (uint64_t key : stale) warm_start_.erase(key);
  last_.debt = 0;
  if (recorder_) recorder_->write(RecordKind::SetPositions, id, x);
}

void World::set_velocities(Id id, const Vec3List& v) {
  Body& b = body(id);
  if (!b.is_dynamic()) fail(Errc::WrongState, b.name + " is static: it has no velocities to set");
  check_values(b, v, "velocities");
  b.v = v;
  b.v_previous = v;  // no trend to extrapolate from velocities the host set
  if (recorder_) recorder_->write(RecordKind::SetVelocities, id, v);
}

}  // namespace mica
