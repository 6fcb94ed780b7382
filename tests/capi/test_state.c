/* SPDX-License-Identifier: Apache-2.0 */
/* Node state, saved states and the contacts readout through the C API:
 *  - set positions and velocities read back exactly; a body put back at rest stays at rest;
 *  - save, step 50, restore, step 50 again: the same positions and tool forces, bit for bit
 *    (default solver and MICA_SOLVER_DIRECT; also restored into a fresh world built alike); the
 *    same from a state saved before the first step;
 *    a state of another world shape, or a truncated one, is refused and the world is unchanged;
 *  - the contact impulses of a step add up to the tool force (sphere and box, with and without
 *    friction). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mica/mica.h>
#include <mica/mica_device.h>

#include "capi_ok.h"

static const double kDt = 0.01;

typedef struct {
  mica_world* world;
  mica_body_id body;
  mica_tool_id tool;
  mica_lpc_id grab;
  int32_t nodes;
} scene;

/* A 0.1 m cube (3x3x3 cells) fixed at y = 0 under gravity, a 2 cm sphere pressing its top near one
 * side and a grab on the opposite top corner. cells_x changes the world's shape; refactor_interval
 * > 0 refreshes the factored sweep's factor in the background. */
static scene make_scene(int32_t solver, int32_t cells_x, int with_tool, int32_t refactor_interval) {
  scene s;
  memset(&s, 0, sizeof s);
  mica_world_def wd = mica_world_def_default();
  wd.solver = solver;
  wd.refactor_interval = refactor_interval;
  OK(NULL, mica_world_create(&wd, &s.world));
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = 2e4;
  bd.rayleigh_alpha = 0.5;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.1, 0.1};
  const int32_t cells[3] = {cells_x, 3, 3};
  OK(s.world, mica_body_create_box(s.world, &bd, lo, hi, cells, 6, &s.body));
  OK(s.world, mica_body_get_counts(s.world, s.body, &s.nodes, NULL, NULL));
  const double point[3] = {0, 0, 0}, normal[3] = {0, 1, 0};
  int32_t base[256], count = 0;
  OK(s.world, mica_body_select_nodes_by_plane(s.world, s.body, point, normal, 1e-9, 1, base, 256, &count));
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc;
  OK(s.world, mica_add_lpc(s.world, s.body, base, count, &fixed, &lpc));
  if (with_tool) {
    mica_tool_def td = mica_tool_def_default();
    td.radius = 0.02;
    td.position[0] = 0.03;
    td.position[1] = 0.1 + 0.02 + 0.0005;
    td.position[2] = 0.05;
    td.friction = 0.3;
    OK(s.world, mica_tool_create(s.world, &td, &s.tool));
  }
  const double corner[3] = {0.1, 0.1, 0.1};
  OK(s.world, mica_lpc_grab(s.world, s.body, corner, 0.04, MICA_NULL_ID, &s.grab));
  return s;
}

/* The host's input before step i: the tool presses in (to 6 mm) and slides; the hand pulls up
 * and sideways. */
static void drive(const scene* s, int i) {
  const double t = i * kDt;
  const double q[4] = {1, 0, 0, 0};
  const double depth = 0.006 * (t < 0.6 ? t / 0.6 : 1.0);
  const double tool[3] = {0.03 + 0.01 * t, 0.1 + 0.02 - depth, 0.05};
  OK(s->world, mica_tool_set_pose(s->world, s->tool, tool, q));
  const double hand[3] = {0.1 + 0.005 * t, 0.1 + 0.01 * t, 0.1};
  OK(s->world, mica_lpc_set_handle_pose(s->world, s->grab, hand, q));
}

typedef struct {
  double* x;     /* 50 steps of positions */
  double* force; /* 50 steps of tool forces */
  double* reaction;
} record;

