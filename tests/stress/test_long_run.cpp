// SPDX-License-Identifier: Apache-2.0
// The long run (ctest label "long"): 100000 steps of 16 ms (27 simulated minutes) of a sphere
// driven into a soft block by a virtual hand through a DeviceLink, the servo loop polled 16 times
// per step in lockstep with the simulation (as tests/capi/test_haptics.c does through the C API),
// so the run is the same on any machine. The hand keeps pressing, sliding and lifting off; every
// step goes through stress::Monitor (finite values, energy against the tool's work, penetration)
// and every servo cycle must give a finite force within the device's limit. At the end the hand
// has been out of contact for 10 s and the block must be back at rest where it started.
//
//   stress_test_long_run [--steps N] [--csv PATH]
#include "stress/stress_harness.hpp"

using namespace mica;
using namespace stress;

namespace {

int64_t g_steps = 100000;
std::string g_csv_path;

constexpr double kStep = 0.016;       // s: 16 servo periods of 1 ms
constexpr int kPollsPerStep = 16;
constexpr double kRadius = 0.015;     // m, the sphere
constexpr double kLiftOff = 10.0;     // s at the end with the hand well above the block

// The hand's target (device frame = scene frame here): it goes down to 1 cm below the surface
// and up to 2 cm above it every 4 s, while wandering over the middle of the top face
// (+-2 cm, incommensurate periods), so contact is made and broken, at varying places, all run.
struct Reach {
  double end;  // s, when the lift-off begins
  Vec3 operator()(double t) const {
    if (t >= end) return Vec3(0, 0.05, 0);
    const double depth = 0.005 + 0.015 * std::cos(2 * M_PI * t / 4.0);  // 2 cm above .. 1 cm below
    return Vec3(0.02 * std::sin(2 * M_PI * t / 11.0), depth, 0.02 * std::sin(2 * M_PI * t / 13.0 + 1.0));
  }
};

}  // namespace

