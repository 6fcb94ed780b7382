/* SPDX-License-Identifier: Apache-2.0 */
/* Direct manipulation through the C API: grab, drag, feel, release. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdlib.h>

#include <mica/mica.h>

typedef struct {
  mica_world* world;
  mica_body_id body;
  int32_t nodes;
} scene;

/* The body's model: co-rotational, or neo-Hookean for the _neo_hookean variants. */
static int32_t g_model = MICA_MODEL_COROTATIONAL;

/* A 0.1 m soft cube fixed at y = 0, no gravity, MICA solver. */
static scene make_scene(void) {
  scene s = {NULL, 0, 0};
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = 0;
  wd.solver = MICA_SOLVER_MICA;
  wd.mica_sweep = MICA_SWEEP_GAUSS_SEIDEL; /* the paper's sweep */
  wd.tolerance = 1e-10;
  wd.max_iterations = 100000;
  assert_int_equal(mica_world_create(&wd, &s.world), MICA_OK);
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = 2e4;
  bd.model = g_model;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.1, 0.1};
  const int32_t cells[3] = {4, 4, 4};
  assert_int_equal(mica_body_create_box(s.world, &bd, lo, hi, cells, 6, &s.body), MICA_OK);
  assert_int_equal(mica_body_get_counts(s.world, s.body, &s.nodes, NULL, NULL), MICA_OK);
  const double point[3] = {0, 0, 0}, normal[3] = {0, 1, 0};
  int32_t count = 0;
  int32_t base[64];
  assert_int_equal(mica_body_select_nodes_by_plane(s.world, s.body, point, normal, 1e-9, 1, base, 64, &count), MICA_OK);
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc;
  assert_int_equal(mica_add_lpc(s.world, s.body, base, count, &fixed, &lpc), MICA_OK);
  return s;
}

static void position_of(const scene* s, int32_t node, double out[3]) {
  const double* x;
  int32_t n;
  assert_int_equal(mica_body_positions_view(s->world, s->body, &x, &n), MICA_OK);
  for (int k = 0; k < 3; ++k) out[k] = x[3 * node + k];
}

/* Grab the top corner region, pull it sideways 1 cm over 10 steps: the held nodes sit exactly
 * on their targets, the hand feels the tissue pulling back, and after release they spring back. */
static void test_grab_drag_release(void** state) {
  (void)state;
  scene s = make_scene();
  const double corner[3] = {0.1, 0.1, 0.1};
  mica_lpc_id grab = 0;
  assert_int_equal(mica_lpc_grab(s.world, s.body, corner, 0.03, MICA_NULL_ID, &grab), MICA_OK);
  int32_t held[64], count = 0;
  assert_int_equal(mica_lpc_get_nodes(s.world, grab, held, 64, &count), MICA_OK);
  assert_true(count >= 4);
  double start[64][3];
  for (int32_t k = 0; k < count; ++k) position_of(&s, held[k], start[k]);
  const double q[4] = {1, 0, 0, 0};
  for (int step = 1; step <= 10; ++step) {
    const double handle[3] = {0.1 + 0.001 * step, 0.1, 0.1};
    assert_int_equal(mica_lpc_set_handle_pose(s.world, grab, handle, q), MICA_OK);
    assert_int_equal(mica_step(s.world, 0.01), MICA_OK);
  }
  for (int32_t k = 0; k < count; ++k) {
    double x[3];
    position_of(&s, held[k], x);
    assert_true(fabs(x[0] - (start[k][0] + 0.01)) < 1e-9);
    assert_true(fabs(x[1] - start[k][1]) < 1e-9 && fabs(x[2] - start[k][2]) < 1e-9);
  }
  double felt[3];
  assert_int_equal(mica_lpc_get_reaction(s.world, grab, felt), MICA_OK);
  assert_true(felt[0] < 0); /* pulled in +x, the hand is pulled back in -x */
  assert_int_equal(mica_lpc_remove(s.world, grab), MICA_OK);
  for (int step = 0; step < 30; ++step) assert_true(mica_step(s.world, 0.01) >= 0);
  double x[3];
  position_of(&s, held[0], x);
  assert_true(x[0] < start[0][0] + 0.01 - 1e-4); /* released: it moved back toward rest */
  mica_world_destroy(s.world);
}

