/* SPDX-License-Identifier: Apache-2.0 */
/* Recording a session and replaying it, through the C API:
 *  - a 5 s haptic session (a simulated hand on its own 1 kHz servo thread driving a sphere into a
 *    soft block, a grab dragged by the host, node forces, the grab released) replays into a fresh
 *    world with every step's positions and tool force bit for bit;
 *  - a session with a saved state restored halfway (the device polled by the test) replays alike,
 *    and so does one where the device drives a grasp;
 *  - a changed fingerprint is reported as MICA_ERR_DIVERGED at its step; a recording cut short
 *    (without the entry mica_world_record_stop ends it with) replays its whole steps, then
 *    MICA_ERR_TRUNCATED says after how many; one of 0.6 (no end entry) ends with its file;
 *  - bad files and calls get their statuses. */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <mica/mica.h>
#include <mica/mica_device.h>

#include "box_scene.h"
#include "wall_clock.h"

#include "capi_ok.h"

static const double kDt = 0.01;

/* The hand's target: down 12 mm into the block over 2 s, then sideways (`user`: NULL, or a
 * factor on the time to press faster). */
static void press(double t, double p[3], void* user) {
  if (user) t *= *(const double*)user;
  const double depth = t < 2.0 ? 0.012 * t / 2.0 : 0.012;
  p[0] = t < 2.0 ? 0.0 : 0.01 * (t - 2.0) / 3.0;
  p[1] = 0.021 - depth; /* the sphere (radius 2 cm) touches the top face y = 0 at p_y = 0.02 */
  p[2] = 0.0;
}

/* What each step of the original left, to compare the replay with. */
typedef struct {
  int32_t steps, nodes;
  double* x;     /* steps x nodes x 3 */
  double* force; /* steps x 3 */
} trace;

static void trace_step(mica_world* w, const box_scene* s, trace* t) {
  int32_t n = 0;
  OK(w, mica_body_get_positions(w, s->body, t->x + (size_t)t->steps * (size_t)t->nodes * 3, t->nodes, &n));
  OK(w, mica_tool_get_force(w, s->tool, t->force + (size_t)t->steps * 3, NULL, NULL));
  t->steps++;
}

static mica_world* new_recorded_world(const char* path, box_scene* s) {
  mica_world_def wd = mica_world_def_default();
  mica_world* w = NULL;
  OK(NULL, mica_world_create(&wd, &w));
  OK(w, mica_world_record_start(w, path));
  box_scene_def def = box_scene_block_def();
  def.cells[0] = def.cells[1] = def.cells[2] = 5;
  def.body.youngs_modulus = 8e3;
  def.body.poisson_ratio = 0.4;
  def.body.rayleigh_alpha = 2;
  OK(w, box_scene_create(w, &def, s));
  return w;
}

/* Replays `path` and checks every step against `t`; returns the steps replayed. */
static int32_t replay_and_compare(const char* path, const box_scene* s, const trace* t) {
  mica_replay* r = NULL;
  OK(NULL, mica_replay_open(path, &r));
  mica_world* w = mica_replay_world(r);
  double* x = malloc((size_t)t->nodes * 3 * sizeof(double));
  int32_t steps = 0, stepped = 1, n = 0;
  while (stepped) {
    OK(w, mica_replay_step(r, &stepped));
    if (!stepped) break;
    assert_true(steps < t->steps);
    double f[3];
    OK(w, mica_body_get_positions(w, s->body, x, t->nodes, &n));
    OK(w, mica_tool_get_force(w, s->tool, f, NULL, NULL));
    if (memcmp(x, t->x + (size_t)steps * (size_t)t->nodes * 3, (size_t)t->nodes * 3 * sizeof(double)) != 0 ||
        memcmp(f, t->force + (size_t)steps * 3, sizeof f) != 0) {
      print_error("step %d: the replay differs from the original\n", steps + 1);
      fail();
    }
    ++steps;
  }
  free(x);
  mica_replay_close(r);
  return steps;
}

