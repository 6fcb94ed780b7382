// SPDX-License-Identifier: Apache-2.0
// The Touch backend against tests/devices/fake_hd, an HD library scripted frame by frame and
// loaded the way the real one is: through MICA_HD_LIBRARY and dlopen. Covers unit conversion,
// the one-frame-per-servo-cycle protocol, the forces sent, the scheduler, HD errors mapped to
// results and every way opening the device fails.
// Built without tests/devices/fake_hd.cmake (MICA_FAKE_HD_LIBRARY undefined) it fails and says so.
#include "devices/touch_device.hpp"

#ifdef MICA_FAKE_HD_LIBRARY
#include "devices/fake_hd/fake_hd.h"
#include "haptics/alloc_counter.hpp"
#include "haptics/device_link.hpp"
#endif

#include "test_util.hpp"

#include <chrono>
#include <cstdlib>
#include <thread>

using namespace mica;

#ifdef MICA_FAKE_HD_LIBRARY

namespace {

// Runs `f`, which must throw mica::Error with `code`; returns its message.
template <class F>
std::string expect_error(Errc code, F f) {
  try {
    f();
  } catch (const Error& e) {
    if (e.code() != code) fail_msg("error code %d, wanted %d: %s", int(e.code()), int(code), e.what());
    return e.what();
  }
  fail_msg("no mica::Error thrown");
  return {};
}

void assert_contains(const std::string& text, const char* part) {
  if (text.find(part) == std::string::npos) fail_msg("\"%s\" does not say \"%s\"", text.c_str(), part);
}

int reset(void**) {
  fake_hd_reset();
  return 0;
}

// Every HD call of the backend came in the right place: inside a frame, with its handle.
void assert_protocol_kept() { assert_int_equal(fake_hd_misuse(), 0); }

}  // namespace

static void test_opens_the_device(void**) {
  {
    TouchDevice touch;
    assert_string_equal(touch.library().c_str(), MICA_FAKE_HD_LIBRARY);
    assert_true(fake_hd_initialized());
    assert_null(fake_hd_device_name());  // HD_DEFAULT_DEVICE
    assert_true(fake_hd_force_output());
    const DeviceInfo info = touch.info();
    assert_string_equal(info.name.data(), "Fake Touch");
    assert_near(info.max_force, 3.3, 0);
    assert_near(info.continuous_force, 0.88, 0);
    assert_near(info.nominal_stiffness, 1250, 1e-9);  // 1.25 N/mm
    assert_near(info.nominal_damping, 2.5, 1e-12);    // 0.0025 N s/mm
    assert_near(info.workspace_radius, 0.035, 1e-15);  // half of the 70 mm depth
    assert_int_equal(fake_hd_calibration_updates(), 0);
  }
  // Closing disables force output and the device.
  assert_false(fake_hd_initialized());
  assert_false(fake_hd_force_output());
  assert_protocol_kept();

  TouchDevice named("Right Touch");
  assert_string_equal(fake_hd_device_name(), "Right Touch");
}

// Positions mm -> m and velocities mm/s -> m/s, each divided once; the orientation is the
// rotation of HD's transform.
static void test_reads_the_stylus_in_si_units(void**) {
  TouchDevice touch;
  const long opening = fake_hd_frame_count();  // the calibration check's frame
  for (long frame = opening; frame < opening + 50; ++frame) {
    DeviceState s;
    assert_int_equal(touch.read(s).code, 0);
    assert_int_equal(fake_hd_frame_count(), frame + 1);
    double p[3], v[3];
    int buttons = 0;
    fake_hd_stylus(frame, p, v, nullptr, &buttons);
    for (int i = 0; i < 3; ++i) {
      assert_true(s.position[i] == p[i] / 1000);
      assert_true(s.velocity[i] == v[i] / 1000);
    }
    assert_int_equal(s.buttons, buttons);
    const double half = 0.0005 * double(frame);  // the fake turns 1 mrad a frame about z
    assert_near(s.orientation.w(), std::cos(half), 1e-12);
    assert_near(s.orientation.z(), std::sin(half), 1e-12);
    assert_near(s.orientation.x(), 0, 1e-12);
    assert_near(s.orientation.y(), 0, 1e-12);
    assert_int_equal(touch.write(Vec3::Zero(), Vec3::Zero()).code, 0);
  }
  // The fake's first frame: (0, 10, 40) mm.
  double p0[3];
  fake_hd_stylus(0, p0, nullptr, nullptr, nullptr);
  assert_true(p0[1] / 1000 == 0.01 && p0[2] / 1000 == 0.04);
  assert_protocol_kept();
}

