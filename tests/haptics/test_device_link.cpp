// SPDX-License-Identifier: Apache-2.0
// The whole servo cycle (read, map, evaluate, filter, limit, write) allocates nothing, renders
// the published force model at the device's pose, and fails safe.
#include "devices/null_device.hpp"
#include "devices/simulated_device.hpp"
#include "haptics/device_link.hpp"
#include "haptics/alloc_counter.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

// A stylus that sits where the test puts it, and remembers what it was sent.
class Probe final : public Device {
 public:
  Vec3 position = Vec3::Zero();
  Vec3 sent = Vec3::Constant(-1);
  bool fail = false, nan = false;
  double clock = 0;
  DeviceInfo info() const override { return DeviceInfo{}; }
  DeviceResult read(DeviceState& out) noexcept override {
    if (fail) return {-1, "probe failed"};
    out.position = nan ? Vec3(NAN, 0, 0) : position;
    out.timestamp = (clock += 1e-3);
    return {};
  }
  DeviceResult write(const Vec3& force, const Vec3&) noexcept override {
    sent = force;
    return {};
  }
};

}  // namespace

static void test_poll_allocates_nothing(void**) {
  DeviceSettings settings;
  DeviceLink link(std::make_unique<VirtualHand>([](double t) { return Vec3(0, -0.01 * t, 0); }), settings);
  ForceModel model;
  model.f0 = Vec3(0, 1, 0);
  model.H = -200 * Mat3::Identity();
  model.in_contact = true;
  link.publish(model);
  DeviceState state;
  Vec3 force;
  link.poll(&state, &force);  // first cycle: lazily-touched statics, if any
  mica_test::start_counting_allocations();
  for (int k = 0; k < 1000; ++k) link.poll(&state, &force);
  assert_int_equal(mica_test::stop_counting_allocations(), 0);
  assert_true(force.allFinite());
}

static void test_renders_the_local_model_in_the_device_frame(void**) {
  auto probe = std::make_unique<Probe>();
  Probe* p = probe.get();
  DeviceSettings settings;
  settings.scale = 2;  // scene = R (2 p) + offset
  settings.offset = Vec3(0, 0.1, 0);
  settings.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()));
  settings.filter_window = 1;  // no smoothing: the raw model
  settings.safety.max_rate = 1e9;
  DeviceLink link(std::move(probe), settings);
  ForceModel model;
  model.f0 = Vec3(0, 1.0, 0);
  model.H = -100 * Mat3::Identity();
  model.x0 = Vec3(0, 0.1, 0);
  model.in_contact = true;
  link.publish(model);
  p->position = Vec3(0.001, 0, 0);  // scene: R (0.002, 0, 0) + offset = (0, 0.102, 0)
  Vec3 force;
  assert_true(link.poll(nullptr, &force).ok());
  ScenePose pose;
  assert_true(link.latest_pose(pose));
  assert_near((pose.position - Vec3(0, 0.102, 0)).norm(), 0, 1e-15);
  // Scene force f0 + H (x - x0) = (0, 1 - 100 * 0.002, 0) = (0, 0.8, 0); device force = s R^T F.
  const Vec3 expected = 2 * (settings.rotation.inverse() * Vec3(0, 0.8, 0));
  assert_near((force - expected).norm(), 0, 1e-12);
  assert_near((p->sent - expected).norm(), 0, 1e-12);
}

static void test_fails_safe(void**) {
  auto probe = std::make_unique<Probe>();
  Probe* p = probe.get();
  DeviceSettings settings;
  settings.filter_window = 1;
  settings.safety.max_rate = 1e9;
  DeviceLink link(std::move(probe), settings);
  ForceModel model;
  model.f0 = Vec3(0, 2, 0);
  model.in_contact = true;
  link.publish(model);
  Vec3 force;
  assert_true(link.poll(nullptr, &force).ok());
  assert_near(force.y(), 2.0, 1e-12);
  // The device fails, reads NaN, or its clock jumps back: zero force, a status, a count.
  p->fail = true;
  assert_false(link.poll(nullptr, &force).ok());
  assert_true(p->sent.isZero(0) && force.isZero(0));
  p->fail = false;
  p->nan = true;
  assert_false(link.poll(nullptr, &force).ok());
  assert_true(p->sent.isZero(0));
  p->nan = false;
  p->clock = -1;
  assert_false(link.poll(nullptr, &force).ok());
  assert_int_equal(link.stats().failures.load(), 3);
  // A model with a huge force is clamped to the device's limit, direction kept.
  model.f0 = Vec3(30, 40, 0);
  link.publish(model);
  p->clock = 10;
  assert_true(link.poll(nullptr, &force).ok());
  assert_near(force.norm(), link.info().max_force, 1e-12);
  assert_near(force.normalized().dot(Vec3(0.6, 0.8, 0)), 1.0, 1e-12);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_poll_allocates_nothing),
      cmocka_unit_test(test_renders_the_local_model_in_the_device_frame),
      cmocka_unit_test(test_fails_safe),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