static void test_haptic_session_replays_bit_for_bit(void** state) {
  (void)state;
  const char* path = "test_recording_haptic.micarec";
  box_scene s;
  mica_world* w = new_recorded_world(path, &s);
  trace t = {0, s.nodes, NULL, NULL};
  const int32_t steps = 500; /* 5 s at 100 Hz, in real time */
  t.x = malloc((size_t)steps * (size_t)s.nodes * 3 * sizeof(double));
  t.force = malloc((size_t)steps * 3 * sizeof(double));

  mica_device_def dd = mica_device_def_default();
  dd.backend = MICA_DEVICE_SIMULATED;
  dd.simulated_kind = MICA_SIMULATED_HAND;
  dd.trajectory = press;
  dd.tool = s.tool;
  mica_device_id device;
  OK(w, mica_device_create(w, &dd, &device));
  OK(w, mica_device_start(w, device));
  mica_lpc_id grab = MICA_NULL_ID;
  double peak = 0, first_pose[3] = {0}, last_pose[3] = {0};
  const double start = now_s();
  for (int32_t k = 0; k < steps; ++k) {
    if (k == 100) { /* the host grabs the top corner and drags it up */
      const double corner[3] = {-0.04, 0.0, -0.04};
      OK(w, mica_lpc_grab(w, s.body, corner, 0.015, MICA_NULL_ID, &grab));
    }
    if (grab != MICA_NULL_ID) {
      const double p[3] = {-0.04, 0.005 * (k - 100) / 250.0, -0.04}, q[4] = {1, 0, 0, 0};
      OK(w, mica_lpc_set_handle_pose(w, grab, p, q));
    }
    if (k == 200) {
      const int32_t nodes[2] = {0, 1};
      const double forces[6] = {0, 0, 0.01, 0, 0, -0.01};
      OK(w, mica_body_set_node_forces(w, s.body, nodes, forces, 2));
    }
    if (k == 350) {
      OK(w, mica_lpc_remove(w, grab));
      grab = MICA_NULL_ID;
    }
    OK(w, mica_step(w, kDt));
    trace_step(w, &s, &t);
    const double* f = t.force + (size_t)k * 3;
    peak = fmax(peak, sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]));
    OK(w, mica_tool_get_pose(w, s.tool, k == 0 ? first_pose : last_pose, NULL));
    sleep_until(start + (k + 1) * kDt);
  }
  OK(w, mica_device_stop(w, device));
  OK(w, mica_world_record_stop(w));
  mica_world_destroy(w);
  /* The session touched the tissue and the hand moved the tool (the recording has something to keep). */
  print_message("session: %.2f s, peak tool force %.3f N, tool moved %.1f mm\n", now_s() - start, peak,
                1e3 * fabs(last_pose[1] - first_pose[1]));
  assert_true(peak > 0.05);
  assert_true(fabs(last_pose[1] - first_pose[1]) > 1e-3);

  assert_int_equal(replay_and_compare(path, &s, &t), steps);
  free(t.x);
  free(t.force);
  remove(path);
}

static void test_restored_state_replays_bit_for_bit(void** state) {
  (void)state;
  const char* path = "test_recording_restore.micarec";
  box_scene s;
  mica_world* w = new_recorded_world(path, &s);
  const int32_t steps = 60;
  trace t = {0, s.nodes, malloc((size_t)steps * (size_t)s.nodes * 3 * sizeof(double)),
             malloc((size_t)steps * 3 * sizeof(double))};
  mica_device_def dd = mica_device_def_default();
  dd.backend = MICA_DEVICE_SIMULATED;
  dd.trajectory = press;
  double speed = 5;
  dd.trajectory_user = &speed;
  dd.tool = s.tool;
  mica_device_id device;
  OK(w, mica_device_create(w, &dd, &device));
  void* saved = NULL;
  double peak = 0;
  size_t bytes = 0;
  for (int32_t k = 0; k < steps; ++k) {
    for (int i = 0; i < 10; ++i) mica_device_poll(w, device, NULL, NULL); /* the servo, by hand */
    if (k == 20) {
      OK(w, mica_world_state_size(w, &bytes));
      saved = malloc(bytes);
      OK(w, mica_world_save_state(w, saved, bytes));
    }
    if (k == 40) OK(w, mica_world_restore_state(w, saved, bytes));
    OK(w, mica_step(w, kDt));
    trace_step(w, &s, &t);
    peak = fmax(peak, fabs(t.force[(size_t)k * 3 + 1]));
  }
  assert_true(peak > 0.05); /* the device pressed the tool into the block */
  OK(w, mica_world_record_stop(w));
  mica_world_destroy(w);
  free(saved);
  assert_int_equal(replay_and_compare(path, &s, &t), steps);
  free(t.x);
  free(t.force);
  remove(path);
}

