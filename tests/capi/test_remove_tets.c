/* SPDX-License-Identifier: Apache-2.0 */
/* Resection through the C API (mica_body_remove_tets).
 *
 * - The removed mass is the removed tets' rho V and the drop of the body's node masses.
 * - A cut body steps as a fresh body made from its exported mesh and state would: nothing the
 *   world kept of the old topology (factors, warm starts, scratch, colourings) is left (exact and
 *   default solvers, one and two threads).
 * - A grasp through the removed region keeps its remaining nodes; a grasp left without nodes is
 *   destroyed (its id is stale).
 * - Bad input is refused with a message naming it, the world bit for bit unchanged; so is a
 *   removal that would empty a grasp a device drives (an embedded render mesh follows: test_embedding.c).
 * - A state saved before a removal is refused by the cut world; one saved after it restores into
 *   a world cut the same way; a recording with removals replays bit for bit.
 * - A piece cut free of the fixed nodes falls at g. */
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
#include "topology_scene.h"

#define L 0.04 /* m, the bar's length along x; 4 cells of 0.01 m */

static mica_world* make_world_threads(int32_t solver, double gravity, int32_t threads) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = gravity;
  wd.solver = solver;
  wd.threads = threads;
  mica_world* w = NULL;
  assert_int_equal(mica_world_create(&wd, &w), MICA_OK);
  return w;
}

static mica_world* make_world(int32_t solver, double gravity) { return make_world_threads(solver, gravity, 1); }

/* A bar [0, L] x [0, 0.02] x [0, 0.02] of 4 x 2 x 2 cells, 5 tets a cell. */
static mica_body_id make_bar(mica_world* w) {
  const mica_body_def bd = mica_body_def_default();
  const double lo[3] = {0, 0, 0}, hi[3] = {L, 0.02, 0.02};
  const int32_t cells[3] = {4, 2, 2};
  mica_body_id body = 0;
  OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 5, &body));
  return body;
}

/* Fixes the nodes of `body` with rest x <= 0. */
static mica_lpc_id fix_left_end(mica_world* w, mica_body_id body) {
  const double point[3] = {0, 0, 0}, normal[3] = {1, 0, 0};
  int32_t nodes[64], count = 0;
  OK(w, mica_body_select_nodes_by_plane(w, body, point, normal, 1e-9, 1, nodes, 64, &count));
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc = 0;
  OK(w, mica_add_lpc(w, body, nodes, count, &fixed, &lpc));
  return lpc;
}

/* The tets whose rest centroid x lies in (lo, hi); returns their count. */
static int32_t tets_between(mica_world* w, mica_body_id body, double lo, double hi, int32_t* out) {
  mesh m = get_mesh(w, body);
  int32_t count = 0;
  for (int32_t e = 0; e < m.tets; ++e) {
    const double x = rest_centroid_x(&m, e);
    if (x > lo && x < hi) out[count++] = e;
  }
  free_mesh(&m);
  return count;
}

static void step_n(mica_world* w, int n) {
  for (int k = 0; k < n; ++k) OK(w, mica_step(w, 0.01));
}

static double* step_and_get_positions(mica_world* w, mica_body_id body, int steps, int32_t* n) {
  step_n(w, steps);
  return get_positions(w, body, n);
}

/* ------------------------------------------------------------------------------------------ */

static void test_removed_mass(void** state) {
  (void)state;
  mica_world* w = make_world(MICA_SOLVER_DIRECT, -9.81);
  const mica_body_id body = make_bar(w);
  mesh m = get_mesh(w, body);
  int32_t tets[128];
  const int32_t count = tets_between(w, body, 0.03, 1, tets); /* the last column of cells */
  double expected = 0;
  for (int32_t k = 0; k < count; ++k) expected += 1000 * rest_volume(&m, tets[k]); /* the default density */
  const double before = total_mass(w, body);
  uint64_t version = 7;
  OK(w, mica_body_get_topology_version(w, body, &version));
  assert_true(version == 0);
  double removed = 0;
  OK(w, mica_body_remove_tets(w, body, tets, count, &removed));
  const double after = total_mass(w, body);
  assert_true(fabs(removed - expected) <= 1e-12 * expected);
  assert_true(fabs((before - after) - removed) <= 1e-12 * before);
  OK(w, mica_body_get_topology_version(w, body, &version));
  assert_true(version == 1);
  /* The nodes of x = 0.04 went with the last column of cells; x = 0.03 stays. */
  int32_t n = 0, t = 0;
  OK(w, mica_body_get_counts(w, body, &n, &t, NULL));
  assert_int_equal(n, m.nodes - 9);
  assert_int_equal(t, m.tets - count);
  OK(w, mica_body_remove_tets(w, body, NULL, 0, NULL)); /* nothing: no change */
  OK(w, mica_body_get_topology_version(w, body, &version));
  assert_true(version == 1);
  free_mesh(&m);
  mica_world_destroy(w);
}

