// SPDX-License-Identifier: Apache-2.0
// The devices that need no hardware: the null device, the simulated stylus (a function or a
// CSV file, linearly interpolated) and the virtual hand, whose spring-damper is checked
// against its analytic step response, static deflection and energy.
#include "devices/null_device.hpp"
#include "devices/simulated_device.hpp"
#include "devices/trajectory.hpp"
#include "haptics/alloc_counter.hpp"
#include "test_util.hpp"

#include <unistd.h>

using namespace mica;

namespace {

// Runs `f`, which must throw mica::Error with `code` and a message containing every `texts`.
template <class F>
void expect_error(F f, Errc code, std::initializer_list<const char*> texts) {
  bool thrown = false;
  Errc got = Errc::Internal;
  std::string message;
  try {
    f();
  } catch (const Error& e) {
    thrown = true;
    got = e.code();
    message = e.what();
  }
  if (!thrown) fail_msg("no mica::Error thrown");
  if (got != code) fail_msg("error code %d, wanted %d: \"%s\"", int(got), int(code), message.c_str());
  for (const char* text : texts)
    if (message.find(text) == std::string::npos) fail_msg("\"%s\" does not say \"%s\"", message.c_str(), text);
}

// A file in /tmp holding `text`, removed at the end of the scope.
struct TempFile {
  std::string path;
  TempFile(const std::string& name, const std::string& text)
      : path("/tmp/mica_test_devices_" + std::to_string(getpid()) + "_" + name) {
    std::ofstream(path) << text;
  }
  ~TempFile() { std::remove(path.c_str()); }
};

void assert_vec_equal(const Vec3& a, const Vec3& b) {
  for (int i = 0; i < 3; ++i)
    if (!(a[i] == b[i])) fail_msg("component %d: %.17g != %.17g", i, a[i], b[i]);
}

void assert_vec_near(const Vec3& a, const Vec3& b, double tol) {
  for (int i = 0; i < 3; ++i) assert_near(a[i], b[i], tol);
}

DeviceState read_ok(Device& device) {
  DeviceState s;
  const DeviceResult r = device.read(s);
  assert_int_equal(r.code, 0);
  return s;
}

// A target that steps from the origin to `to` just after t = 0.
Trajectory step_to(const Vec3& to) {
  return [to](double t) { return t > 0 ? to : Vec3(Vec3::Zero()); };
}

}  // namespace

// ---- null

static void test_null_device(void**) {
  NullDevice device;
  const DeviceInfo info = device.info();
  assert_string_equal(info.name.data(), "null");
  assert_near(info.max_force, DeviceInfo{}.max_force, 0);
  for (int k = 0; k < 3; ++k) {
    const DeviceState s = read_ok(device);
    assert_vec_equal(s.position, Vec3::Zero());
    assert_vec_equal(s.velocity, Vec3::Zero());
    assert_true(s.orientation.coeffs() == Eigen::Quaterniond::Identity().coeffs());
    assert_int_equal(s.buttons, 0);
    assert_near(s.timestamp, k * NullDevice::kServoPeriod, 1e-15);
    assert_int_equal(device.write(Vec3(1, 2, 3), Vec3(4, 5, 6)).code, 0);
  }
}

// ---- stylus

static void test_stylus_follows_a_function(void**) {
  SimulatedStylus stylus([](double t) { return Vec3(t, 2 * t, t * t); });
  assert_string_equal(stylus.info().name.data(), "simulated stylus");
  const double dt = SimulatedStylus::kServoPeriod;
  for (int k = 0; k < 5; ++k) {
    const double t = k * dt;
    const DeviceState s = read_ok(stylus);
    assert_near(s.timestamp, t, 1e-15);
    assert_vec_equal(s.position, Vec3(s.timestamp, 2 * s.timestamp, s.timestamp * s.timestamp));
    // The backward difference over one period; nothing before t = 0.
    const Vec3 v = k == 0 ? Vec3(Vec3::Zero()) : Vec3(1, 2, 2 * t - dt);
    assert_vec_near(s.velocity, v, 1e-9);
    // The stylus ignores the force.
    assert_int_equal(stylus.write(Vec3(100, 0, 0), Vec3::Zero()).code, 0);
  }
  assert_near(stylus.time(), 5 * dt, 1e-15);
  stylus.set_time(2.0);
  const DeviceState s = read_ok(stylus);
  assert_vec_equal(s.position, Vec3(2, 4, 4));
  assert_vec_near(s.velocity, Vec3(1, 2, 4 - dt), 1e-9);
  expect_error([&] { stylus.set_time(-1); }, Errc::InvalidArgument, {"time"});
  expect_error([&] { stylus.set_time(NAN); }, Errc::InvalidArgument, {"time"});
}