static record run(const scene* s, int first, int steps) {
  record r;
  r.x = malloc(sizeof(double) * 3 * (size_t)s->nodes * (size_t)steps);
  r.force = malloc(sizeof(double) * 3 * (size_t)steps);
  r.reaction = malloc(sizeof(double) * 3 * (size_t)steps);
  for (int k = 0; k < steps; ++k) {
    drive(s, first + k);
    OK(s->world, mica_step(s->world, kDt));
    OK(s->world, mica_body_get_positions(s->world, s->body, r.x + 3 * (size_t)s->nodes * (size_t)k, s->nodes, NULL));
    OK(s->world, mica_tool_get_force(s->world, s->tool, r.force + 3 * k, NULL, NULL));
    OK(s->world, mica_lpc_get_reaction(s->world, s->grab, r.reaction + 3 * k));
  }
  return r;
}

static void free_record(record* r) {
  free(r->x);
  free(r->force);
  free(r->reaction);
}

static void* save(const scene* s, size_t* bytes) {
  OK(s->world, mica_world_state_size(s->world, bytes));
  void* buffer = malloc(*bytes);
  assert_non_null(buffer);
  OK(s->world, mica_world_save_state(s->world, buffer, *bytes));
  return buffer;
}

static void assert_same_run(const scene* s, const record* a, const record* b, int steps) {
  assert_memory_equal(a->x, b->x, sizeof(double) * 3 * (size_t)s->nodes * (size_t)steps);
  assert_memory_equal(a->force, b->force, sizeof(double) * 3 * (size_t)steps);
  assert_memory_equal(a->reaction, b->reaction, sizeof(double) * 3 * (size_t)steps);
}

static void check_replay(int32_t solver, int32_t refactor_interval) {
  scene s = make_scene(solver, 3, 1, refactor_interval);
  record before = run(&s, 0, 50);
  size_t bytes = 0;
  void* state = save(&s, &bytes);
  record first = run(&s, 50, 50);
  /* The run is not trivial: the tool is in contact and the tissue moved. */
  assert_true(fabs(first.force[3 * 49 + 1]) > 1e-3);
  OK(s.world, mica_world_restore_state(s.world, state, bytes));
  record again = run(&s, 50, 50);
  assert_same_run(&s, &first, &again, 50);

  /* Into a fresh world built the same way. */
  scene fresh = make_scene(solver, 3, 1, refactor_interval);
  OK(fresh.world, mica_world_restore_state(fresh.world, state, bytes));
  record replay = run(&fresh, 50, 50);
  assert_same_run(&s, &first, &replay, 50);

  mica_world_stats stats;
  stats.struct_size = sizeof stats;
  OK(fresh.world, mica_world_get_stats(fresh.world, &stats));
  assert_int_equal(stats.step_count, 100); /* the step counter is part of the state */

  free(state);
  free_record(&before);
  free_record(&first);
  free_record(&again);
  free_record(&replay);
  mica_world_destroy(s.world);
  mica_world_destroy(fresh.world);
}

static void test_replay_default_solver(void** st) {
  (void)st;
  check_replay(mica_world_def_default().solver, 0);
  /* Saved with a refreshed factor in flight (every 3 steps: step 50 is between two), whose worker
   * also makes the contact nodes' columns. */
  check_replay(mica_world_def_default().solver, 3);
}

static void test_replay_direct_solver(void** st) {
  (void)st;
  check_replay(MICA_SOLVER_DIRECT, 0);
}

/* A state saved before the first step (a checkpoint of the scene as built) restores, and the run
 * from it repeats bit for bit. */
static void test_state_before_first_step(void** st) {
  (void)st;
  scene s = make_scene(MICA_SOLVER_MICA, 3, 1, 0);
  size_t bytes = 0;
  void* state = save(&s, &bytes);
  record first = run(&s, 0, 20);
  OK(s.world, mica_world_restore_state(s.world, state, bytes));
  record again = run(&s, 0, 20);
  assert_same_run(&s, &first, &again, 20);
  free(state);
  free_record(&first);
  free_record(&again);
  mica_world_destroy(s.world);
}

