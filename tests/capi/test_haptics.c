/* SPDX-License-Identifier: Apache-2.0 */
/* The haptic loop through the C API: a simulation thread at 60 Hz and libmica's 1 kHz servo
 * thread, with a virtual hand (mass-spring-damper) reaching into a soft block. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <time.h>

#include <mica/mica.h>
#include <mica/mica_device.h>

typedef struct {
  mica_world* world;
  mica_body_id body;
  mica_tool_id tool;
  mica_lpc_id base;
} scene;

static scene make_scene(double youngs_modulus) {
  scene s = {NULL, 0, 0, 0};
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = 0;
  wd.solver = MICA_SOLVER_MICA;
  wd.tolerance = 1e-6;
  wd.max_iterations = 5000;
  assert_int_equal(mica_world_create(&wd, &s.world), MICA_OK);
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = youngs_modulus;
  bd.rayleigh_alpha = 2;
  const double lo[3] = {-0.05, -0.1, -0.05}, hi[3] = {0.05, 0, 0.05};
  const int32_t cells[3] = {5, 5, 5};
  assert_int_equal(mica_body_create_box(s.world, &bd, lo, hi, cells, 6, &s.body), MICA_OK);
  int32_t base[64], n = 0;
  const double o[3] = {0, -0.1, 0}, up[3] = {0, 1, 0};
  assert_int_equal(mica_body_select_nodes_by_plane(s.world, s.body, o, up, 1e-9, 1, base, 64, &n), MICA_OK);
  const mica_lpc_def fixed = mica_lpc_def_default();
  assert_int_equal(mica_add_lpc(s.world, s.body, base, n, &fixed, &s.base), MICA_OK);
  mica_tool_def td = mica_tool_def_default();
  td.radius = 0.015;
  td.position[0] = 0.004;
  td.position[1] = 0.05;
  assert_int_equal(mica_tool_create(s.world, &td, &s.tool), MICA_OK);
  return s;
}

/* The hand reaches for a point 1 cm below the surface: the sphere (radius 1.5 cm, centred on
 * the hand) presses 2.5 cm into the block, and the tissue pushes back. It comes down 4 mm off
 * the cell's diagonal: a sphere smaller than the cells, centred exactly over a surface edge, can
 * still slip between nodes (contacts are made at nodes and face interiors; edges are next). */
static void reach(double t, double p[3], void* user) {
  (void)user;
  p[0] = 0.004;
  p[1] = t < 0.5 ? 0.05 - 0.12 * t : 0.015 - 0.025;
  p[2] = 0;
}

/* A virtual hand following `reach`, driving the scene's tool. */
static mica_device_id add_hand(scene* s, mica_device_def* dd, mica_device_info* info) {
  *dd = mica_device_def_default();
  dd->backend = MICA_DEVICE_SIMULATED;
  dd->simulated_kind = MICA_SIMULATED_HAND;
  dd->trajectory = reach;
  dd->tool = s->tool;
  mica_device_id device;
  assert_int_equal(mica_device_create(s->world, dd, &device), MICA_OK);
  info->struct_size = sizeof *info;
  assert_int_equal(mica_device_get_info(s->world, device, info), MICA_OK);
  return device;
}

static void sleep_ms(double ms) {
  struct timespec ts = {0, (long)(ms * 1e6)};
  nanosleep(&ts, NULL);
}

/* The hand and the simulation in lockstep: 16 servo polls (the hand's clock advances 1 ms per
 * read) per 16 ms step, so the run is the same on any machine. */
