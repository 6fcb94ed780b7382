// SPDX-License-Identifier: Apache-2.0
// The last stage before the device: non-finite forces become zero, the magnitude is clamped
// along the same direction, growth is rate-limited while drops pass at once, a stalled
// simulation fades the force linearly to exactly zero, and apply() allocates nothing.
#include "haptics/force_safety.hpp"
#include "alloc_counter.hpp"
#include "test_util.hpp"

#include <limits>

using namespace mica;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

SafetySettings settings(double max_force, double max_rate, double timeout = 0.1, double ramp = 0.05) {
  SafetySettings s;
  s.max_force = max_force;
  s.max_rate = max_rate;
  s.stall_timeout = timeout;
  s.stall_ramp = ramp;
  return s;
}

}  // namespace

static void test_non_finite_gives_zero(void**) {
  ForceSafety safety(settings(3, kInf));
  SafetyFlags flags;
  const Vec3 good(1, 0, 0);
  for (const Vec3& bad : {Vec3(kNaN, 0, 0), Vec3(0, kInf, 0), Vec3(0, 0, -kInf), Vec3(kNaN, kNaN, kNaN)}) {
    assert_true(safety.apply(good, 0, 0, 1e-3, flags) == good);
    assert_false(flags.non_finite);
    assert_true(safety.apply(bad, 0, 0, 1e-3, flags) == Vec3::Zero());  // at once, not ramped
    assert_true(flags.non_finite);
  }
}

static void test_clamp_keeps_direction(void**) {
  ForceSafety safety(settings(3, kInf));
  SafetyFlags flags;
  const Vec3 f(30, 40, 120);  // |f| = 130
  const Vec3 out = safety.apply(f, 0, 0, 1e-3, flags);
  assert_true(flags.clamped);
  assert_false(flags.rate_limited);
  assert_near(out.norm(), 3, 1e-15);
  assert_near(out.normalized().dot(f.normalized()), 1, 1e-15);
  assert_near(out.cross(f).norm() / f.norm(), 0, 1e-15);

  // Components so large the plain norm overflows: the direction must survive.
  const Vec3 huge(1e300, -2e300, 2e300);
  const Vec3 out2 = safety.apply(huge, 0, 0, 1e-3, flags);
  assert_true(flags.clamped);
  assert_near(out2.x(), 1, 1e-15);
  assert_near(out2.y(), -2, 1e-15);
  assert_near(out2.z(), 2, 1e-15);

  // Under the limit: untouched.
  assert_true(safety.apply(Vec3(1, 2, 2), 0, 0, 1e-3, flags) == Vec3(1, 2, 2));
  assert_false(flags.clamped);
}

static void test_rate_limits_growth_not_drops(void**) {
  const double rate = 100, dt = 1e-3, step = rate * dt;  // 0.1 N per tick
  ForceSafety safety(settings(3, rate));
  SafetyFlags flags;
  const Vec3 dir = Vec3(1, -2, 2).normalized();
  const Vec3 target = 2.0 * dir;

  // Rising from zero: exactly `step` per tick along the target's direction, until it is reached.
  Vec3 previous = Vec3::Zero();
  int ticks = 0;
  for (; ticks < 100 && previous != target; ++ticks) {
    const Vec3 out = safety.apply(target, 0, 0, dt, flags);
    assert_le((out - previous).norm(), step * (1 + 1e-12));
    assert_near(out.normalized().dot(dir), 1, 1e-12);
    if (out != target) {
      assert_true(flags.rate_limited);
      assert_near((out - previous).norm(), step, 1e-12);
    }
    previous = out;
  }
  assert_true(previous == target);
  assert_in_range(ticks, 20, 21);

  // A partial drop along the same direction passes at once.
  assert_true(safety.apply(0.25 * target, 0, 0, dt, flags) == 0.25 * target);
  assert_false(flags.rate_limited);
  // Back up: limited again.
  assert_near(safety.apply(target, 0, 0, dt, flags).norm(), 0.5 + step, 1e-12);
  assert_true(flags.rate_limited);
  // Release: zero at once.
  assert_true(safety.apply(Vec3::Zero(), 0, 0, dt, flags) == Vec3::Zero());
  assert_false(flags.rate_limited);

  // A reversal drops at once and grows again in the new direction at the rate limit.
  for (int i = 0; i < 40; ++i) safety.apply(target, 0, 0, dt, flags);
  assert_true(safety.previous() == target);
  const Vec3 reversed = safety.apply(-target, 0, 0, dt, flags);
  assert_true(flags.rate_limited);
  assert_near(reversed.norm(), step, 1e-12);
  assert_near(reversed.normalized().dot(-dir), 1, 1e-12);

  // No time, no growth (and no NaN from inf * 0).
  ForceSafety unlimited(settings(3, kInf));
  assert_true(unlimited.apply(target, 0, 0, 0.0, flags) == Vec3::Zero());
  assert_true(unlimited.apply(target, 0, 0, kNaN, flags) == Vec3::Zero());
  assert_true(unlimited.apply(target, 0, 0, dt, flags) == target);
}

