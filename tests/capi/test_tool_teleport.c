/* SPDX-License-Identifier: Apache-2.0 */
/* A tool's first pose: mica_tool_set_pose sweeps from the last pose (a tool created inside the
 * cube and set above it drags the tissue down on its way), mica_tool_teleport does not (the
 * sphere above the cube touches nothing); creating a tool inside a body logs a warning; a
 * teleport is recorded and replays bit for bit. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <cmocka.h>

#include <mica/mica.h>

#include "box_scene.h"
#include "capi_ok.h"
#include "log_capture.h"


/* The cube [0, 0.1]^3 fixed at its base, no gravity, and a 1 cm sphere created at `start`. */
static mica_world* cube_and_sphere(const double start[3], log_capture* log, box_scene* s) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = 0;
  wd.log = capture_log;
  wd.log_user = log;
  mica_world* w = NULL;
  OK(NULL, mica_world_create(&wd, &w));
  box_scene_def def = box_scene_def_default();
  def.cells[0] = def.cells[1] = def.cells[2] = 4;
  def.tool_radius = 0.01;
  for (int k = 0; k < 3; ++k) def.tool_position[k] = start[k];
  OK(w, box_scene_create(w, &def, s));
  return w;
}

static double body_speed(mica_world* w, mica_body_id body) {
  static double v[3 * 4096];
  int32_t n = 0;
  OK(w, mica_body_get_velocities(w, body, v, 4096, &n));
  double top = 0;
  for (int32_t i = 0; i < 3 * n; ++i) top = fabs(v[i]) > top ? fabs(v[i]) : top;
  return top;
}

static const double kInside[3] = {0.05, 0.05, 0.05};
static const double kAbove[3] = {0.05, 0.1 + 0.025, 0.05}; /* 1.5 cm clear of the top face */
static const double kIdentity[4] = {1, 0, 0, 0};

static void test_set_pose_sweeps_and_teleport_does_not(void** state) {
  (void)state;
  for (int teleport = 0; teleport <= 1; ++teleport) {
    log_capture log = {0, ""};
    box_scene s;
    mica_world* w = cube_and_sphere(kInside, &log, &s);
    assert_int_equal(log.warnings, 1);
    assert_non_null(strstr(log.last, "inside"));
    assert_non_null(strstr(log.last, "mica_tool_teleport"));
    if (teleport)
      OK(w, mica_tool_teleport(w, s.tool, kAbove, kIdentity));
    else
      OK(w, mica_tool_set_pose(w, s.tool, kAbove, kIdentity));
    OK(w, mica_step(w, 0.01));
    double f[3];
    int32_t contacts = 0;
    OK(w, mica_tool_get_force(w, s.tool, f, NULL, &contacts));
    print_message("%s: force (%g, %g, %g) N, %d contacts, body speed %g m/s\n", teleport ? "teleport" : "set_pose",
                  f[0], f[1], f[2], contacts, body_speed(w, s.body));
    if (teleport) {
      /* Nothing touched: no force, the body at rest. */
      assert_true(f[0] == 0 && f[1] == 0 && f[2] == 0);
      assert_int_equal(contacts, 0);
      assert_true(body_speed(w, s.body) < 1e-9); /* round-off of the solve at rest */
    } else {
      /* The sweep from inside to above pulled tissue along: the tissue pulls the tool down. */
      assert_true(f[1] < -1);
      assert_true(body_speed(w, s.body) > 0.1);
    }
    mica_world_destroy(w);
  }
}

static void test_a_tool_created_outside_warns_nothing(void** state) {
  (void)state;
  log_capture log = {0, ""};
  box_scene s;
  mica_world* w = cube_and_sphere(kAbove, &log, &s);
  assert_int_equal(log.warnings, 0);
  /* A plane's origin is a point of the plane: never "inside". */
  mica_tool_def plane = mica_tool_def_default();
  plane.shape = MICA_TOOL_PLANE;
  for (int k = 0; k < 3; ++k) plane.position[k] = kInside[k];
  mica_tool_id id;
  OK(w, mica_tool_create(w, &plane, &id));
  assert_int_equal(log.warnings, 0);
  mica_world_destroy(w);
}

static void test_teleport_is_validated_and_replayed(void** state) {
  (void)state;
  log_capture log = {0, ""};
  box_scene s;
  mica_world* w = cube_and_sphere(kAbove, &log, &s);
  const double nan_position[3] = {0, NAN, 0}, zero[4] = {0, 0, 0, 0};
  assert_int_equal(mica_tool_teleport(w, s.tool, nan_position, kIdentity), MICA_ERR_INVALID_ARGUMENT);
  assert_int_equal(mica_tool_teleport(w, s.tool, kAbove, zero), MICA_ERR_INVALID_ARGUMENT);
  assert_int_equal(mica_tool_teleport(w, s.body, kAbove, kIdentity), MICA_ERR_STALE_ID);
  assert_int_equal(mica_tool_teleport(NULL, s.tool, kAbove, kIdentity), MICA_ERR_NULL_ARGUMENT);
  mica_world_destroy(w);

  /* Recorded: pressed in, teleported out and back in, pressed on; the replay matches bit for bit. */
  char path[] = "/tmp/mica_teleport_XXXXXX";
  const int fd = mkstemp(path);
  assert_true(fd >= 0);
  close(fd);
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = 0;
  OK(NULL, mica_world_create(&wd, &w));
  OK(w, mica_world_record_start(w, path));
  box_scene_def def = box_scene_def_default();
  def.cells[0] = def.cells[1] = def.cells[2] = 4;
  def.tool_radius = 0.01;
  for (int k = 0; k < 3; ++k) def.tool_position[k] = kAbove[k];
  OK(w, box_scene_create(w, &def, &s));
  for (int k = 0; k < 12; ++k) {
    const double p[3] = {0.05, 0.1 + 0.01 - 0.001 * k, 0.05};
    if (k == 6)
      OK(w, mica_tool_teleport(w, s.tool, kAbove, kIdentity));
    else if (k == 7)
      OK(w, mica_tool_teleport(w, s.tool, p, kIdentity));
    else
      OK(w, mica_tool_set_pose(w, s.tool, p, kIdentity));
    OK(w, mica_step(w, 0.01));
  }
  OK(w, mica_world_record_stop(w));
  mica_world_destroy(w);
  mica_replay* r = NULL;
  OK(NULL, mica_replay_open(path, &r));
  int32_t steps = 0, stepped = 1;
  while (stepped) {
    OK(NULL, mica_replay_step(r, &stepped)); /* a step that differs from the recording fails here */
    steps += stepped;
  }
  assert_int_equal(steps, 12);
  mica_replay_close(r);
  remove(path);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_set_pose_sweeps_and_teleport_does_not),
      cmocka_unit_test(test_a_tool_created_outside_warns_nothing),
      cmocka_unit_test(test_teleport_is_validated_and_replayed),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