/* The same grasp on a neo-Hookean body (MICA_MODEL_NEO_HOOKEAN). */
static void test_grab_drag_release_neo_hookean(void** state) {
  g_model = MICA_MODEL_NEO_HOOKEAN;
  test_grab_drag_release(state);
  g_model = MICA_MODEL_COROTATIONAL;
}

/* A grab that follows a tool (forceps): moving the tool carries the held nodes; a rotation of
 * the tool turns them about the tool origin. */
static void test_grab_follows_tool(void** state) {
  (void)state;
  scene s = make_scene();
  mica_tool_def td = mica_tool_def_default();
  td.radius = 0.005;
  td.position[0] = 0.05;
  td.position[1] = 0.11;
  td.position[2] = 0.05;
  mica_tool_id tool;
  assert_int_equal(mica_tool_create(s.world, &td, &tool), MICA_OK);
  const double center[3] = {0.05, 0.1, 0.05};
  mica_lpc_id grab;
  assert_int_equal(mica_lpc_grab(s.world, s.body, center, 0.001, tool, &grab), MICA_OK);
  int32_t node, count;
  assert_int_equal(mica_lpc_get_nodes(s.world, grab, &node, 1, &count), MICA_OK);
  assert_int_equal(count, 1);
  /* Lift the tool 5 mm and turn it 90 degrees about y: the node (straight below the tool
   * origin, on the axis) rises with it and stays on the axis. */
  const double lifted[3] = {0.05, 0.115, 0.05};
  const double turn[4] = {cos(M_PI / 4), 0, sin(M_PI / 4), 0};
  assert_int_equal(mica_tool_set_pose(s.world, tool, lifted, turn), MICA_OK);
  assert_int_equal(mica_step(s.world, 0.01), MICA_OK);
  double x[3];
  position_of(&s, node, x);
  assert_true(fabs(x[0] - 0.05) < 1e-9 && fabs(x[1] - 0.105) < 1e-9 && fabs(x[2] - 0.05) < 1e-9);
  mica_world_destroy(s.world);
}

/* Targets per node, then back to a velocity; wrong counts and empty grabs are refused. */
static void test_targets_and_velocity(void** state) {
  (void)state;
  scene s = make_scene();
  const double corner[3] = {0.1, 0.1, 0.1};
  mica_lpc_id grab;
  assert_int_equal(mica_lpc_grab(s.world, s.body, corner, 1e-6, MICA_NULL_ID, &grab), MICA_OK);
  int32_t node, count;
  assert_int_equal(mica_lpc_get_nodes(s.world, grab, &node, 1, &count), MICA_OK);
  const double target[3] = {0.11, 0.1, 0.1};
  assert_int_equal(mica_lpc_set_targets(s.world, grab, target, 1), MICA_OK);
  assert_int_equal(mica_step(s.world, 0.01), MICA_OK);
  double x[3];
  position_of(&s, node, x);
  assert_true(fabs(x[0] - 0.11) < 1e-12);
  const double v[3] = {0, 0.5, 0};
  assert_int_equal(mica_lpc_set_velocity(s.world, grab, v), MICA_OK);
  assert_int_equal(mica_step(s.world, 0.01), MICA_OK);
  double y[3];
  position_of(&s, node, y);
  assert_true(fabs(y[1] - (x[1] + 0.005)) < 1e-12 && fabs(y[0] - x[0]) < 1e-12);
  const double two[6] = {0, 0, 0, 0, 0, 0};
  assert_int_equal(mica_lpc_set_targets(s.world, grab, two, 2), MICA_ERR_INVALID_ARGUMENT);
  const double far[3] = {5, 5, 5};
  mica_lpc_id none = 0;
  assert_int_equal(mica_lpc_grab(s.world, s.body, far, 0.01, MICA_NULL_ID, &none), MICA_ERR_INVALID_ARGUMENT);
  const double q[4] = {1, 0, 0, 0};
  /* set_velocity dropped the handle: moving it is now the wrong call */
  assert_int_equal(mica_lpc_set_handle_pose(s.world, grab, far, q), MICA_ERR_WRONG_STATE);
  mica_world_destroy(s.world);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_grab_drag_release),
      cmocka_unit_test(test_grab_drag_release_neo_hookean),
      cmocka_unit_test(test_grab_follows_tool),
      cmocka_unit_test(test_targets_and_velocity),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
