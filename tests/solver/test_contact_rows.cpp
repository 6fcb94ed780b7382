// SPDX-License-Identifier: Apache-2.0
// The normal row's bias: a gap the tool's own motion closed this step is made way for at the
// tool's speed; only penetration present at the step's start is recovered at max_recovery_speed.
#include "solver/contact_rows.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

constexpr double kH = 1e-3;           // s
constexpr double kMaxRecovery = 1.0;  // m/s

// A node contact with a tool whose point moves at `tool_speed` along -n (towards the node when > 0).
Contact tool_contact(double gap, double tool_speed) {
  const Vec3 n = Vec3(1, 2, -2).normalized();
  Contact c{1, node_point(0, 0), BodyPoint{}, n, Vec3::Zero(), gap, 0.0, Vec3::Zero()};
  c.tool = 0;
  c.other_velocity = tool_speed * n + Vec3(0.3, 0, 0.15).cross(n);  // plus some sliding, which must not matter
  return c;
}

}  // namespace

// The tool came 1 cm at 10 m/s into a node that touched it: the whole gap is its motion, and the
// node must get out of the way at 10 m/s (the old clamp asked 1 m/s and the tool went through).
static void test_tool_motion_is_not_clamped(void**) {
  const Contact c = tool_contact(-0.01, 10.0);
  assert_near(normal_bias(c, kH, kMaxRecovery), -10.0, 1e-9);
}

// A tool at rest with a node 1 cm inside: penetration, recovered at 1 m/s as before.
static void test_penetration_is_clamped(void**) {
  assert_near(normal_bias(tool_contact(-0.01, 0.0), kH, kMaxRecovery), -kMaxRecovery, 1e-12);
}

// Both: 5 mm inside at the step's start and the tool 1 cm further in: the tool's part is made
// way for in full, the old penetration at 1 m/s.
static void test_motion_plus_penetration(void**) {
  const Contact c = tool_contact(-0.015, 10.0);
  assert_near(normal_bias(c, kH, kMaxRecovery), -10.0 - kMaxRecovery, 1e-9);
  // ... and a shallow old penetration (0.5 um: 0.5 mm/s in this step) is recovered in full.
  assert_near(normal_bias(tool_contact(-0.0100005, 10.0), kH, kMaxRecovery), -10.0005, 1e-9);
}

// The clamp only relaxes a row, and only for an approaching tool: a gap stays a gap whichever way
// the tool moves (the node may not close more than the gap), and a receding tool explains none
// of a penetration: it is recovered at max_recovery_speed as without the tool's motion.
static void test_receding_tool_relaxes_nothing(void**) {
  assert_near(normal_bias(tool_contact(0.002, -10.0), kH, kMaxRecovery), 2.0, 1e-12);
  assert_near(normal_bias(tool_contact(0.002, 10.0), kH, kMaxRecovery), 2.0, 1e-12);
  assert_near(normal_bias(tool_contact(-0.002, -10.0), kH, kMaxRecovery), -kMaxRecovery, 1e-12);
  assert_near(normal_bias(tool_contact(-0.0005, -10.0), kH, kMaxRecovery), -0.5, 1e-12);
}

// Between bodies there is no tool: the penetration is clamped as it is.
static void test_body_contact_clamps_penetration(void**) {
  Contact c = tool_contact(-0.01, 10.0);
  c.tool = -1;
  c.b = node_point(1, 0);
  c.other_velocity = Vec3::Zero();
  assert_near(normal_bias(c, kH, kMaxRecovery), -kMaxRecovery, 1e-12);
}

// The rows carry it.
static void test_rows_use_it(void**) {
  const std::vector<Contact> contacts = {tool_contact(-0.01, 10.0), tool_contact(-0.01, 0.0)};
  ContactRows rows;
  rows.build(contacts, kH, kMaxRecovery);
  assert_int_equal(rows.size(), 2);
  assert_near(rows.bias[0], -10.0, 1e-9);
  assert_near(rows.bias[1], -kMaxRecovery, 1e-12);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_tool_motion_is_not_clamped),
      cmocka_unit_test(test_penetration_is_clamped),
      cmocka_unit_test(test_motion_plus_penetration),
      cmocka_unit_test(test_receding_tool_relaxes_nothing),
      cmocka_unit_test(test_body_contact_clamps_penetration),
      cmocka_unit_test(test_rows_use_it),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