static void closed_loop(double youngs_modulus) {
  scene s = make_scene(youngs_modulus);
  mica_device_def dd;
  mica_device_info info;
  const mica_device_id device = add_hand(&s, &dd, &info);
  double max_force = 0, last_y[3] = {0, 0, 0}, tool[3] = {0, 0, 0};
  for (int k = 0; k < 150; ++k) { /* 2.4 s */
    for (int p = 0; p < 16; ++p) {
      double f[3];
      assert_true(mica_device_poll(s.world, device, NULL, f) >= 0);
      const double m = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
      assert_true(isfinite(m));
      if (m > max_force) max_force = m;
    }
    assert_true(mica_step(s.world, 0.016) >= 0);
    assert_int_equal(mica_tool_get_force(s.world, s.tool, tool, NULL, NULL), MICA_OK);
    last_y[k % 3] = tool[1];
    if (getenv("MICA_TEST_TRACE")) print_message("step %d tool force y %.4f\n", k, tool[1]);
  }
  mica_device_stats st = {sizeof st};
  assert_int_equal(mica_device_get_stats(s.world, device, &st), MICA_OK);
  print_message("%lld polls, %lld failures, %lld limited; peak rendered force %.3f N (device max %.2f N); final tool "
                "force y %.3f N\n",
                (long long)st.polls, (long long)st.failures, (long long)st.clamped, max_force, info.max_force, tool[1]);
  assert_int_equal(st.failures, 0);
  assert_true(max_force <= info.max_force * (1 + 1e-12)); /* never above the device's limit */
  assert_true(tool[1] > 0.05);     /* the tissue pushes the tool (and the hand) back up */
  /* Settled, not oscillating: the last three steps' forces agree within 1%. */
  assert_true(fabs(last_y[0] - last_y[1]) < 0.01 * fabs(last_y[0]) && fabs(last_y[1] - last_y[2]) < 0.01 * fabs(last_y[1]));
  /* At rest the hand's spring (200 N/m toward y = -0.01 m) balances the force it is rendered:
   * the tissue's, or the device's limit when the tissue pushes harder. */
  double pose[3];
  assert_int_equal(mica_tool_get_pose(s.world, s.tool, pose, NULL), MICA_OK);
  const double pull = dd.hand_stiffness * (pose[1] - (-0.01));
  const double rendered = tool[1] < info.max_force ? tool[1] : info.max_force;
  print_message("E %.0e Pa: hand spring pull %.4f N against rendered %.4f N (tissue %.4f N)\n", youngs_modulus, pull,
                rendered, tool[1]);
  assert_true(fabs(pull - rendered) < 0.03 * rendered);
  assert_int_equal(mica_device_destroy(s.world, device), MICA_OK);
  mica_world_destroy(s.world);
}

static void test_closed_loop_soft(void** state) {
  (void)state;
  closed_loop(5e3);
}

/* A stiff body pushes back harder than the device can render: the hand presses on until its
 * pull equals the device's limit, and stays there. */
static void test_closed_loop_stiff(void** state) {
  (void)state;
  closed_loop(1e6);
}

/* The real thing: libmica's 1 kHz servo thread beside a 60 Hz simulation thread. What it
 * asserts holds whatever the machine's speed (under a sanitizer too): every force finite and
 * within the device's limit, the servo loop running, no device failure. */
static void test_servo_thread_beside_simulation(void** state) {
  (void)state;
  scene s = make_scene(5e3);
  mica_device_def dd;
  mica_device_info info;
  const mica_device_id device = add_hand(&s, &dd, &info);
  assert_int_equal(mica_device_start(s.world, device), MICA_OK);
  for (int k = 0; k < 60; ++k) {
    assert_true(mica_step(s.world, 1.0 / 60.0) >= 0);
    mica_device_stats st = {sizeof st};
    assert_int_equal(mica_device_get_stats(s.world, device, &st), MICA_OK);
    const double f = sqrt(st.last_force[0] * st.last_force[0] + st.last_force[1] * st.last_force[1] +
                          st.last_force[2] * st.last_force[2]);
    assert_true(isfinite(f) && f <= info.max_force * (1 + 1e-12));
    sleep_ms(1000.0 / 60.0);
  }
  assert_int_equal(mica_device_stop(s.world, device), MICA_OK);
  mica_device_stats st = {sizeof st};
  assert_int_equal(mica_device_get_stats(s.world, device, &st), MICA_OK);
  print_message("%lld polls in 1 s of wall time (%.0f Hz), %lld failures\n", (long long)st.polls, st.rate_hz,
                (long long)st.failures);
  assert_true(st.polls > 100);
  assert_int_equal(st.failures, 0);
  assert_int_equal(mica_device_destroy(s.world, device), MICA_OK);
  mica_world_destroy(s.world);
}

/* A host device through the callback table, polled by hand: the tool follows the stylus
 * (through the workspace mapping), a failing read gives zero force and a status, and the
 * simulation goes on. */
typedef struct {
  double y;
  int fail;
  double sent[3];
  int writes;
} stylus;