/* A state is refused, with the world unchanged, by a world of another shape and when truncated. */
static void test_restore_refusals(void** st) {
  (void)st;
  scene s = make_scene(MICA_SOLVER_MICA, 3, 1, 0);
  record r = run(&s, 0, 5);
  size_t bytes = 0;
  void* state = save(&s, &bytes);

  const struct {
    const char* name;
    scene target;
    size_t bytes;
    mica_status expected;
    const char* phrase;
  } cases[] = {
      {"more cells", make_scene(MICA_SOLVER_MICA, 4, 1, 0), bytes, MICA_ERR_INVALID_ARGUMENT, "nodes"},
      {"no tool", make_scene(MICA_SOLVER_MICA, 3, 0, 0), bytes, MICA_ERR_INVALID_ARGUMENT, "tool"},
      {"another solver", make_scene(MICA_SOLVER_DIRECT, 3, 1, 0), bytes, MICA_ERR_INVALID_ARGUMENT, "solver"},
      {"truncated by one byte", make_scene(MICA_SOLVER_MICA, 3, 1, 0), bytes - 1, MICA_ERR_PARSE, "truncated"},
      {"only the header's start", make_scene(MICA_SOLVER_MICA, 3, 1, 0), 16, MICA_ERR_PARSE, "truncated"},
  };
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
    const scene* t = &cases[c].target;
    OK(t->world, mica_step(t->world, kDt));
    double* x0 = malloc(sizeof(double) * 3 * (size_t)t->nodes);
    double* x1 = malloc(sizeof(double) * 3 * (size_t)t->nodes);
    OK(t->world, mica_body_get_positions(t->world, t->body, x0, t->nodes, NULL));
    const mica_status got = mica_world_restore_state(t->world, state, cases[c].bytes);
    const char* message = mica_world_last_error(t->world);
    if (got != cases[c].expected || !strstr(message, cases[c].phrase)) {
      print_error("%s: got %s, want %s; message: %s\n", cases[c].name, mica_status_string(got),
                  mica_status_string(cases[c].expected), message);
      fail();
    }
    OK(t->world, mica_body_get_positions(t->world, t->body, x1, t->nodes, NULL));
    assert_memory_equal(x0, x1, sizeof(double) * 3 * (size_t)t->nodes);
    mica_world_stats stats;
    stats.struct_size = sizeof stats;
    OK(t->world, mica_world_get_stats(t->world, &stats));
    assert_int_equal(stats.step_count, 1);
    free(x0);
    free(x1);
    mica_world_destroy(t->world);
  }
  /* A corrupted byte fails the checksum; a buffer too small to save into is refused. */
  unsigned char* bad = malloc(bytes);
  memcpy(bad, state, bytes);
  bad[bytes / 2] ^= 0x40;
  assert_int_equal(mica_world_restore_state(s.world, bad, bytes), MICA_ERR_PARSE);
  assert_non_null(strstr(mica_world_last_error(s.world), "checksum"));
  assert_int_equal(mica_world_save_state(s.world, bad, bytes - 1), MICA_ERR_BUFFER_TOO_SMALL);
  free(bad);
  free(state);
  free_record(&r);
  mica_world_destroy(s.world);
}

/* Positions and velocities set read back exactly. */
static void test_set_get_round_trip(void** st) {
  (void)st;
  scene s = make_scene(MICA_SOLVER_MICA, 3, 1, 0);
  const size_t n = 3 * (size_t)s.nodes;
  double* x = malloc(sizeof(double) * n);
  double* v = malloc(sizeof(double) * n);
  double* back = malloc(sizeof(double) * n);
  OK(s.world, mica_body_get_rest_positions(s.world, s.body, x, s.nodes, NULL));
  for (size_t k = 0; k < n; ++k) {
    x[k] += 1e-3 * sin(0.7 * (double)k);
    v[k] = 0.01 * cos(1.3 * (double)k);
  }
  OK(s.world, mica_body_set_positions(s.world, s.body, x, s.nodes));
  OK(s.world, mica_body_set_velocities(s.world, s.body, v, s.nodes));
  OK(s.world, mica_body_get_positions(s.world, s.body, back, s.nodes, NULL));
  assert_memory_equal(back, x, sizeof(double) * n);
  OK(s.world, mica_body_get_velocities(s.world, s.body, back, s.nodes, NULL));
  assert_memory_equal(back, v, sizeof(double) * n);
  free(x);
  free(v);
  free(back);
  mica_world_destroy(s.world);
}