/* The hand's target for a grasp: up 5 mm over the first 0.3 s, from the top face. */
static void lift(double t, double p[3], void* user) {
  (void)user;
  p[0] = -0.04;
  p[1] = 0.005 * (t < 0.3 ? t / 0.3 : 1.0);
  p[2] = -0.04;
}

static void test_grasp_device_session_replays_bit_for_bit(void** state) {
  (void)state;
  const char* path = "test_recording_grasp.micarec";
  box_scene s;
  mica_world* w = new_recorded_world(path, &s);
  const int32_t steps = 40;
  trace t = {0, s.nodes, malloc((size_t)steps * (size_t)s.nodes * 3 * sizeof(double)),
             malloc((size_t)steps * 3 * sizeof(double))};
  const double corner[3] = {-0.04, 0.0, -0.04};
  mica_lpc_id grasp;
  OK(w, mica_lpc_grab(w, s.body, corner, 0.015, MICA_NULL_ID, &grasp));
  mica_device_def dd = mica_device_def_default();
  dd.backend = MICA_DEVICE_SIMULATED;
  dd.trajectory = lift;
  dd.lpc = grasp;
  mica_device_id device;
  OK(w, mica_device_create(w, &dd, &device));
  double lifted = 0;
  for (int32_t k = 0; k < steps; ++k) {
    for (int i = 0; i < 10; ++i) mica_device_poll(w, device, NULL, NULL); /* the servo, by hand */
    OK(w, mica_step(w, kDt));
    trace_step(w, &s, &t);
    double reaction[3];
    OK(w, mica_lpc_get_reaction(w, grasp, reaction));
    lifted = fmax(lifted, fabs(reaction[1]));
  }
  assert_true(lifted > 0.01); /* the device's grasp pulled on the tissue */
  OK(w, mica_world_record_stop(w));
  mica_world_destroy(w);
  assert_int_equal(replay_and_compare(path, &s, &t), steps);
  free(t.x);
  free(t.force);
  remove(path);
}

static long file_size(const char* path) {
  FILE* f = fopen(path, "rb");
  assert_non_null(f);
  fseek(f, 0, SEEK_END);
  const long size = ftell(f);
  fclose(f);
  return size;
}

/* Records 30 steps of the block pressed by the host. */
static void record_small(const char* path) {
  box_scene s;
  mica_world* w = new_recorded_world(path, &s);
  for (int32_t k = 0; k < 30; ++k) {
    const double p[3] = {0, 0.021 - 0.0003 * k, 0}, q[4] = {1, 0, 0, 0};
    OK(w, mica_tool_set_pose(w, s.tool, p, q));
    OK(w, mica_step(w, kDt));
  }
  OK(w, mica_world_record_stop(w));
  mica_world_destroy(w);
}

/* Replays `path` to its end or its first error; returns the steps replayed (the failing one
 * included), the last status in `*last` and, when `message` is not NULL, the replay's message. */
static int32_t replay_count(const char* path, mica_status* last, char* message, size_t capacity) {
  mica_replay* r = NULL;
  OK(NULL, mica_replay_open(path, &r));
  int32_t steps = 0, stepped = 1;
  *last = MICA_OK;
  while (stepped && *last >= 0) {
    *last = mica_replay_step(r, &stepped);
    steps += stepped;
  }
  if (message) snprintf(message, capacity, "%s", mica_world_last_error(mica_replay_world(r)));
  mica_replay_close(r);
  return steps;
}

/* The entry mica_world_record_stop ends a recording with: a 16-byte entry header and the step count. */
static const long kEndEntryBytes = 24;

/* Copies the first `bytes` of `from` into `to` (head -c). */
static void copy_head(const char* from, const char* to, long bytes) {
  FILE* in = fopen(from, "rb");
  FILE* out = fopen(to, "wb");
  assert_non_null(in);
  assert_non_null(out);
  for (long k = 0; k < bytes; ++k) {
    const int c = fgetc(in);
    assert_true(c != EOF);
    fputc(c, out);
  }
  fclose(in);
  fclose(out);
}