static void test_stylus_without_trajectory_rests_at_origin(void**) {
  SimulatedStylus stylus(nullptr);
  for (int k = 0; k < 3; ++k) {
    const DeviceState s = read_ok(stylus);
    assert_vec_equal(s.position, Vec3::Zero());
    assert_vec_equal(s.velocity, Vec3::Zero());
  }
}

static void test_stylus_reports_a_throwing_trajectory(void**) {
  SimulatedStylus stylus([](double) -> Vec3 { throw std::runtime_error("no"); });
  DeviceState s;
  assert_true(stylus.read(s).code < 0);
}

// Knots at dyadic times and positions, so that interpolation is exact in floating point.
static void test_sampled_trajectory_interpolates_linearly(void**) {
  const SampledTrajectory path({0.5, 1.0, 2.0, 2.5}, {Vec3(0, 0, 0), Vec3(1, -2, 4), Vec3(3, 2, 0), Vec3(3, 2, 1)});
  for (std::size_t i = 0; i < path.times().size(); ++i) assert_vec_equal(path(path.times()[i]), path.positions()[i]);
  assert_vec_equal(path(0.75), Vec3(0.5, -1, 2));
  assert_vec_equal(path(1.5), Vec3(2, 0, 2));
  assert_vec_equal(path(2.25), Vec3(3, 2, 0.5));
  assert_vec_equal(path(1.25), Vec3(1.5, -1, 3));  // a quarter of the way
  // Held at the ends, and a NaN time reads the first sample.
  assert_vec_equal(path(-3), Vec3(0, 0, 0));
  assert_vec_equal(path(7), Vec3(3, 2, 1));
  assert_vec_equal(path(NAN), Vec3(0, 0, 0));

  const SampledTrajectory single({1.0}, {Vec3(1, 2, 3)});
  assert_vec_equal(single(0), Vec3(1, 2, 3));
  assert_vec_equal(single(5), Vec3(1, 2, 3));
  expect_error([] { SampledTrajectory({}, {}); }, Errc::InvalidArgument, {"at least one"});
  expect_error([] { SampledTrajectory({1, 1}, {Vec3::Zero(), Vec3::Zero()}); }, Errc::InvalidArgument,
               {"increase"});
}

static void test_stylus_follows_a_csv_file(void**) {
  const TempFile csv("path.csv",
                     "# a scripted stroke\n"
                     "t,x,y,z\n"
                     "0.5, 0, 0, 0\r\n"
                     "\n"
                     "1.0,1,-2,4\n"
                     "  2.0 ,3, 2e0 ,+0\n"
                     "2.5,3,2,1");  // no newline at the end
  SimulatedStylus stylus(load_trajectory_csv(csv.path));
  const double knots[4] = {0.5, 1.0, 2.0, 2.5};
  const Vec3 at[4] = {Vec3(0, 0, 0), Vec3(1, -2, 4), Vec3(3, 2, 0), Vec3(3, 2, 1)};
  for (int i = 0; i < 4; ++i) {
    stylus.set_time(knots[i]);
    assert_vec_equal(read_ok(stylus).position, at[i]);
  }
  stylus.set_time(1.5);
  assert_vec_equal(read_ok(stylus).position, Vec3(2, 0, 2));
  stylus.set_time(0);
  assert_vec_equal(read_ok(stylus).position, at[0]);  // held before the first row
  stylus.set_time(3);
  assert_vec_equal(read_ok(stylus).position, at[3]);  // and after the last
  stylus.set_time(1.5);
  assert_vec_near(read_ok(stylus).velocity, Vec3(2, 4, -4), 1e-9);  // the slope of the segment

  // Without a header.
  const TempFile bare("bare.csv", "0,1,2,3\n1,2,3,4\n");
  assert_vec_equal(load_trajectory_csv(bare.path)(0.5), Vec3(1.5, 2.5, 3.5));
}

