// SPDX-License-Identifier: Apache-2.0
// The servo path's force between simulation steps: the local model is exactly linear in the
// tool position, hold ignores it, the coupling pulls the device toward the tool and damps
// their relative motion, and the passivity bound is K T / 2.
#include "haptics/force_model.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

Vec3 random_vec(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  return Vec3(u(rng), u(rng), u(rng));
}

ForceModel random_model(std::mt19937& rng) {
  ForceModel m;
  m.f0 = random_vec(rng);
  const Mat3 a = Mat3::NullaryExpr([&](Eigen::Index, Eigen::Index) { return random_vec(rng).x(); });
  m.H = -400 * (a * a.transpose());  // a contact stiffness: symmetric, negative semidefinite, N/m
  m.x0 = 0.05 * random_vec(rng);
  m.in_contact = true;
  m.step = 3;
  return m;
}

}  // namespace

static void test_default_model_is_zero(void**) {
  const ForceModel m;
  assert_int_equal(m.step, -1);
  assert_false(m.in_contact);
  assert_true(m.evaluate(Vec3(0.1, 0.2, 0.3), ForceMode::LocalModel) == Vec3::Zero());
  assert_true(m.evaluate(Vec3(0.1, 0.2, 0.3), ForceMode::Hold) == Vec3::Zero());
}

static void test_local_model_is_linear(void**) {
  std::mt19937 rng(9);
  for (int trial = 0; trial < 100; ++trial) {
    // The linear regime: |f0| > |H d| for the displacements below, so the contact stays closed.
    ForceModel m = random_model(rng);
    m.f0 = m.f0.normalized() * (1 + m.H.norm());
    // At x0 it is f0 exactly.
    assert_true(m.evaluate(m.x0, ForceMode::LocalModel) == m.f0);
    // Anywhere: f0 + H (x - x0), computed component by component.
    const Vec3 x = m.x0 + 0.01 * random_vec(rng);
    const Vec3 got = m.evaluate(x, ForceMode::LocalModel);
    for (int i = 0; i < 3; ++i) {
      double expected = m.f0[i];
      for (int j = 0; j < 3; ++j) expected += m.H(i, j) * (x[j] - m.x0[j]);
      assert_near(got[i], expected, 1e-12);
    }
    // Superposition of displacements: F(x0 + a d1 + b d2) - f0 = a (F(x0 + d1) - f0) + b (F(x0 + d2) - f0).
    const Vec3 d1 = 0.01 * random_vec(rng), d2 = 0.01 * random_vec(rng);
    const double a = 1.7, b = -0.6;
    const Vec3 lhs = m.evaluate(m.x0 + a * d1 + b * d2, ForceMode::LocalModel) - m.f0;
    const Vec3 rhs = a * (m.evaluate(m.x0 + d1, ForceMode::LocalModel) - m.f0) +
                     b * (m.evaluate(m.x0 + d2, ForceMode::LocalModel) - m.f0);
    assert_near((lhs - rhs).norm(), 0, 1e-12);
    // Pushing further in (along a direction H resists) adds force against the push: d^T H d <= 0.
    const Vec3 push = 0.001 * random_vec(rng);
    assert_le((m.evaluate(m.x0 + push, ForceMode::LocalModel) - m.f0).dot(push), 1e-15);
  }
}

static void test_hold_ignores_the_position(void**) {
  std::mt19937 rng(4);
  const ForceModel m = random_model(rng);
  for (int i = 0; i < 10; ++i) assert_true(m.evaluate(random_vec(rng), ForceMode::Hold) == m.f0);
  // Coupling is not a function of the position: evaluate() holds f0 for it.
  assert_true(m.evaluate(random_vec(rng), ForceMode::Coupling) == m.f0);
}

static void test_coupling_force_signs(void**) {
  const double k = 300, b = 2;
  const Vec3 zero = Vec3::Zero();
  // Device above the tool: pulled down, by k times the offset.
  const Vec3 spring = coupling_force(Vec3(0, 0, 0.01), zero, zero, zero, k, b);
  assert_near(spring.z(), -3, 1e-12);
  assert_near(spring.head<2>().norm(), 0, 0);
  // Device moving away from a resting tool along +x: damped along -x.
  const Vec3 damper = coupling_force(zero, Vec3(0.5, 0, 0), zero, zero, k, b);
  assert_near(damper.x(), -1, 1e-12);
  // Only relative motion counts: moving together, no damping.
  const Vec3 together = coupling_force(Vec3(1, 2, 3), Vec3(0.3, -0.2, 0.1), Vec3(1, 2, 3), Vec3(0.3, -0.2, 0.1), k, b);
  assert_true(together == Vec3::Zero());
  // The tool trailing the device: the force on the device points back at the tool.
  const Vec3 x_device(0.02, -0.01, 0.005), x_tool(0.015, -0.012, 0.001);
  const Vec3 pull = coupling_force(x_device, zero, x_tool, zero, k, b);
  assert_near(pull.normalized().dot((x_tool - x_device).normalized()), 1, 1e-12);
}

static void test_passivity_bound(void**) {
  assert_near(passive_coupling_damping(300, 1e-3), 0.15, 1e-15);
  assert_near(passive_coupling_damping(400, 1e-3), 0.2, 1e-15);
  assert_near(passive_coupling_damping(300, 1e-2), 1.5, 1e-15);  // a slower loop needs more damping
  assert_near(passive_coupling_damping(0, 1e-3), 0, 0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::pair<double, double> bad[] = {{-1, 1e-3}, {nan, 1e-3}, {300, 0}, {300, -1e-3}, {300, nan}};
  for (const auto& [k, period] : bad) {
    bool thrown = false;
    try {
      passive_coupling_damping(k, period);
    } catch (const Error& e) {
      thrown = e.code() == Errc::InvalidArgument;
    }
    assert_true(thrown);
  }
}

// Pulling the tool out past the model's reach opens the contact: zero, never a pull.
static void test_local_model_never_pulls(void**) {
  ForceModel m;
  m.f0 = Vec3(0, 1, 0);
  m.H = -100 * Mat3::Identity();
  m.x0 = Vec3::Zero();
  assert_near(m.evaluate(Vec3(0, 0.005, 0), ForceMode::LocalModel).y(), 0.5, 1e-12);
  assert_true(m.evaluate(Vec3(0, 0.02, 0), ForceMode::LocalModel).isZero(0));  // would be -1 N
  ForceModel none;  // no contact: nothing to extrapolate
  assert_true(none.evaluate(Vec3(1, 2, 3), ForceMode::LocalModel).isZero(0));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_local_model_never_pulls),
      cmocka_unit_test(test_default_model_is_zero),
      cmocka_unit_test(test_local_model_is_linear),
      cmocka_unit_test(test_hold_ignores_the_position),
      cmocka_unit_test(test_coupling_force_signs),
      cmocka_unit_test(test_passivity_bound),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