// One read and one write are one frame; the forces arrive exactly as sent.
static void test_sends_forces_one_frame_per_cycle(void**) {
  TouchDevice touch;
  const long before = fake_hd_force_count(), opening = fake_hd_frame_count();
  std::vector<Vec3> sent;
  for (int k = 0; k < 20; ++k) {
    DeviceState s;
    touch.read(s);
    sent.emplace_back(0.1 * k, -0.3 + 0.01 * k, 1.0 / (k + 3));
    assert_int_equal(touch.write(sent.back(), Vec3(1, 1, 1)).code, 0);
  }
  assert_int_equal(fake_hd_frame_count() - opening, 20);
  assert_int_equal(fake_hd_force_count() - before, 20);
  for (int k = 0; k < 20; ++k) {
    double f[3];
    assert_true(fake_hd_force(before + k, f));
    for (int i = 0; i < 3; ++i) assert_true(f[i] == sent[std::size_t(k)][i]);
  }
  // A write without a read is a frame of its own; a read without a write ends its frame,
  // sending no force, when the next cycle begins.
  touch.write(Vec3(0.5, 0, 0), Vec3::Zero());
  DeviceState s;
  touch.read(s);
  touch.read(s);
  double f[3];
  assert_true(fake_hd_force(fake_hd_force_count() - 1, f));
  assert_true(f[0] == 0 && f[1] == 0 && f[2] == 0);
  touch.write(Vec3(0.25, 0, 0), Vec3::Zero());
  assert_int_equal(fake_hd_frame_count() - opening, 23);
  assert_protocol_kept();
  assert_int_equal(fake_hd_nonfinite_forces(), 0);
}

static void test_servo_calls_do_not_allocate(void**) {
  TouchDevice touch;
  DeviceState s;
  mica_test::start_counting_allocations();
  for (int k = 0; k < 100; ++k) {
    touch.read(s);
    touch.write(Vec3(0.1, 0, 0), Vec3::Zero());
  }
  assert_int_equal(mica_test::stop_counting_allocations(), 0);
}

namespace {

// What libmica's poll does on each tick: read, then write a force computed from the reading.
struct Servo {
  TouchDevice* touch = nullptr;
  long ticks = 0;
  long failures = 0;
  static void tick(void* self) {
    Servo& servo = *static_cast<Servo*>(self);
    DeviceState s;
    if (!servo.touch->read(s).ok()) ++servo.failures;
    const Vec3 force = -10.0 * s.position;  // a spring to the origin
    if (!servo.touch->write(force, Vec3::Zero()).ok()) ++servo.failures;
    ++servo.ticks;
  }
};

}  // namespace

// Driven tick by tick: every tick is one frame, one reading and one force computed from it.
static void test_scheduler_ticks_are_servo_cycles(void**) {
  fake_hd_set_manual_scheduler(1);
  TouchDevice touch;
  const long opening = fake_hd_frame_count();
  Servo servo;
  servo.touch = &touch;
  assert_true(touch.start_scheduler(&Servo::tick, &servo));
  fake_hd_run_ticks(250);
  assert_int_equal(servo.ticks, 250);
  assert_int_equal(servo.failures, 0);
  assert_int_equal(fake_hd_frame_count() - opening, 250);
  assert_int_equal(fake_hd_force_count(), 250);
  for (long k = 0; k < 250; ++k) {
    double p[3], f[3];
    fake_hd_stylus(opening + k, p, nullptr, nullptr, nullptr);
    assert_true(fake_hd_force(k, f));
    for (int i = 0; i < 3; ++i) assert_true(f[i] == -10.0 * (p[i] / 1000));
  }
  touch.stop_scheduler();
  fake_hd_run_ticks(5);  // unscheduled: HD no longer calls it
  assert_int_equal(servo.ticks, 250);
  assert_protocol_kept();
}