/* The cut body against a fresh one made from its mesh, state and constraint: one step each. */
static void check_cut_steps_as_fresh(int32_t solver, int32_t threads) {
  mica_world* a = make_world_threads(solver, -9.81, threads);
  const mica_body_id cut = make_bar(a);
  const mica_lpc_id fixed = fix_left_end(a, cut);
  step_n(a, 5);
  int32_t tets[128];
  const int32_t count = tets_between(a, cut, 0.025, 1, tets);
  OK(a, mica_body_remove_tets(a, cut, tets, count, NULL));

  mica_world* b = make_world_threads(solver, -9.81, threads);
  const mica_body_def bd = mica_body_def_default();
  int32_t held = 0;
  const double worst = step_against_fresh(a, cut, fixed, b, &bd, 0.01, L, &held);
  assert_int_equal(held, 9);
  if (worst > 1e-9) fail_msg("solver %d, %d threads: the cut body differs from a fresh one by %g (relative)", solver, threads, worst);
  mica_world_destroy(a);
  mica_world_destroy(b);
}

static void test_cut_body_steps_as_a_fresh_one(void** state) {
  (void)state;
  check_cut_steps_as_fresh(MICA_SOLVER_DIRECT, 1);
  check_cut_steps_as_fresh(mica_world_def_default().solver, 1);
  check_cut_steps_as_fresh(mica_world_def_default().solver, 2); /* the colourings of the cut body */
}

/* A bar fixed at its left end, stepped `steps` times (the exact solver). */
static mica_world* fixed_bar(mica_body_id* body, int steps) {
  mica_world* w = make_world(MICA_SOLVER_DIRECT, -9.81);
  *body = make_bar(w);
  fix_left_end(w, *body);
  step_n(w, steps);
  return w;
}

static void remove_last_column(mica_world* w, mica_body_id body) {
  int32_t tets[128];
  const int32_t count = tets_between(w, body, 0.03, 1, tets);
  OK(w, mica_body_remove_tets(w, body, tets, count, NULL));
}

static void test_grasp_through_the_removed_region(void** state) {
  (void)state;
  mica_world* w = make_world(MICA_SOLVER_DIRECT, 0);
  const mica_body_id body = make_bar(w);
  const double wide[3] = {0.035, 0.01, 0.01}, end[3] = {L, 0.01, 0.01};
  mica_lpc_id grasp = 0, tip = 0;
  OK(w, mica_lpc_grab(w, body, wide, 0.0075, 0, &grasp));
  OK(w, mica_lpc_grab(w, body, end, 0.003, 0, &tip));
  int32_t old_nodes[64], old_count = 0, n = 0;
  OK(w, mica_lpc_get_nodes(w, grasp, old_nodes, 64, &old_count));
  double* x_old = get_positions(w, body, &n);
  int32_t kept = 0;
  double kept_x[64][3];
  for (int32_t k = 0; k < old_count; ++k)
    if (x_old[3 * old_nodes[k]] < 0.035) memcpy(kept_x[kept++], x_old + 3 * old_nodes[k], sizeof kept_x[0]);
  assert_true(kept > 0 && kept < old_count);

  remove_last_column(w, body);

  int32_t nodes[64], held = 0;
  OK(w, mica_lpc_get_nodes(w, grasp, nodes, 64, &held));
  assert_int_equal(held, kept);
  double* x = get_positions(w, body, &n);
  for (int32_t k = 0; k < held; ++k) assert_memory_equal(x + 3 * nodes[k], kept_x[k], sizeof kept_x[0]);
  assert_int_equal(mica_lpc_get_nodes(w, tip, nodes, 64, &held), MICA_ERR_STALE_ID);
  /* The grasp still holds: its nodes stay at their targets while the body steps. */
  step_n(w, 3);
  free(x);
  x = get_positions(w, body, &n);
  OK(w, mica_lpc_get_nodes(w, grasp, nodes, 64, &held));
  for (int32_t k = 0; k < held; ++k)
    for (int c = 0; c < 3; ++c) assert_true(fabs(x[3 * nodes[k] + c] - kept_x[k][c]) < 1e-9);
  free(x), free(x_old);
  mica_world_destroy(w);
}