static mica_status read_stylus(void* user, mica_device_state* out) {
  stylus* s = user;
  if (s->fail) return MICA_ERR_DEVICE;
  out->position[0] = 0;
  out->position[1] = s->y;
  out->position[2] = 0;
  out->timestamp += 0.001;
  return MICA_OK;
}

static mica_status write_stylus(void* user, const double force[3], const double torque[3]) {
  (void)torque;
  stylus* s = user;
  for (int k = 0; k < 3; ++k) s->sent[k] = force[k];
  s->writes++;
  return MICA_OK;
}

static void test_callback_device(void** state) {
  (void)state;
  scene s = make_scene(2e4);
  stylus st = {0.02, 0, {0, 0, 0}, 0};
  mica_device_callbacks cb = {sizeof cb, 0, &st, NULL, NULL, NULL, read_stylus, write_stylus};
  mica_device_def dd = mica_device_def_default();
  dd.backend = MICA_DEVICE_CALLBACKS;
  dd.callbacks = &cb;
  dd.tool = s.tool;
  dd.scale = 2.0; /* 1 cm of stylus is 2 cm in the scene */
  dd.offset[1] = 0.01;
  mica_device_id device;
  assert_int_equal(mica_device_create(s.world, &dd, &device), MICA_OK);
  /* Stylus at y = 0.002 m: scene y = 2 * 0.002 + 0.01 = 0.014, the sphere's bottom 1 mm under the surface. */
  st.y = 0.002;
  mica_device_state ds = {sizeof ds};
  double f[3];
  double rendered = 0;
  for (int k = 0; k < 30; ++k) {
    assert_true(mica_device_poll(s.world, device, &ds, f) >= 0);
    assert_true(mica_step(s.world, 0.01) >= 0);
    st.y -= 0.0002; /* pressing on */
    rendered = f[1];
  }
  assert_true(mica_device_poll(s.world, device, &ds, f) >= 0);
  double tool_force[3];
  assert_int_equal(mica_tool_get_force(s.world, s.tool, tool_force, NULL, NULL), MICA_OK);
  print_message("stylus y %.4f m; tool force %.4f N; rendered (device frame, scale 2) %.4f N\n", st.y, tool_force[1],
                f[1]);
  assert_true(st.writes == 31 && rendered > 0 && f[1] > 0); /* pushed back up */
  /* The device fails: zero force, a status, and the simulation steps on. */
  st.fail = 1;
  assert_int_equal(mica_device_poll(s.world, device, &ds, f), MICA_ERR_DEVICE);
  assert_true(st.sent[0] == 0 && st.sent[1] == 0 && st.sent[2] == 0);
  assert_true(mica_step(s.world, 0.01) >= 0);
  mica_device_stats stats = {sizeof stats};
  assert_int_equal(mica_device_get_stats(s.world, device, &stats), MICA_OK);
  assert_int_equal(stats.failures, 1);
  assert_int_equal(stats.last_status, MICA_ERR_DEVICE);
  /* Bad ids on the servo path: a status, nothing else. */
  assert_int_equal(mica_device_poll(s.world, 12345, &ds, f), MICA_ERR_STALE_ID);
  assert_int_equal(mica_device_poll(NULL, device, &ds, f), MICA_ERR_NULL_ARGUMENT);
  /* A driven tool cannot be destroyed under its device. */
  assert_int_equal(mica_tool_destroy(s.world, s.tool), MICA_ERR_WRONG_STATE);
  assert_int_equal(mica_device_destroy(s.world, device), MICA_OK);
  assert_int_equal(mica_tool_destroy(s.world, s.tool), MICA_OK);
  mica_world_destroy(s.world);
}

/* A virtual hand driving a grasp (mica_device_def.lpc, since 0.6): it grasps the top face at
 * (-0.01, 0, -0.01) and aims 1 cm above it. In lockstep (16 polls per 16 ms step) until hand and
 * block are at rest; then, with the hand still:
 * - the device renders what the grasped tissue puts on the hand, the grasp's reaction (the
 *   filter has settled: within 1%), pointing down (the tissue pulls the lifting hand back);
 * - the reaction is the force on the holder: with no gravity the grasp and the fixed base hold
 *   the block between them, their reactions cancel (to 1%, the block's leftover motion);
 * - the hand rests where its arm's pull balances the rendered force: k (target - x) + F = 0;
 * - the grasp cannot be removed under its device, and can once the device is gone. */