static void test_csv_errors_name_the_line(void**) {
  const TempFile fields("fields.csv", "t,x,y,z\n0,0,0,0\n1,2,3\n");
  expect_error([&] { load_trajectory_csv(fields.path); }, Errc::Parse,
               {fields.path.c_str(), "line 3", "expected 4", "got 3"});
  const TempFile number("number.csv", "0,0,0,0\n1,2,abc,4\n");
  expect_error([&] { load_trajectory_csv(number.path); }, Errc::Parse, {number.path.c_str(), "line 2", "y", "'abc'"});
  const TempFile nan("nan.csv", "0,0,0,0\n1,nan,0,0\n");
  expect_error([&] { load_trajectory_csv(nan.path); }, Errc::Parse, {"line 2", "x is not a finite number"});
  const TempFile order("order.csv", "t,x,y,z\n0,0,0,0\n\n1,0,0,0\n1,1,1,1\n");
  expect_error([&] { load_trajectory_csv(order.path); }, Errc::Parse, {"line 5", "does not come after"});
  // A misspelt first row is data, not a header.
  const TempFile typo("typo.csv", "0,0,0,q\n1,1,1,1\n");
  expect_error([&] { load_trajectory_csv(typo.path); }, Errc::Parse, {"line 1", "z"});
  const TempFile empty("empty.csv", "t,x,y,z\n# nothing\n");
  expect_error([&] { load_trajectory_csv(empty.path); }, Errc::Parse, {empty.path.c_str(), "no samples"});
  expect_error([] { load_trajectory_csv("/nonexistent/mica/path.csv"); }, Errc::Io, {"/nonexistent/mica/path.csv"});
}

// ---- virtual hand

static void test_hand_starts_on_its_target_and_feels_the_force(void**) {
  const Vec3 target(0.01, -0.02, 0.03);
  VirtualHand hand([target](double) { return target; });
  assert_string_equal(hand.info().name.data(), "virtual hand");
  DeviceState s = read_ok(hand);  // the initial state, before any step
  assert_vec_equal(s.position, target);
  assert_vec_equal(s.velocity, Vec3::Zero());
  assert_near(s.timestamp, 0, 0);
  // On its target the only force is the rendered one: one step gains F dt / m.
  const Vec3 F(0.2, 0, -0.1);
  hand.write(F, Vec3(9, 9, 9));
  s = read_ok(hand);
  const double dt = VirtualHand::kServoPeriod, m = hand.params().mass;
  assert_vec_near(s.velocity, F * dt / m, 1e-15);
  assert_vec_near(s.position, target + F * dt * dt / m, 1e-15);
  assert_near(s.timestamp, dt, 1e-15);
}

// Settles on a step target with no force: the steady state is the target.
static void test_hand_settles_on_its_target(void**) {
  const Vec3 A(0.02, -0.01, 0.005);
  VirtualHand hand(step_to(A));
  DeviceState s;
  for (int k = 0; k < 5000; ++k) {  // 5 s: 1.5e-5 of the initial amplitude remains after 3 s
    s = read_ok(hand);
    hand.write(Vec3::Zero(), Vec3::Zero());
  }
  assert_vec_near(s.position, A, 1e-9);
  assert_vec_near(s.velocity, Vec3::Zero(), 1e-8);
}

// The step response's overshoot and peak time are those of the damped oscillator, for a
// light and a heavier damping.
static void test_hand_overshoot_matches_its_damping_ratio(void**) {
  for (const double damping : {2.0, 5.0}) {
    HandParams p;  // 0.1 kg, 200 N/m
    p.damping = damping;
    const double A = 0.01;
    VirtualHand hand(step_to(Vec3(A, 0, 0)), p);
    const double wn = std::sqrt(p.stiffness / p.mass), zeta = p.damping / (2 * std::sqrt(p.stiffness * p.mass));
    const double wd = wn * std::sqrt(1 - zeta * zeta);
    const double overshoot = std::exp(-zeta * M_PI / std::sqrt(1 - zeta * zeta));
    double peak = 0, peak_time = 0;
    for (int k = 0; k < 1000; ++k) {
      const DeviceState s = read_ok(hand);
      if (s.position.x() > peak) {
        peak = s.position.x();
        peak_time = s.timestamp;
      }
    }
    print_message("damping ratio %.4f: overshoot %.5f, analytic %.5f; peak at %.4f s, analytic %.4f s\n", zeta,
                  peak / A - 1, overshoot, peak_time - VirtualHand::kServoPeriod, M_PI / wd);
    // The explicit damping term of the 1 ms step decays the amplitude a little faster than
    // the continuous hand (|lambda|^2 = 1 - dt b/m against exp(-dt b/m)): under 1% at b = 2,
    // 4% at b = 5. A 10% error on the damping ratio would move the overshoot by 13% or more.
    assert_near(peak / A - 1, overshoot, 0.05 * overshoot);
    // The step reaches the hand one period late.
    assert_near(peak_time - VirtualHand::kServoPeriod, M_PI / wd, 2e-3);
  }
}