static void expect_refused(mica_world* w, mica_body_id body, const int32_t* tets, int32_t count, mica_status status,
                           const char* words) {
  size_t before_bytes = 0, after_bytes = 0;
  uint8_t* before = save(w, &before_bytes);
  double removed = -1;
  assert_int_equal(mica_body_remove_tets(w, body, tets, count, &removed), status);
  if (!strstr(mica_world_last_error(w), words)) fail_msg("message \"%s\" lacks \"%s\"", mica_world_last_error(w), words);
  assert_true(removed == -1);
  uint8_t* after = save(w, &after_bytes);
  assert_int_equal(before_bytes, after_bytes);
  assert_memory_equal(before, after, before_bytes);
  free(before), free(after);
}

static void test_bad_input_changes_nothing(void** state) {
  (void)state;
  mica_body_id body = 0;
  mica_world* w = fixed_bar(&body, 2);
  int32_t t = 0;
  OK(w, mica_body_get_counts(w, body, NULL, &t, NULL));
  const int32_t out_of_range[2] = {3, t}, negative[1] = {-1}, twice[3] = {4, 9, 4};
  expect_refused(w, body, out_of_range, 2, MICA_ERR_OUT_OF_RANGE, "tet index 80 at position 1 is outside 0..79");
  expect_refused(w, body, negative, 1, MICA_ERR_OUT_OF_RANGE, "tet index -1");
  expect_refused(w, body, twice, 3, MICA_ERR_INVALID_ARGUMENT, "tet 4 is listed twice (positions 0 and 2)");
  int32_t* every = malloc(sizeof(int32_t) * (size_t)t);
  for (int32_t e = 0; e < t; ++e) every[e] = t - 1 - e;
  expect_refused(w, body, every, t, MICA_ERR_INVALID_ARGUMENT, "without tets: destroy the body instead");
  expect_refused(w, body, NULL, 2, MICA_ERR_NULL_ARGUMENT, "tets");
  expect_refused(w, body, twice, -1, MICA_ERR_INVALID_ARGUMENT, "count");
  expect_refused(w, 0, twice, 1, MICA_ERR_STALE_ID, "body id");
  expect_refused(w, body + 1, twice, 1, MICA_ERR_STALE_ID, "body id");
  assert_int_equal(mica_body_remove_tets(NULL, body, twice, 1, NULL), MICA_ERR_NULL_ARGUMENT);
  uint64_t version = 0;
  assert_int_equal(mica_body_get_topology_version(w, body, NULL), MICA_ERR_NULL_ARGUMENT);
  assert_int_equal(mica_body_get_topology_version(w, 0, &version), MICA_ERR_STALE_ID);
  free(every);
  mica_world_destroy(w);
}

/* A removal that would empty a grasp a device drives is refused; one under an embedded render mesh
 * is not (the mesh follows: tests/capi/test_embedding.c). */
static void test_what_holds_the_body_refuses(void** state) {
  (void)state;
  mica_body_id body = 0;
  mica_world* w = fixed_bar(&body, 1);
  int32_t tets[128];
  const int32_t count = tets_between(w, body, 0.03, 1, tets);
  const double end[3] = {L, 0.01, 0.01};
  mica_lpc_id tip = 0;
  OK(w, mica_lpc_grab(w, body, end, 0.003, 0, &tip));
  mica_device_def dd = mica_device_def_default();
  dd.backend = MICA_DEVICE_SIMULATED;
  dd.lpc = tip;
  mica_device_id device = 0;
  OK(w, mica_device_create(w, &dd, &device));
  expect_refused(w, body, tets, count, MICA_ERR_WRONG_STATE, "a device drives without nodes: destroy the device first");
  OK(w, mica_device_destroy(w, device));

  const double xyz[9] = {0.005, 0.005, 0.005, 0.015, 0.005, 0.005, 0.005, 0.015, 0.005};
  const int32_t triangle[3] = {0, 1, 2};
  const mica_embedding_def ed = mica_embedding_def_default();
  mica_embedding_id sheet = 0;
  OK(w, mica_embedding_create(w, body, &ed, xyz, 3, triangle, 1, &sheet));
  OK(w, mica_body_remove_tets(w, body, tets, count, NULL)); /* the sheet is at the fixed end: kept */
  int32_t inside = 0;
  OK(w, mica_embedding_get_counts(w, sheet, NULL, &inside, NULL, NULL));
  assert_int_equal(inside, 3);
  mica_world_destroy(w);
}