static const double kGraspAt[3] = {-0.01, 0, -0.01};
static void lift(double t, double p[3], void* user) {
  (void)user;
  p[0] = kGraspAt[0];
  p[1] = kGraspAt[1] + 0.01 * (t < 0.5 ? t / 0.5 : 1);
  p[2] = kGraspAt[2];
}

static void test_grasp_renders_its_reaction(void** state) {
  (void)state;
  scene s = make_scene(5e3);
  mica_lpc_id grasp;
  assert_int_equal(mica_lpc_grab(s.world, s.body, kGraspAt, 0.021, MICA_NULL_ID, &grasp), MICA_OK);
  mica_device_def dd = mica_device_def_default();
  dd.backend = MICA_DEVICE_SIMULATED;
  dd.simulated_kind = MICA_SIMULATED_HAND;
  dd.trajectory = lift;
  dd.lpc = grasp;
  /* Lockstep polls come microseconds apart in wall time, which the rate limit measures: lifted
   * here so the force follows the steps (the limit itself is tests/haptics' business). */
  dd.max_force_rate = 1e7;
  mica_device_id device;
  assert_int_equal(mica_device_create(s.world, &dd, &device), MICA_OK);
  mica_device_info info = {sizeof info};
  assert_int_equal(mica_device_get_info(s.world, device, &info), MICA_OK);
  double f[3] = {0, 0, 0}, reaction[3] = {0, 0, 0}, base[3] = {0, 0, 0};
  mica_device_state hand = {sizeof hand};
  for (int k = 0; k < 250; ++k) { /* 4 s */
    for (int p = 0; p < 16; ++p) assert_true(mica_device_poll(s.world, device, &hand, f) >= 0);
    assert_true(mica_step(s.world, 0.016) >= 0);
    assert_int_equal(mica_lpc_get_reaction(s.world, grasp, reaction), MICA_OK);
    if (getenv("MICA_TEST_TRACE"))
      print_message("step %d hand y %.5f rendered y %.4f grasp reaction y %.4f\n", k, hand.position[1], f[1],
                    reaction[1]);
  }
  /* Still: the filter's window (20 polls) sees one model, the hand has stopped. */
  for (int p = 0; p < 40; ++p) assert_true(mica_device_poll(s.world, device, &hand, f) >= 0);
  assert_int_equal(mica_lpc_get_reaction(s.world, s.base, base), MICA_OK);
  const double r = sqrt(reaction[0] * reaction[0] + reaction[1] * reaction[1] + reaction[2] * reaction[2]);
  print_message("hand at y %.5f m (speed %.2e m/s); rendered (%.4f, %.4f, %.4f) N; grasp reaction (%.4f, %.4f, %.4f) "
                "N; base reaction y %.4f N\n",
                hand.position[1], hand.velocity[1], f[0], f[1], f[2], reaction[0], reaction[1], reaction[2], base[1]);
  assert_true(reaction[1] < -0.1 && r < info.max_force); /* pulled down, below the clamp: rendered whole */
  for (int k = 0; k < 3; ++k) assert_true(fabs(f[k] - reaction[k]) < 0.01 * r);
  for (int k = 0; k < 3; ++k) assert_true(fabs(base[k] + reaction[k]) < 0.01 * r);
  double target[3];
  lift(1.0, target, NULL);
  for (int k = 0; k < 3; ++k) assert_true(fabs(dd.hand_stiffness * (target[k] - hand.position[k]) + f[k]) < 0.01 * r);
  assert_int_equal(mica_lpc_remove(s.world, grasp), MICA_ERR_WRONG_STATE);
  assert_int_equal(mica_device_destroy(s.world, device), MICA_OK);
  assert_int_equal(mica_lpc_remove(s.world, grasp), MICA_OK);
  mica_world_destroy(s.world);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_callback_device),
      cmocka_unit_test(test_closed_loop_soft),
      cmocka_unit_test(test_closed_loop_stiff),
      cmocka_unit_test(test_servo_thread_beside_simulation),
      cmocka_unit_test(test_grasp_renders_its_reaction),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