/* A body bent by a load, then put back at its rest positions with zero velocity and no load, stays
 * still: nothing derived from the bent shape (rotations, warm starts) survives the set. */
static void check_rest_stays_still(int32_t solver) {
  mica_world* w = NULL;
  mica_world_def wd = mica_world_def_default();
  wd.solver = solver;
  wd.gravity[1] = 0;
  OK(NULL, mica_world_create(&wd, &w));
  mica_body_def bd = mica_body_def_default();
  const double lo[3] = {0, 0, 0}, hi[3] = {0.3, 0.05, 0.05};
  const int32_t cells[3] = {6, 1, 1};
  mica_body_id body;
  OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &body));
  int32_t n = 0;
  OK(w, mica_body_get_counts(w, body, &n, NULL, NULL));
  const double point[3] = {0, 0, 0}, normal[3] = {1, 0, 0};
  int32_t root[64], count = 0;
  OK(w, mica_body_select_nodes_by_plane(w, body, point, normal, 1e-9, 1, root, 64, &count));
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc;
  OK(w, mica_add_lpc(w, body, root, count, &fixed, &lpc));
  /* Bend it far (large rotations) with a tip load. */
  const int32_t tip[1] = {n - 1};
  const double load[3] = {0, -0.05, 0};
  OK(w, mica_body_set_node_forces(w, body, tip, load, 1));
  for (int i = 0; i < 30; ++i) OK(w, mica_step(w, kDt));
  const double none[3] = {0, 0, 0};
  OK(w, mica_body_set_node_forces(w, body, tip, none, 1)); /* zero forces remove the load */
  double* rest = malloc(sizeof(double) * 3 * (size_t)n);
  double* x = malloc(sizeof(double) * 3 * (size_t)n);
  double* v = calloc(3 * (size_t)n, sizeof(double));
  OK(w, mica_body_get_positions(w, body, x, n, NULL));
  OK(w, mica_body_get_rest_positions(w, body, rest, n, NULL));
  double bent = 0;
  for (int k = 0; k < 3 * n; ++k) bent = fmax(bent, fabs(x[k] - rest[k]));
  assert_true(bent > 0.01); /* it was bent: more than 1 cm */
  OK(w, mica_body_set_positions(w, body, rest, n));
  OK(w, mica_body_set_velocities(w, body, v, n));
  for (int i = 0; i < 20; ++i) OK(w, mica_step(w, kDt));
  OK(w, mica_body_get_positions(w, body, x, n, NULL));
  OK(w, mica_body_get_velocities(w, body, v, n, NULL));
  double drift = 0, speed = 0;
  for (int k = 0; k < 3 * n; ++k) {
    drift = fmax(drift, fabs(x[k] - rest[k]));
    speed = fmax(speed, fabs(v[k]));
  }
  /* At rest the elastic force is zero up to round-off: nothing moves beyond that. */
  if (!(drift < 1e-9 && speed < 1e-7)) {
    print_error("solver %d: drift %g m, speed %g m/s after 20 steps from rest\n", solver, drift, speed);
    fail();
  }
  free(rest);
  free(x);
  free(v);
  mica_world_destroy(w);
}

static void test_rest_stays_still(void** st) {
  (void)st;
  check_rest_stays_still(mica_world_def_default().solver);
  check_rest_stays_still(MICA_SOLVER_DIRECT);
}

/* Contacts of the last step: per tool, sum of normal * normal_impulse + tangent_impulse +
 * curvature_impulse over dt is minus the tool's force. */