// The real thing: HD's scheduler thread at 1 kHz for a while.
static void test_runs_the_hd_scheduler(void**) {
  TouchDevice touch;
  const long opening = fake_hd_frame_count();
  Servo servo;
  servo.touch = &touch;
  assert_true(touch.start_scheduler(&Servo::tick, &servo));
  assert_true(fake_hd_scheduler_running());
  assert_int_equal(fake_hd_last_priority(), 0xFFFF);  // HD_MAX_SCHEDULER_PRIORITY
  assert_int_equal(fake_hd_scheduled_callbacks(), 1);
  expect_error(Errc::WrongState, [&] { touch.start_scheduler(&Servo::tick, &servo); });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  touch.stop_scheduler();
  assert_false(fake_hd_scheduler_running());
  assert_int_equal(fake_hd_scheduled_callbacks(), 0);
  const long ticks = servo.ticks;
  print_message("200 ms of the fake's 1 kHz scheduler: %ld ticks\n", ticks);
  assert_true(ticks >= 20);  // 2 shared cores: a loose floor
  assert_int_equal(servo.failures, 0);
  // Every tick was one frame and one force: -10 N/m times the position the tick read.
  assert_int_equal(fake_hd_frame_count() - opening, ticks);
  assert_int_equal(fake_hd_force_count(), ticks);
  for (long k = 0; k < ticks; ++k) {
    double p[3], f[3];
    fake_hd_stylus(opening + k, p, nullptr, nullptr, nullptr);
    assert_true(fake_hd_force(k, f));
    for (int i = 0; i < 3; ++i) assert_true(f[i] == -10.0 * (p[i] / 1000));
  }
  assert_int_equal(fake_hd_nonfinite_forces(), 0);
  assert_protocol_kept();
  // Stopped means stopped.
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  assert_int_equal(servo.ticks, ticks);
}

// The scheduler restarts after a stop, and closing the device stops it.
static void test_destructor_stops_the_scheduler(void**) {
  Servo servo;
  long first_run = 0;
  {
    TouchDevice touch;
    servo.touch = &touch;
    touch.start_scheduler(&Servo::tick, &servo);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    touch.stop_scheduler();
    first_run = servo.ticks;
    assert_true(touch.start_scheduler(&Servo::tick, &servo));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    assert_true(fake_hd_scheduler_running());
  }
  assert_true(servo.ticks > first_run);
  assert_false(fake_hd_scheduler_running());
  assert_int_equal(fake_hd_scheduled_callbacks(), 0);
  assert_false(fake_hd_initialized());
  assert_int_equal(servo.failures, 0);
  assert_protocol_kept();
}