/* Replays `path`, which must replay `steps` steps and then be reported cut short after them. */
static void expect_cut_short(const char* path, int32_t steps) {
  mica_status status = MICA_OK;
  char message[512], expected[64];
  const int32_t replayed = replay_count(path, &status, message, sizeof message);
  snprintf(expected, sizeof expected, "cut short after %d steps", steps);
  if (status != MICA_ERR_TRUNCATED || replayed != steps || !strstr(message, expected)) {
    print_error("%s: %d steps replayed, then %s (%s); expected %d steps, then MICA_ERR_TRUNCATED (%s)\n", path,
                replayed, mica_status_string(status), message, steps, expected);
    fail();
  }
}

static void test_divergence_and_truncation_are_reported(void** state) {
  (void)state;
  const char* path = "test_recording_small.micarec";
  record_small(path);
  mica_status last = MICA_OK;
  assert_int_equal(replay_count(path, &last, NULL, 0), 30);
  assert_int_equal(last, MICA_OK);

  /* The 8 bytes before the end entry are the last step's fingerprint: changed, that step diverges. */
  const long size = file_size(path);
  FILE* f = fopen(path, "r+b");
  fseek(f, size - kEndEntryBytes - 1, SEEK_SET);
  const int byte = fgetc(f);
  fseek(f, size - kEndEntryBytes - 1, SEEK_SET);
  fputc(byte ^ 1, f);
  fclose(f);
  char message[512];
  assert_int_equal(replay_count(path, &last, message, sizeof message), 30);
  assert_int_equal(last, MICA_ERR_DIVERGED);
  assert_non_null(strstr(message, "step 30"));
  remove(path);
}

/* A recording that ends before mica_world_record_stop's end entry (a host that died, a file cut
 * with head -c) replays its whole steps, then says it was cut short and after how many steps. */
static void test_cut_recording_is_reported(void** state) {
  (void)state;
  const char* path = "test_recording_whole.micarec";
  const char* cut = "test_recording_cut.micarec";
  record_small(path);
  const long size = file_size(path);
  copy_head(path, cut, size - 4); /* inside the end entry */
  expect_cut_short(cut, 30);
  copy_head(path, cut, size - kEndEntryBytes); /* right after the last step */
  expect_cut_short(cut, 30);
  copy_head(path, cut, size - kEndEntryBytes - 4); /* inside the last step */
  expect_cut_short(cut, 29);
  copy_head(path, cut, 1200); /* inside the body's mesh, before any step */
  expect_cut_short(cut, 0);

  /* 600 bytes fewer: a few steps fewer, as many as are whole in what is left. */
  copy_head(path, cut, size - kEndEntryBytes - 600);
  mica_status last = MICA_OK;
  const int32_t steps = replay_count(cut, &last, NULL, 0);
  assert_true(steps >= 20 && steps < 30);
  expect_cut_short(cut, steps);

  /* Bytes after the end entry are not part of a recording. */
  copy_head(path, cut, size);
  FILE* f = fopen(cut, "ab");
  fputs("junk", f);
  fclose(f);
  assert_int_equal(replay_count(cut, &last, NULL, 0), 30);
  assert_int_equal(last, MICA_ERR_PARSE);

  /* A recording of libmica 0.6 (format 1) has no end entry: its replay ends where the file ends,
   * cut short or not, as 0.6 replayed it. Made from today's format, which differs only by the end
   * entry. */
  copy_head(path, cut, size - kEndEntryBytes);
  f = fopen(cut, "r+b");
  const uint32_t version = 1;
  fseek(f, 8, SEEK_SET); /* after the magic "MICAREC1" */
  fwrite(&version, sizeof version, 1, f);
  fclose(f);
  assert_int_equal(replay_count(cut, &last, NULL, 0), 30);
  assert_int_equal(last, MICA_OK);
  assert_int_equal(truncate(cut, size - kEndEntryBytes - 4), 0); /* cut inside the last step */
  assert_int_equal(replay_count(cut, &last, NULL, 0), 29);
  assert_int_equal(last, MICA_OK);

  /* Destroying the world ends its recording as mica_world_record_stop does. */
  box_scene s;
  mica_world* w = new_recorded_world(path, &s);
  for (int32_t k = 0; k < 3; ++k) OK(w, mica_step(w, kDt));
  mica_world_destroy(w);
  assert_int_equal(replay_count(path, &last, NULL, 0), 3);
  assert_int_equal(last, MICA_OK);
  remove(path);
  remove(cut);
}