static void test_virtual_hand_long_run(void**) {
  Case c;
  c.scenario = 'L';
  c.E = 5e3;
  c.nu = 0.45;
  c.h = kStep;
  c.solver = SolverKind::Mica;
  c.tol = 1e-6;
  c.max_iter = 5000;
  Result r;
  r.c = c;
  r.scene = format("virtual hand through a DeviceLink (16 polls per step) pressing a sphere r 1.5 cm into a 10 cm "
                   "block (750 tets), %lld steps",
                   (long long)g_steps);

  WorldSettings ws;
  ws.gravity = Vec3::Zero();
  ws.solver = c.solver;
  ws.mica_sweep = c.sweep;
  ws.tolerance = c.tol;
  ws.max_iterations = c.max_iter;
  World w(ws);
  BodySettings bs;
  bs.material = {c.E, c.nu, 1000};
  bs.rayleigh_alpha = 2;
  const Id body = w.add_body(make_box_grid(Vec3(-0.05, -0.1, -0.05), Vec3(0.05, 0, 0.05), {5, 5, 5}, 6), bs,
                             Vec3::Zero(), Vec3::Zero());
  w.add_lpc(body, nodes_where(w.body(body), [](const Vec3& p) { return p.y() < -0.1 + 1e-9; }), LpcSpec{});
  Tool t;
  t.radius = kRadius;
  t.margin = 1e-3;
  t.position = Vec3(0, 0.05, 0);
  const Id tool = w.add_tool(t);
  const double end = (double(g_steps) * kStep) - kLiftOff;
  DeviceSettings ds;
  ds.tool = tool;
  const Id device = w.add_device(std::make_unique<VirtualHand>(Reach{end}), ds);
  DeviceLink& link = w.device(device);
  const double max_force = link.info().max_force;

  const Body& b = w.body(body);
  Monitor m(w, {body}, r, 0.02);
  m.set_penetration([&] { return sphere_node_penetration(b, w.tool(tool).position, kRadius); }, kRadius,
                    0.1 * kRadius);
  double peak_force = 0, far = 0;
  int64_t contact_steps = 0, bad_force = 0;
  for (int64_t k = 0; k < g_steps; ++k) {
    m.phase(double(k) * kStep < end ? "touch" : "lift-off");
    for (int p = 0; p < kPollsPerStep; ++p) {
      Vec3 f;
      DeviceState state;
      const DeviceResult res = link.poll(&state, &f);
      if (!res.ok() || !f.allFinite() || !(f.norm() <= max_force * (1 + 1e-12)) || !state.position.allFinite()) {
        if (bad_force++ == 0)
          r.failure(int(k), format("servo cycle %d: code %d, force (%g, %g, %g) N (limit %g N)", p, res.code, f.x(),
                                   f.y(), f.z(), max_force));
      }
      peak_force = std::max(peak_force, f.norm());
    }
    if (!m.step(kStep)) break;
    const Tool& tt = w.tool(tool);
    if (!tt.force.allFinite() || !tt.position.allFinite()) r.failure(int(k), "non-finite tool force or pose");
    contact_steps += tt.contact_count > 0;
    // Bounded: no node strays more than 10 cm from where it started, the tool stays in reach.
    for (size_t i = 0; i < b.x.size(); ++i) far = std::max(far, (b.x[i] - b.fem.rest[i]).norm());
    if (tt.position.norm() > 0.5) r.failure(int(k), "the tool left the workspace");
    if (r.failures.size() >= 8) break;
  }
  m.finish();
  if (far > 0.1) r.failure(r.steps, format("a node moved %.3g m from its rest position", far));
  // Back at rest where it started: nothing drifted over the run.
  double drift = 0, speed = 0;
  for (size_t i = 0; i < b.x.size(); ++i) {
    drift = std::max(drift, (b.x[i] - b.fem.rest[i]).norm());
    speed = std::max(speed, b.v[i].norm());
  }
  if (!(drift < 1e-4 && speed < 1e-4))
    r.failure(r.steps, format("after %.0f s without contact the block is not back at rest: %.3g m from the rest shape, "
                              "%.3g m/s",
                              kLiftOff, drift, speed));
  const ServoStats& st = link.stats();
  if (st.failures.load() != 0) r.failure(r.steps, format("%lld servo failures", (long long)st.failures.load()));
  r.notes = format(" %lld contact steps; peak rendered force %.3f N (limit %.2f N); %lld limited servo cycles; "
                   "farthest node excursion %.3g m; final drift %.3g m;",
                   (long long)contact_steps, peak_force, max_force, (long long)st.clamped.load(), far, drift);
  if (!r.failures.empty()) r.status = "FAIL";
  Csv csv;
  csv.open(g_csv_path);
  csv.write(r);
  print_message("%d steps in %.1f s of CPU (%.3f ms/step), %d not converged, %d hidden non-converged (worst residual "
                "of a converged step %.2g), %.1f iterations/step; energy ratio %.3g (non-converged included %.3g); "
                "penetration %.3g m; inverted max %d;%s\n",
                r.steps, r.cpu_s, 1e3 * r.cpu_s / std::max(r.steps, 1), r.nonconverged, r.hidden_nonconverged,
                r.residual, r.steps ? double(r.iterations) / r.steps : 0.0, r.energy_ratio, r.energy_ratio_all,
                r.penetration, r.max_inverted, r.notes.c_str());
  for (const std::string& f : r.failures) print_message("  %s\n", f.c_str());
  assert_true(r.failures.empty());
  assert_int_equal(r.steps, g_steps);
  assert_true(contact_steps > g_steps / 4);  // it did press, most of the time
}

int main(int argc, char** argv) {
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--steps" && k + 1 < argc) {
      g_steps = std::atoll(argv[++k]);
    } else if (a == "--csv" && k + 1 < argc) {
      g_csv_path = argv[++k];
    } else {
      std::fprintf(stderr, "usage: %s [--steps N] [--csv PATH]\n", argv[0]);
      return 2;
    }
  }
  const struct CMUnitTest tests[] = {cmocka_unit_test(test_virtual_hand_long_run)};
  return cmocka_run_group_tests(tests, NULL, NULL);
}