// HD_WARM_MOTORS and HD_EXCEEDED_MAX_FORCE are warnings (the force was sent); the rest fail.
static void test_maps_hd_errors_to_results(void**) {
  TouchDevice touch;
  DeviceState s;
  fake_hd_set_frame_error(HD_WARM_MOTORS);
  assert_int_equal(touch.read(s).code, 0);
  DeviceResult r = touch.write(Vec3(0.1, 0, 0), Vec3::Zero());
  assert_int_equal(r.code, HD_WARM_MOTORS);
  assert_true(r.ok());
  assert_contains(r.message, "HD_WARM_MOTORS");

  fake_hd_set_frame_error(HD_EXCEEDED_MAX_FORCE);
  touch.read(s);
  r = touch.write(Vec3(5, 0, 0), Vec3::Zero());
  assert_int_equal(r.code, HD_EXCEEDED_MAX_FORCE);

  fake_hd_set_frame_error(HD_COMM_ERROR);
  touch.read(s);
  r = touch.write(Vec3(0.1, 0, 0), Vec3::Zero());
  assert_int_equal(r.code, -HD_COMM_ERROR);
  assert_false(r.ok());
  assert_contains(r.message, "HD_COMM_ERROR");

  // The error stack is emptied each time: the next clean frame is clean.
  fake_hd_set_frame_error(HD_SUCCESS);
  assert_int_equal(touch.read(s).code, 0);
  assert_int_equal(touch.write(Vec3::Zero(), Vec3::Zero()).code, 0);
  // The force went out every time, warning or not.
  assert_int_equal(fake_hd_force_count(), 4);
  assert_protocol_kept();
}

static void test_init_failure_gives_the_hd_code(void**) {
  fake_hd_fail_init(HD_COMM_ERROR);
  const std::string message = expect_error(Errc::Device, [] { TouchDevice touch("Left Touch"); });
  print_message("%s\n", message.c_str());
  assert_contains(message, "0x0302");
  assert_contains(message, "HD_COMM_ERROR");
  assert_contains(message, "fake HD: communication error");  // hdGetErrorString
  assert_contains(message, "'Left Touch'");
  assert_false(fake_hd_initialized());
}

static void test_calibration(void**) {
  // Needing an update: HD updates it alone, in the style the device supports.
  fake_hd_set_calibration(HD_CALIBRATION_NEEDS_UPDATE, HD_CALIBRATION_INKWELL | HD_CALIBRATION_ENCODER_RESET);
  {
    TouchDevice touch;
    assert_int_equal(fake_hd_calibration_updates(), 1);
    assert_int_equal(fake_hd_calibration_style_used(), HD_CALIBRATION_INKWELL);
  }
  fake_hd_set_calibration(HD_CALIBRATION_NEEDS_UPDATE, HD_CALIBRATION_AUTO | HD_CALIBRATION_INKWELL);
  { TouchDevice touch; }
  assert_int_equal(fake_hd_calibration_style_used(), HD_CALIBRATION_AUTO);
  // Needing a person: the error says what to do, and the device is released.
  fake_hd_set_calibration(HD_CALIBRATION_NEEDS_MANUAL_INPUT, HD_CALIBRATION_INKWELL);
  const std::string message = expect_error(Errc::Device, [] { TouchDevice touch; });
  print_message("%s\n", message.c_str());
  assert_contains(message, "manual calibration");
  assert_contains(message, "inkwell");
  assert_false(fake_hd_initialized());
  assert_protocol_kept();
}

static void test_missing_library_names_the_path(void**) {
  const char* path = "/nonexistent/OpenHaptics/libHD.so";
  std::string message = expect_error(Errc::Device, [&] { TouchDevice touch("", path); });
  print_message("%s\n", message.c_str());
  assert_contains(message, path);
  assert_contains(message, "MICA_HD_LIBRARY");
  // The same through the environment, and the default when it is unset.
  setenv("MICA_HD_LIBRARY", path, 1);
  message = expect_error(Errc::Device, [] { TouchDevice touch; });
  assert_contains(message, path);
  unsetenv("MICA_HD_LIBRARY");
  assert_string_equal(TouchDevice::default_library().c_str(), "libHD.so");
  setenv("MICA_HD_LIBRARY", MICA_FAKE_HD_LIBRARY, 1);
  // A library that is not HD: it lacks the functions.
  message = expect_error(Errc::Device, [] { TouchDevice touch("", "libm.so.6"); });
  assert_contains(message, "hdInitDevice");
}