static void check_contact_sum(int32_t shape, double friction, int32_t solver) {
  mica_world* w = NULL;
  mica_world_def wd = mica_world_def_default();
  wd.solver = solver;
  OK(NULL, mica_world_create(&wd, &w));
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = 2e4;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.1, 0.1};
  const int32_t cells[3] = {4, 4, 4};
  mica_body_id body;
  OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &body));
  const double point[3] = {0, 0, 0}, normal[3] = {0, 1, 0};
  int32_t base[64], count = 0;
  OK(w, mica_body_select_nodes_by_plane(w, body, point, normal, 1e-9, 1, base, 64, &count));
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc;
  OK(w, mica_add_lpc(w, body, base, count, &fixed, &lpc));
  mica_tool_def td = mica_tool_def_default();
  td.shape = shape;
  td.radius = 0.02;
  td.half_extents[0] = td.half_extents[1] = td.half_extents[2] = 0.015;
  const double reach = shape == MICA_TOOL_SPHERE ? td.radius : td.half_extents[1];
  td.position[0] = 0.045;
  td.position[1] = 0.1 + reach + 0.0005;
  td.position[2] = 0.052;
  td.friction = friction;
  mica_tool_id tool;
  OK(w, mica_tool_create(w, &td, &tool));
  const double q[4] = {1, 0, 0, 0};
  for (int i = 1; i <= 12; ++i) {
    /* Press 4 mm in, then slide sideways (friction acts). */
    const double p[3] = {0.045 + (i > 8 ? 0.001 * (i - 8) : 0), 0.1 + reach - 0.0005 * (i < 8 ? i : 8), 0.052};
    OK(w, mica_tool_set_pose(w, tool, p, q));
    OK(w, mica_step(w, kDt));
  }
  double force[3];
  int32_t active = 0;
  OK(w, mica_tool_get_force(w, tool, force, NULL, &active));
  assert_true(active > 0);
  int32_t n = 0;
  OK(w, mica_world_get_contacts(w, NULL, 0, &n));
  assert_true(n >= active);
  mica_contact* contacts = calloc((size_t)n, sizeof *contacts);
  contacts[0].struct_size = sizeof *contacts;
  int32_t got = 0;
  OK(w, mica_world_get_contacts(w, contacts, n, &got));
  assert_int_equal(got, n);
  double sum[3] = {0, 0, 0}, scale = 0, tangent = 0, curvature = 0;
  for (int32_t c = 0; c < n; ++c) {
    const mica_contact* k = &contacts[c];
    assert_int_equal(k->struct_size, sizeof *k);
    assert_int_equal(k->body, body);
    assert_int_equal(k->other_kind, MICA_CONTACT_OTHER_TOOL);
    assert_int_equal(k->other, tool);
    assert_true(k->kind >= MICA_CONTACT_NODE && k->kind <= MICA_CONTACT_TRIANGLE);
    double wsum = 0;
    for (int j = 0; j < k->kind; ++j) wsum += k->weights[j];
    assert_true(fabs(wsum - 1) < 1e-12);
    assert_true(k->normal_impulse >= 0);
    for (int j = 0; j < 3; ++j) {
      const double impulse = k->normal[j] * k->normal_impulse + k->tangent_impulse[j] + k->curvature_impulse[j];
      sum[j] += impulse;
      scale += fabs(impulse);
      tangent += fabs(k->tangent_impulse[j]);
      curvature += fabs(k->curvature_impulse[j]);
    }
    if (k->kind == MICA_CONTACT_NODE) assert_true(k->curvature_impulse[0] == 0 && k->curvature_impulse[1] == 0 &&
                                                  k->curvature_impulse[2] == 0);
  }
  if (friction == 0) assert_true(tangent == 0);
  else assert_true(tangent > 1e-3 * scale); /* the slide mobilised friction */
  /* A rounded tool sliding over triangles: the curvature term pushes too, and the sum needs it. */
  print_message("shape %d, friction %g, solver %d: curvature impulses %.3g of the contact impulses\n", shape, friction,
                solver, curvature / scale);
  assert_true(curvature > 1e-4 * scale); /* both tools are rounded (2 cm) */
  for (int j = 0; j < 3; ++j) {
    const double expected = -force[j];
    if (!(fabs(sum[j] / kDt - expected) <= 1e-12 * scale / kDt)) {
      print_error("shape %d, friction %g, solver %d: axis %d: contacts sum to %.17g N, tool force %.17g N\n", shape,
                  friction, solver, j, sum[j] / kDt, force[j]);
      fail();
    }
  }
  assert_true(force[1] > 0.01); /* the tissue pushes the tool up */
  free(contacts);
  mica_world_destroy(w);
}