// A constant rendered force F moves the rest point to target + F / k.
static void test_hand_under_constant_force_settles_at_the_spring_deflection(void**) {
  const Vec3 A(0.01, 0.02, -0.03), F(0.5, -0.25, 0.1);
  HandParams p;
  p.stiffness = 150;
  VirtualHand hand(step_to(A), p);
  DeviceState s;
  for (int k = 0; k < 6000; ++k) {
    s = read_ok(hand);
    hand.write(F, Vec3::Zero());
  }
  assert_vec_near(s.position, A + F / p.stiffness, 1e-9);
}

// Energy = kinetic + spring about the target: damping drains it, and with none the
// semi-implicit step neither drains nor feeds it over thousands of periods.
static double hand_energy(const VirtualHand& hand, const Vec3& target) {
  return 0.5 * hand.params().mass * hand.velocity().squaredNorm() +
         0.5 * hand.params().stiffness * (hand.position() - target).squaredNorm();
}

static void test_hand_energy_decays_with_damping(void**) {
  const Vec3 A(0.01, 0, 0);
  VirtualHand hand(step_to(A));
  read_ok(hand);
  const double e0 = hand_energy(hand, A);
  // The largest energy of each half period (35 ms) decreases from one to the next.
  double last_max = e0 * (1 + 1e-12);
  for (int window = 0; window < 20; ++window) {
    double max = 0;
    for (int k = 0; k < 35; ++k) {
      read_ok(hand);
      max = std::max(max, hand_energy(hand, A));
    }
    assert_le(max, last_max);
    last_max = max;
  }
  assert_le(hand_energy(hand, A), 1e-4 * e0);

  HandParams undamped;
  undamped.damping = 0;
  VirtualHand spring(step_to(A), undamped);
  read_ok(spring);
  for (int k = 0; k < 5000; ++k) {
    read_ok(spring);
    assert_near(hand_energy(spring, A) / e0, 1.0, 0.03);
  }
}

static void test_hand_rejects_bad_parameters(void**) {
  const auto make = [](double m, double k, double b) { VirtualHand({}, HandParams{m, k, b}); };
  expect_error([&] { make(0, 200, 5); }, Errc::InvalidArgument, {"mass"});
  expect_error([&] { make(0.1, -1, 5); }, Errc::InvalidArgument, {"stiffness"});
  expect_error([&] { make(0.1, 200, NAN); }, Errc::InvalidArgument, {"damping"});
  // 1 ms steps are unstable beyond dt^2 k/m + 2 dt b/m = 4.
  expect_error([&] { make(0.001, 5000, 0); }, Errc::InvalidArgument, {"too high"});
  make(0.001, 3000, 0.4);  // 3 + 0.8 < 4: stable
}

// read() and write() run on the servo thread: no allocation.
static void test_servo_calls_do_not_allocate(void**) {
  NullDevice null_device;
  SimulatedStylus stylus(load_trajectory_csv(TempFile("alloc.csv", "0,0,0,0\n1,1,1,1\n").path));
  VirtualHand hand([](double t) { return Vec3(t, 0, 0); });
  Device* devices[3] = {&null_device, &stylus, &hand};
  DeviceState s;
  mica_test::start_counting_allocations();
  for (Device* d : devices)
    for (int k = 0; k < 10; ++k) {
      d->read(s);
      d->write(Vec3(0.1, 0, 0), Vec3::Zero());
    }
  assert_int_equal(mica_test::stop_counting_allocations(), 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_null_device),
      cmocka_unit_test(test_stylus_follows_a_function),
      cmocka_unit_test(test_stylus_without_trajectory_rests_at_origin),
      cmocka_unit_test(test_stylus_reports_a_throwing_trajectory),
      cmocka_unit_test(test_sampled_trajectory_interpolates_linearly),
      cmocka_unit_test(test_stylus_follows_a_csv_file),
      cmocka_unit_test(test_csv_errors_name_the_line),
      cmocka_unit_test(test_hand_starts_on_its_target_and_feels_the_force),
      cmocka_unit_test(test_hand_settles_on_its_target),
      cmocka_unit_test(test_hand_overshoot_matches_its_damping_ratio),
      cmocka_unit_test(test_hand_under_constant_force_settles_at_the_spring_deflection),
      cmocka_unit_test(test_hand_energy_decays_with_damping),
      cmocka_unit_test(test_hand_rejects_bad_parameters),
      cmocka_unit_test(test_servo_calls_do_not_allocate),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
