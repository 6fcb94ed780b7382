// SPDX-License-Identifier: Apache-2.0
// The one list of a world's dynamic state: every value a later step depends on beyond what the
// host built. save_state writes the list, restore_state reads it back (first checking all of it,
// then moving it in), and the replay's fingerprint hashes the fields marked kFingerprint (the
// step's results a recording compares). A value a step carries to the next and this list leaves
// out is neither saved nor restored, and tests/capi/test_state.c (a state restored into a fresh
// world steps as the original, every readout compared bit for bit) fails.
//
// A visitor is called as v(what, field, flags): `what` names the field in messages, `flags` says
// how a restore checks it (its length, finite values) and whether the fingerprint hashes it.
#pragma once
#include "world/world.hpp"

namespace mica {

enum StateFlags : uint32_t {
  kPlain = 0,
  kFingerprint = 1,    // the replay compares it after each step
  kPerNode = 2,        // one value per node of the body
  kPerNodeOrNone = 4,  // one per node, or empty
  kPerElement = 8,     // one per tet of the body
  kFinite = 16,        // no NaN or infinity
};

// What the last step left: the contacts readout, the statistics, the energy debt.
template <class V>
void visit_state(V& v, StepResults& r) {
  v("the statistics", r.stats, kPlain);
  v("the energy debt", r.debt, kPlain);
  v("the contacts", r.contacts, kPlain);
  v("the contact rows", r.rows.start, kPlain);
  v("the contact rows", r.rows.terms, kPlain);
  v("the contact rows", r.rows.direction, kPlain);
  v("the contact rows", r.rows.bias, kPlain);
  v("the contact rows", r.rows.normal_of, kPlain);
  v("the contact rows", r.rows.mu, kPlain);
  v("the contact rows", r.rows.contact, kPlain);
  v("the contact rows", r.rows.key, kPlain);
  v("the contact impulses", r.lambda, kPlain);
  v("the contact impulses", r.curvature_impulse, kPlain);
  v("the step's bodies", r.bodies, kPlain);
  v("the step's tools", r.tools, kPlain);
}

template <class V>
void visit_state(V& v, BodyState& s) {
  v("a body's positions", s.x, kPerNode | kFinite | kFingerprint);
  v("a body's velocities", s.v, kPerNode | kFinite | kFingerprint);
  v("a body's last velocities", s.v_previous, kPerNode | kFinite);
  v("a body's node forces", s.node_forces, kPerNode | kFinite);
  v("a body's node forces", s.has_node_forces, kPlain);
  v("a body's end positions", s.end.x, kPerNodeOrNone);
  v("a body's end rotations", s.end.R, kPerElement);
  v("a body's end energy", s.end.u, kPlain);
}

template <class V>
void visit_state(V& v, ToolState& t) {
  v("a tool's pose", t.position, kPlain);
  v("a tool's pose", t.orientation, kPlain);
  v("a tool's last pose", t.previous_position, kPlain);
  v("a tool's last pose", t.previous_orientation, kPlain);
  v("a tool's force", t.force, kFingerprint);
  v("a tool's torque", t.torque, kFingerprint);
  v("a tool's contacts", t.contact_count, kPlain);
  v("a tool's stiffness", t.stiffness, kPlain);
}

// A constraint's state; its handle (targets or grab offsets, pose, tool) is one field.
template <class V>
void visit_state(V& v, Lpc& c) {
  v("a constraint's velocity", c.velocity, kPlain);
  v("a constraint's reaction", c.reaction, kFingerprint);
  v("a constraint's handle", c.handle, kPlain);
}

template <class V>
void visit_state(V& v, DeviceLink::FilterState& f) {
  v("a device's filter", f.average.samples, kPlain);
  v("a device's filter", f.average.next, kPlain);
  v("a device's filter", f.average.count, kPlain);
  v("a device's filter", f.average.since_resum, kPlain);
  v("a device's filter", f.average.sum, kPlain);
  v("a device's filter", f.average.in_contact, kPlain);
  v("a device's filter", f.previous_force, kPlain);
}

}  // namespace mica