static void test_saved_states_across_a_removal(void** state) {
  (void)state;
  mica_body_id body = 0;
  mica_world* w = fixed_bar(&body, 3);
  size_t old_bytes = 0;
  uint8_t* old_state = save(w, &old_bytes);
  remove_last_column(w, body);
  step_n(w, 2);
  size_t cut_bytes = 0, check_bytes = 0;
  uint8_t* cut_state = save(w, &cut_bytes);
  /* The state from before the removal does not fit: the message names the shape's difference. */
  assert_int_equal(mica_world_restore_state(w, old_state, old_bytes), MICA_ERR_INVALID_ARGUMENT);
  assert_non_null(strstr(mica_world_last_error(w), "nodes"));
  uint8_t* check = save(w, &check_bytes);
  assert_int_equal(check_bytes, cut_bytes);
  assert_memory_equal(check, cut_state, cut_bytes);

  /* The state after it restores into another world cut the same way (unstepped since). */
  mica_body_id other = 0;
  mica_world* w2 = fixed_bar(&other, 0);
  remove_last_column(w2, other);
  OK(w2, mica_world_restore_state(w2, cut_state, cut_bytes));
  int32_t n = 0, n2 = 0;
  double* x = step_and_get_positions(w, body, 2, &n);
  double* x2 = step_and_get_positions(w2, other, 2, &n2);
  assert_int_equal(n, n2);
  assert_memory_equal(x, x2, sizeof(double) * 3 * (size_t)n);
  free(x), free(x2), free(old_state), free(cut_state), free(check);
  mica_world_destroy(w);
  mica_world_destroy(w2);
}

static void test_recording_replays_removals(void** state) {
  (void)state;
  const char* path = "test_remove_tets.micarec";
  mica_world* w = make_world(MICA_SOLVER_DIRECT, -9.81);
  OK(w, mica_world_record_start(w, path));
  const mica_body_id body = make_bar(w);
  fix_left_end(w, body);
  step_n(w, 3);
  remove_last_column(w, body);
  step_n(w, 2);
  int32_t tets[128];
  tets_between(w, body, 0.02, 0.03, tets);
  OK(w, mica_body_remove_tets(w, body, tets, 3, NULL));
  step_n(w, 2);
  OK(w, mica_world_record_stop(w));
  int32_t n = 0;
  double* x = get_positions(w, body, &n);

  mica_replay* r = NULL;
  OK(NULL, mica_replay_open(path, &r));
  mica_world* replayed = mica_replay_world(r);
  int32_t steps = 0, stepped = 1;
  while (stepped) {
    OK(replayed, mica_replay_step(r, &stepped));
    steps += stepped;
  }
  assert_int_equal(steps, 7);
  uint64_t version = 0;
  OK(replayed, mica_body_get_topology_version(replayed, body, &version));
  assert_true(version == 2);
  int32_t n2 = 0;
  double* x2 = get_positions(replayed, body, &n2);
  assert_int_equal(n, n2);
  assert_memory_equal(x, x2, sizeof(double) * 3 * (size_t)n);
  mica_replay_close(r);
  remove(path);
  free(x), free(x2);
  mica_world_destroy(w);
}

static void test_a_piece_cut_free_falls(void** state) {
  (void)state;
  const double g = 9.81, h = 0.01;
  mica_world* w = make_world(mica_world_def_default().solver, -g);
  const mica_body_id body = make_bar(w);
  fix_left_end(w, body);
  int32_t tets[128];
  const int32_t count = tets_between(w, body, 0.02, 0.03, tets); /* the third column of cells */
  OK(w, mica_body_remove_tets(w, body, tets, count, NULL));
  mesh m = get_mesh(w, body);
  double* mass = malloc(sizeof(double) * (size_t)m.nodes);
  double* v = malloc(sizeof(double) * 3 * (size_t)m.nodes);
  OK(w, mica_body_get_node_masses(w, body, mass, m.nodes, NULL));
  for (int k = 0; k < 20; ++k) OK(w, mica_step(w, h)); /* no failed step */
  OK(w, mica_body_get_velocities(w, body, v, m.nodes, NULL));
  double p = 0, piece = 0; /* the free piece's momentum along y and mass */
  for (int32_t i = 0; i < m.nodes; ++i)
    if (m.rest[3 * i] > 0.025) {
      p += mass[i] * v[3 * i + 1];
      piece += mass[i];
    }
  const double acceleration = -p / piece / (20 * h);
  if (fabs(acceleration - g) > 0.01 * g) fail_msg("the free piece accelerates at %g m/s^2", acceleration);
  free(mass), free(v);
  free_mesh(&m);
  mica_world_destroy(w);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_removed_mass),
      cmocka_unit_test(test_cut_body_steps_as_a_fresh_one),
      cmocka_unit_test(test_grasp_through_the_removed_region),
      cmocka_unit_test(test_bad_input_changes_nothing),
      cmocka_unit_test(test_what_holds_the_body_refuses),
      cmocka_unit_test(test_saved_states_across_a_removal),
      cmocka_unit_test(test_recording_replays_removals),
      cmocka_unit_test(test_a_piece_cut_free_falls),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
