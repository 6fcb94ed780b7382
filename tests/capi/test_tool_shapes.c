/* SPDX-License-Identifier: Apache-2.0 */
/* Every tool shape through the C API presses a soft block the way its geometry says: the hull of
 * a box's eight corners is the box, so they must give the same force; a capsule lying flat
 * presses like a cylinder of its radius; a plane lifted into the block pushes everything up. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>

#include <mica/mica.h>

/* A 0.1 m block fixed at y = 0, no gravity; the tool is lowered into its top face over 10 steps. */
static double last_torque[3];

static double press(mica_tool_def td, double depth, int32_t* contacts) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = 0;
  wd.solver = MICA_SOLVER_MICA;
  wd.mica_sweep = MICA_SWEEP_GAUSS_SEIDEL; /* the paper's sweep */
  wd.tolerance = 1e-10;
  wd.max_iterations = 100000;
  mica_world* w = NULL;
  assert_int_equal(mica_world_create(&wd, &w), MICA_OK);
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = 2e4;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.1, 0.1};
  const int32_t cells[3] = {6, 6, 6};
  mica_body_id body;
  assert_int_equal(mica_body_create_box(w, &bd, lo, hi, cells, 6, &body), MICA_OK);
  int32_t base[64], n = 0;
  const double o[3] = {0, 0, 0}, up[3] = {0, 1, 0};
  assert_int_equal(mica_body_select_nodes_by_plane(w, body, o, up, 1e-9, 1, base, 64, &n), MICA_OK);
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc;
  assert_int_equal(mica_add_lpc(w, body, base, n, &fixed, &lpc), MICA_OK);
  const double start = td.position[1];
  mica_tool_id tool;
  assert_int_equal(mica_tool_create(w, &td, &tool), MICA_OK);
  for (int k = 1; k <= 10; ++k) {
    double p[3] = {td.position[0], start - depth * k / 10.0, td.position[2]};
    assert_int_equal(mica_tool_set_pose(w, tool, p, td.orientation), MICA_OK);
    assert_true(mica_step(w, 0.01) >= 0);
  }
  double f[3];
  assert_int_equal(mica_tool_get_force(w, tool, f, last_torque, contacts), MICA_OK);
  assert_true(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2]));
  mica_world_destroy(w);
  return f[1];
}

static void test_hull_of_box_corners_presses_like_the_box(void** state) {
  (void)state;
  const double a = 0.02; /* half size */
  mica_tool_def box = mica_tool_def_default();
  box.shape = MICA_TOOL_BOX;
  box.half_extents[0] = box.half_extents[1] = box.half_extents[2] = a;
  box.position[0] = 0.05;
  box.position[1] = 0.1 + a;
  box.position[2] = 0.05;
  mica_tool_def hull = box;
  hull.shape = MICA_TOOL_HULL;
  double corners[24];
  for (int c = 0; c < 8; ++c) {
    corners[3 * c] = (c & 1) ? a : -a;
    corners[3 * c + 1] = (c & 2) ? a : -a;
    corners[3 * c + 2] = (c & 4) ? a : -a;
  }
  hull.hull_points = corners;
  hull.hull_point_count = 8;
  int32_t nb = 0, nh = 0;
  const double fb = press(box, 0.008, &nb), fh = press(hull, 0.008, &nh);
  print_message("box %.6f N (%d contacts), hull %.6f N (%d contacts)\n", fb, nb, fh, nh);
  assert_true(fb > 0.1);
  /* Gaps and normals are exact for both; for face-on-face contact the contact point is any
   * point of the overlap (libccd's MPR), which moves the triangle rows' weights a little. */
  assert_true(fabs(fb - fh) <= 1e-4 * fb);
  assert_int_equal(nb, nh);
}

static void test_capsule_and_plane_push_up(void** state) {
  (void)state;
  mica_tool_def capsule = mica_tool_def_default();
  capsule.shape = MICA_TOOL_CAPSULE;
  capsule.radius = 0.01;
  capsule.half_length = 0.03;
  /* lying along x: turn local z onto x, 90 degrees about y */
  capsule.orientation[0] = cos(M_PI / 4);
  capsule.orientation[2] = sin(M_PI / 4);
  capsule.position[0] = 0.05;
  capsule.position[1] = 0.11;
  capsule.position[2] = 0.05;
  int32_t nc = 0;
  const double fc = press(capsule, 0.006, &nc);
  mica_tool_def plane = mica_tool_def_default();
  plane.shape = MICA_TOOL_PLANE;
  plane.normal[1] = -1; /* a ceiling: the block stays below it */
  plane.normal[2] = 0;
  plane.position[1] = 0.1;
  int32_t np = 0;
  const double fp = press(plane, 0.002, &np);
  print_message("capsule %.4f N (%d contacts), plane %.4f N (%d contacts)\n", fc, nc, fp, np);
  assert_true(fc > 0.05 && nc >= 3);
  /* A ceiling lowered 2 mm onto the whole top face: a column compressed by 2%, E A strain = 2e4 * 0.01 * 0.02 = 4 N
   * (more with the Poisson ratio's confinement at the fixed base), pushing the tool up. */
  assert_true(fp > 2.0 && fp < 12.0);
  assert_int_equal(np, 49);
}

/* Torque about the tool origin: none for a frictionless sphere (every contact normal passes
 * through its centre); a box pressing with only its -x half on the block (centred on the edge
 * x = 0.1) is pushed up left of its centre, so it turns clockwise about z (negative). */
static void test_torque(void** state) {
  (void)state;
  mica_tool_def sphere = mica_tool_def_default();
  sphere.radius = 0.03;
  sphere.position[0] = 0.04;
  sphere.position[1] = 0.13;
  sphere.position[2] = 0.05;
  int32_t n = 0;
  const double fs = press(sphere, 0.01, &n);
  const double ts = sqrt(last_torque[0] * last_torque[0] + last_torque[1] * last_torque[1] + last_torque[2] * last_torque[2]);
  print_message("sphere: force %.4f N, |torque| %.3g N m\n", fs, ts);
  assert_true(fs > 0.1 && ts <= 1e-9 * fs * 0.03);
  mica_tool_def box = mica_tool_def_default();
  box.shape = MICA_TOOL_BOX;
  box.half_extents[0] = box.half_extents[1] = box.half_extents[2] = 0.02;
  box.position[0] = 0.1;
  box.position[1] = 0.12;
  box.position[2] = 0.05;
  const double fb = press(box, 0.006, &n);
  print_message("box on the edge: force %.4f N, torque z %.4g N m\n", fb, last_torque[2]);
  assert_true(fb > 0.1);
  assert_true(last_torque[2] < -0.002 * fb); /* lever of at least 2 mm */
  assert_true(last_torque[2] > -0.02 * fb);  /* and at most the half width */
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_hull_of_box_corners_presses_like_the_box),
      cmocka_unit_test(test_capsule_and_plane_push_up),
      cmocka_unit_test(test_torque),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