static void test_random_forces_stay_in_bounds(void**) {
  // Whatever comes in: the output is finite, at most max_force, grows by at most max_rate dt, and
  // lies within max_rate dt of the segment from zero to the previous output.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-5, 5);
  std::uniform_int_distribution<int> pick(0, 9);
  const double max_force = 3, rate = 50, dt = 1e-3, step = rate * dt;
  ForceSafety safety(settings(max_force, rate));
  SafetyFlags flags;
  Vec3 p = Vec3::Zero();
  for (int k = 0; k < 100000; ++k) {
    Vec3 f(u(rng), u(rng), u(rng));
    if (pick(rng) == 0) f = p + Vec3(u(rng), u(rng), u(rng)) * 1e-3;  // small moves too
    if (pick(rng) == 1) f[k % 3] = k % 2 ? kNaN : -kInf;
    const double now = pick(rng) == 2 ? kNaN : 0.0;
    const Vec3 out = safety.apply(f, now, 0, dt, flags);
    assert_true(out.allFinite());
    assert_le(out.norm(), max_force * (1 + 1e-15));
    assert_le(out.norm(), p.norm() + step * (1 + 1e-12));
    const double s = p.squaredNorm() > 0 ? std::clamp(out.dot(p) / p.squaredNorm(), 0.0, 1.0) : 0.0;
    assert_le((out - s * p).norm(), step * (1 + 1e-12));
    p = out;
  }
}

static void test_stall_ramps_to_zero_and_recovers(void**) {
  const double timeout = 0.1, ramp = 0.05, dt = 1e-3, rate = 100;
  ForceSafety safety(settings(3, rate, timeout, ramp));
  SafetyFlags flags;
  const Vec3 f(0, 0, 1);
  // Build up to f with fresh publishes.
  for (int i = 0; i < 20; ++i) safety.apply(f, i * dt, i * dt, dt, flags);
  assert_true(safety.previous() == f);

  // The simulation stops publishing at t = 0.02; the servo keeps running.
  const double last_publish = 0.02;
  double now = last_publish;
  for (int i = 0; i <= 200; ++i, now = last_publish + i * dt) {
    const Vec3 out = safety.apply(f, now, last_publish, dt, flags);
    const double late = (now - last_publish) - timeout;
    if (late <= 0) {
      assert_false(flags.stalled);
      assert_true(out == f);
    } else if (late < ramp) {
      assert_true(flags.stalled);
      assert_near(out.z(), 1 - late / ramp, 1e-12);  // linear fade
    } else {
      assert_true(flags.stalled);
      assert_true(out == Vec3::Zero());  // exactly zero, not merely small
    }
  }
  // Publishing resumes: the force comes back, growing at the rate limit.
  for (int i = 1; i <= 10; ++i) {
    now += dt;
    const Vec3 out = safety.apply(f, now, now, dt, flags);
    assert_false(flags.stalled);
    assert_near(out.z(), i * rate * dt, 1e-12);
  }
  // A NaN clock counts as stalled: zero.
  assert_true(safety.apply(f, kNaN, now, dt, flags) == Vec3::Zero());
  assert_true(flags.stalled);

  // A zero-length ramp cuts at once after the timeout.
  ForceSafety cut(settings(3, kInf, timeout, 0));
  assert_true(cut.apply(f, timeout, 0, dt, flags) == f);
  assert_true(cut.apply(f, timeout + 1e-9, 0, dt, flags) == Vec3::Zero());
}

static void test_bad_settings_throw(void**) {
  const SafetySettings bad[] = {settings(0, 1), settings(-1, 1), settings(kInf, 1), settings(kNaN, 1),
                                settings(1, 0), settings(1, kNaN), settings(1, 1, -1), settings(1, 1, kNaN),
                                settings(1, 1, 0.1, -1), settings(1, 1, 0.1, kInf)};
  for (const SafetySettings& s : bad) {
    bool thrown = false;
    try {
      ForceSafety safety(s);
    } catch (const Error& e) {
      thrown = e.code() == Errc::InvalidArgument;
    }
    assert_true(thrown);
  }
  ForceSafety ok(settings(1, kInf, 0, 0));  // an unlimited rate and an immediate cut are allowed
  assert_near(ok.settings().max_force, 1, 0);
}

static void test_apply_does_not_allocate(void**) {
  ForceSafety safety(settings(3, 100));
  SafetyFlags flags;
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-5, 5);
  std::vector<Vec3> forces(5000);
  for (Vec3& f : forces) f = Vec3(u(rng), u(rng), u(rng));
  forces[10].x() = kNaN;
  Vec3 sink = Vec3::Zero();
  mica_test::start_counting_allocations();
  for (size_t k = 0; k < forces.size(); ++k) sink += safety.apply(forces[k], 1e-3 * double(k), 0, 1e-3, flags);
  safety.reset();
  const int64_t counted = mica_test::stop_counting_allocations();
  assert_int_equal(counted, 0);
  assert_true(sink.allFinite());
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_non_finite_gives_zero),
      cmocka_unit_test(test_clamp_keeps_direction),
      cmocka_unit_test(test_rate_limits_growth_not_drops),
      cmocka_unit_test(test_random_forces_stay_in_bounds),
      cmocka_unit_test(test_stall_ramps_to_zero_and_recovers),
      cmocka_unit_test(test_bad_settings_throw),
      cmocka_unit_test(test_apply_does_not_allocate),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