static void test_bad_calls_and_files(void** state) {
  (void)state;
  mica_world_def wd = mica_world_def_default();
  mica_world* w = NULL;
  OK(NULL, mica_world_create(&wd, &w));
  assert_int_equal(mica_world_record_stop(w), MICA_ERR_WRONG_STATE);
  assert_int_equal(mica_world_record_start(w, "/nonexistent-dir/x.micarec"), MICA_ERR_IO);
  assert_non_null(strstr(mica_world_last_error(w), "/nonexistent-dir/x.micarec"));
  assert_int_equal(mica_world_record_start(w, NULL), MICA_ERR_NULL_ARGUMENT);
  assert_int_equal(mica_world_record_start(NULL, "x"), MICA_ERR_NULL_ARGUMENT);
  box_scene s;
  box_scene_def def = box_scene_block_def();
  def.cells[0] = def.cells[1] = def.cells[2] = 2;
  OK(w, box_scene_create(w, &def, &s));
  assert_int_equal(mica_world_record_start(w, "test_recording_late.micarec"), MICA_ERR_WRONG_STATE);
  assert_non_null(strstr(mica_world_last_error(w), "new world"));

  /* mica_world_get_ids lists what the scene made, by kind, in creation order. */
  uint64_t ids[4];
  int32_t count = -1;
  OK(w, mica_world_get_ids(w, MICA_OBJECT_BODY, ids, 4, &count));
  assert_int_equal(count, 1);
  assert_true(ids[0] == s.body);
  OK(w, mica_world_get_ids(w, MICA_OBJECT_LPC, ids, 4, &count));
  assert_int_equal(count, 1);
  assert_true(ids[0] == s.base);
  OK(w, mica_world_get_ids(w, MICA_OBJECT_TOOL, NULL, 0, &count));
  assert_int_equal(count, 1);
  OK(w, mica_world_get_ids(w, MICA_OBJECT_DEVICE, ids, 4, &count));
  assert_int_equal(count, 0);
  assert_int_equal(mica_world_get_ids(w, MICA_OBJECT_TOOL, ids, 0, &count), MICA_ERR_BUFFER_TOO_SMALL);
  assert_int_equal(count, 1);
  assert_int_equal(mica_world_get_ids(w, 0, ids, 4, &count), MICA_ERR_INVALID_ARGUMENT);
  assert_non_null(strstr(mica_world_last_error(w), "MICA_OBJECT_"));
  assert_int_equal(mica_world_get_ids(w, MICA_OBJECT_BODY, ids, -1, &count), MICA_ERR_INVALID_ARGUMENT);
  assert_int_equal(mica_world_get_ids(w, MICA_OBJECT_BODY, NULL, 0, NULL), MICA_ERR_NULL_ARGUMENT);
  assert_int_equal(mica_world_get_ids(NULL, MICA_OBJECT_BODY, ids, 4, &count), MICA_ERR_NULL_ARGUMENT);
  mica_world_destroy(w);

  mica_replay* r = (mica_replay*)&r;
  assert_int_equal(mica_replay_open("/nonexistent-dir/x.micarec", &r), MICA_ERR_IO);
  assert_null(r);
  const char* junk = "test_recording_junk.micarec";
  FILE* f = fopen(junk, "wb");
  fputs("this is not a recording at all, just some text", f);
  fclose(f);
  assert_int_equal(mica_replay_open(junk, &r), MICA_ERR_PARSE);
  assert_non_null(strstr(mica_world_last_error(NULL), "not a libmica recording"));
  remove(junk);
  assert_int_equal(mica_replay_open(NULL, &r), MICA_ERR_NULL_ARGUMENT);
  int32_t stepped = 7;
  assert_int_equal(mica_replay_step(NULL, &stepped), MICA_ERR_NULL_ARGUMENT);
  assert_int_equal(stepped, 0);
  assert_null(mica_replay_world(NULL));
  mica_replay_close(NULL);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_haptic_session_replays_bit_for_bit),
      cmocka_unit_test(test_restored_state_replays_bit_for_bit),
      cmocka_unit_test(test_grasp_device_session_replays_bit_for_bit),
      cmocka_unit_test(test_divergence_and_truncation_are_reported),
      cmocka_unit_test(test_cut_recording_is_reported),
      cmocka_unit_test(test_bad_calls_and_files),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