// A hostile libHD (issue 16): NaN and huge poses, transforms that are no rotation, 50 ms stalls,
// absurd nominal figures. Through the servo cycle (DeviceLink::poll) every cycle ends with a
// status, a finite force within the clamp reaches HD, and the bad readings are refused; absurd
// figures are refused when the device is attached.
static void test_hostile_hd(void**) {
  const std::string figures = expect_error(Errc::Device, [] {
    fake_hd_set_hostile(FAKE_HD_HOSTILE_FIGURES);
    DeviceLink link(std::make_unique<TouchDevice>(), DeviceSettings{});
  });
  assert_contains(figures, "max_force");
  const int modes[] = {FAKE_HD_HOSTILE_NAN_POSE, FAKE_HD_HOSTILE_HUGE_POSE, FAKE_HD_HOSTILE_BAD_ROTATION,
                       FAKE_HD_HOSTILE_STALL};
  const char* names[] = {"NaN poses", "huge poses", "bad rotations", "50 ms stalls"};
  for (int m = 0; m < 4; ++m) {
    fake_hd_reset();
    fake_hd_set_hostile(modes[m]);
    DeviceSettings settings;
    settings.mode = ForceMode::Hold;
    settings.filter_window = 1;
    DeviceLink link(std::make_unique<TouchDevice>(), settings);
    const double clamp = link.info().max_force;
    ForceModel model;
    model.f0 = Vec3(0, 50, 0);  // far above the clamp
    model.step = 1;
    link.publish(model);
    const long first_force = fake_hd_force_count();
    int failures = 0;
    for (int k = 0; k < 60; ++k) {
      DeviceState state;
      Vec3 force;
      const DeviceResult r = link.poll(&state, &force);
      assert_true(r.code >= -1 && r.code <= 1);
      assert_true(r.message != nullptr);
      failures += r.code < 0;
      assert_true(force.allFinite());
      assert_true(force.norm() <= clamp * (1 + 1e-12));
      if (r.ok()) {
        assert_true(state.position.allFinite());
        assert_near(state.orientation.norm(), 1, 1e-12);
      }
      if (k % 10 == 9) link.publish(model);
    }
    for (long i = first_force; i < fake_hd_force_count(); ++i) {
      double f[3];
      assert_true(fake_hd_force(i, f));
      assert_true(std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) <= clamp * (1 + 1e-12));
    }
    print_message("%-14s 60 cycles, %d refused, clamp %.2f N\n", names[m], failures, clamp);
    if (modes[m] == FAKE_HD_HOSTILE_STALL) assert_int_equal(failures, 0);
    else assert_true(failures >= 15);
    assert_int_equal(fake_hd_nonfinite_forces(), 0);
  }
  assert_protocol_kept();
}

int main(void) {
  // The backend finds the fake as it would find OpenHaptics.
  setenv("MICA_HD_LIBRARY", MICA_FAKE_HD_LIBRARY, 1);
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup(test_opens_the_device, reset),
      cmocka_unit_test_setup(test_reads_the_stylus_in_si_units, reset),
      cmocka_unit_test_setup(test_sends_forces_one_frame_per_cycle, reset),
      cmocka_unit_test_setup(test_servo_calls_do_not_allocate, reset),
      cmocka_unit_test_setup(test_scheduler_ticks_are_servo_cycles, reset),
      cmocka_unit_test_setup(test_runs_the_hd_scheduler, reset),
      cmocka_unit_test_setup(test_destructor_stops_the_scheduler, reset),
      cmocka_unit_test_setup(test_maps_hd_errors_to_results, reset),
      cmocka_unit_test_setup(test_init_failure_gives_the_hd_code, reset),
      cmocka_unit_test_setup(test_calibration, reset),
      cmocka_unit_test_setup(test_missing_library_names_the_path, reset),
      cmocka_unit_test_setup(test_hostile_hd, reset),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

#else

int main(void) {
  std::fprintf(stderr,
               "devices/test_touch_backend needs the fake HD library: add\n"
               "  include(${CMAKE_CURRENT_SOURCE_DIR}/devices/fake_hd.cmake)\n"
               "to tests/CMakeLists.txt\n");
  return 1;
}

#endif