/* A stylus the test moves: down 0.04 mm a poll from y0 (scene = device: scale 1, no offset). */
typedef struct {
  double y0;
  int polls;
  double t;
} stylus;

static mica_status read_stylus(void* user, mica_device_state* out) {
  stylus* s = user;
  out->position[0] = 0.03;
  out->position[1] = s->y0 - 4e-5 * s->polls++;
  out->position[2] = 0.05;
  out->timestamp = (s->t += 0.001); /* the device's clock never goes back */
  return MICA_OK;
}

static mica_status drop_force(void* user, const double force[3], const double torque[3]) {
  (void)user, (void)force, (void)torque;
  return MICA_OK;
}

/* Polls 10 times and steps, `steps` times, keeping every force the device was sent. */
static void poll_and_step(mica_world* w, mica_device_id device, int steps, double* sent) {
  for (int k = 0; k < steps; ++k) {
    for (int i = 0; i < 10; ++i) assert_true(mica_device_poll(w, device, NULL, sent + 3 * (10 * k + i)) >= 0);
    OK(w, mica_step(w, kDt));
  }
}

/* The device's filter (moving average) and rate limit are in the state: restored, the same stylus
 * motion renders the same forces, poll for poll, as after the save. */
static void test_device_filter_restores(void** st) {
  (void)st;
  scene s = make_scene(MICA_SOLVER_MICA, 3, 1, 0);
  stylus pen = {0.1 + 0.02 + 0.0005, 0, 0};
  mica_device_callbacks cb = {sizeof cb, 0, &pen, NULL, NULL, NULL, read_stylus, drop_force};
  mica_device_def dd = mica_device_def_default();
  dd.backend = MICA_DEVICE_CALLBACKS;
  dd.callbacks = &cb;
  dd.tool = s.tool;
  dd.max_force_rate = 1e9; /* the rate limit and the stall fade read the wall clock: out of the way */
  dd.stall_timeout = 100;
  mica_device_id device;
  OK(s.world, mica_device_create(s.world, &dd, &device));
  enum { kSteps = 6 };
  double warmup[3 * 10 * 10], first[3 * 10 * kSteps], second[3 * 10 * kSteps];
  poll_and_step(s.world, device, 10, warmup); /* the stylus reaches the block and presses in */
  size_t bytes = 0;
  OK(s.world, mica_world_state_size(s.world, &bytes));
  void* saved = malloc(bytes);
  OK(s.world, mica_world_save_state(s.world, saved, bytes));
  const int polls = pen.polls;
  poll_and_step(s.world, device, kSteps, first);
  OK(s.world, mica_world_restore_state(s.world, saved, bytes));
  pen.polls = polls; /* the stylus moves as it did after the save */
  poll_and_step(s.world, device, kSteps, second);
  assert_memory_equal(first, second, sizeof first);
  /* The filter had something to restore: the rendered force was growing through the save. */
  print_message("rendered after the save: %.4f N, %d polls later %.4f N, the same after the restore\n", first[1],
                10 * kSteps, first[3 * 10 * kSteps - 2]);
  assert_true(fabs(first[1]) > 0.01 && fabs(first[3 * 10 * kSteps - 2]) > fabs(first[1]) + 0.01);
  free(saved);
  OK(s.world, mica_device_destroy(s.world, device));
  mica_world_destroy(s.world);
}

static void test_contacts_sum_to_tool_force(void** st) {
  (void)st;
  const int32_t shapes[2] = {MICA_TOOL_SPHERE, MICA_TOOL_BOX};
  const double frictions[2] = {0, 0.5};
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b) {
      check_contact_sum(shapes[a], frictions[b], mica_world_def_default().solver);
      check_contact_sum(shapes[a], frictions[b], MICA_SOLVER_DIRECT);
    }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_set_get_round_trip),
      cmocka_unit_test(test_rest_stays_still),
      cmocka_unit_test(test_replay_default_solver),
      cmocka_unit_test(test_replay_direct_solver),
      cmocka_unit_test(test_state_before_first_step),
      cmocka_unit_test(test_restore_refusals),
      cmocka_unit_test(test_device_filter_restores),
      cmocka_unit_test(test_contacts_sum_to_tool_force),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
