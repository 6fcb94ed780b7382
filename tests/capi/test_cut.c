/* SPDX-License-Identifier: Apache-2.0 */
/* Incision through the C API (mica_body_cut).
 *
 * - A bar fixed at one end and cut through its middle parts in two: the free half falls at g, the
 *   fixed half's support carries only its own weight; the mass stays (1e-12).
 * - A cut off the element faces still parts the bar (the faces nearest the triangles); a cut
 *   that stops inside the bar leaves it whole, opened up to where it stops.
 * - A cut frees no sliver (a piece of fewer than 12 tets), and frees a larger piece.
 * - A cut body steps as a fresh body made from its exported mesh and state would (exact and
 *   default solvers, one and two threads).
 * - A grasp across the cut holds both copies of each node it held.
 * - Bad input is refused with a message naming it, the world bit for bit unchanged.
 * - Saved states and recordings across cuts: bit for bit. */
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

#include "capi_ok.h"
#include "topology_scene.h"

#define G 9.81
#define L 0.1 /* m, the bar's length along x; 10 cells of 0.01 m */

static mica_world* make_world(int32_t solver, int32_t threads) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = -G;
  wd.solver = solver;
  wd.threads = threads;
  mica_world* w = NULL;
  assert_int_equal(mica_world_create(&wd, &w), MICA_OK);
  return w;
}

/* A bar [0, L] x [0, 0.02] x [0, 0.02] of 10 x 2 x 2 cells, 5 tets a cell, fixed at x = 0;
 * stiffness-proportional damping (it leaves a free fall alone). */
static mica_body_id fixed_bar(mica_world* w, mica_lpc_id* out_fixed) {
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = 1e5;
  bd.rayleigh_beta = 0.1;
  const double lo[3] = {0, 0, 0}, hi[3] = {L, 0.02, 0.02};
  const int32_t cells[3] = {10, 2, 2};
  mica_body_id body = 0;
  OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 5, &body));
  const double point[3] = {0, 0, 0}, normal[3] = {1, 0, 0};
  int32_t nodes[64], count = 0;
  OK(w, mica_body_select_nodes_by_plane(w, body, point, normal, 1e-9, 1, nodes, 64, &count));
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc = 0;
  OK(w, mica_add_lpc(w, body, nodes, count, &fixed, &lpc));
  if (out_fixed) *out_fixed = lpc;
  return body;
}

static void step_n(mica_world* w, int n) {
  for (int k = 0; k < n; ++k) OK(w, mica_step(w, 0.01));
}

/* Two triangles covering the plane x = at across the bar (and beyond it), or, with `depth` < 1,
 * only its part y < depth * 0.02. */
static void cross_section(double at, double depth, double out[18]) {
  const double y0 = -0.01, y1 = -0.01 + depth * 0.03, z0 = -0.01, z1 = 0.03;
  const double t[18] = {at, y0, z0, at, y1, z0, at, y1, z1, at, y0, z0, at, y1, z1, at, y0, z1};
  memcpy(out, t, sizeof t);
}

static mica_status cut_at(mica_world* w, mica_body_id body, double at, double depth, int32_t* faces, int32_t* added) {
  double t[18];
  cross_section(at, depth, t);
  return mica_body_cut(w, body, t, 2, faces, added);
}

/* The body's node masses and the pieces its tets make. */
typedef struct {
  mesh m;
  double* mass;
  int32_t* piece;
  int32_t pieces;
} pieces;

static pieces get_pieces(mica_world* w, mica_body_id body) {
  pieces p;
  p.m = get_mesh(w, body);
  p.mass = malloc(sizeof(double) * (size_t)p.m.nodes);
  p.piece = malloc(sizeof(int32_t) * (size_t)p.m.nodes);
  OK(w, mica_body_get_node_masses(w, body, p.mass, p.m.nodes, NULL));
  p.pieces = find_pieces(&p.m, p.piece);
  return p;
}

static void free_pieces(pieces* p) {
  free_mesh(&p->m);
  free(p->mass);
  free(p->piece);
}

/* The momentum along y and the mass of piece k. */
static void piece_momentum(mica_world* w, mica_body_id body, const pieces* p, int32_t k, double* momentum, double* mass) {
  double* v = malloc(sizeof(double) * 3 * (size_t)p->m.nodes);
  OK(w, mica_body_get_velocities(w, body, v, p->m.nodes, NULL));
  *momentum = *mass = 0;
  for (int32_t i = 0; i < p->m.nodes; ++i)
    if (p->piece[i] == k) {
      *momentum += p->mass[i] * v[3 * i + 1];
      *mass += p->mass[i];
    }
  free(v);
}

/* ------------------------------------------------------------------------------------------ */

static void test_a_bar_cut_through_parts_in_two(void** state) {
  (void)state;
  mica_world* w = make_world(mica_world_def_default().solver, 1);
  mica_lpc_id fixed = 0;
  const mica_body_id body = fixed_bar(w, &fixed);
  step_n(w, 200); /* it settles under its weight */
  const double mass = total_mass(w, body);
  double reaction[3];
  OK(w, mica_lpc_get_reaction(w, fixed, reaction));
  if (fabs(-reaction[1] - mass * G) > 0.01 * mass * G) fail_msg("the support carries %g N of %g N", -reaction[1], mass * G);

  int32_t faces = 0, added = 0, n_before = 0;
  OK(w, mica_body_get_counts(w, body, &n_before, NULL, NULL));
  OK(w, cut_at(w, body, 0.05, 1, &faces, &added));
  assert_int_equal(faces, 2 * 2 * 2); /* a 2 x 2 cell section, two triangles per cell face */
  assert_int_equal(added, 3 * 3);     /* the section's 3 x 3 nodes */
  uint64_t version = 0;
  OK(w, mica_body_get_topology_version(w, body, &version));
  assert_true(version == 1);
  const double after = total_mass(w, body);
  if (fabs(after - mass) > 1e-12 * mass) fail_msg("the cut changed the mass by %g kg", after - mass);

  pieces p = get_pieces(w, body);
  assert_int_equal(p.pieces, 2);
  const int32_t held = p.piece[0], free_piece = 1 - held; /* node 0 is at x = 0: fixed */
  double p0 = 0, m_free = 0, p1 = 0;
  piece_momentum(w, body, &p, free_piece, &p0, &m_free);
  step_n(w, 20);
  piece_momentum(w, body, &p, free_piece, &p1, &m_free);
  const double acceleration = -(p1 - p0) / m_free / 0.2;
  if (fabs(acceleration - G) > 0.01 * G) fail_msg("the free half accelerates at %g m/s^2", acceleration);

  step_n(w, 150); /* the fixed half settles */
  double m_held = 0, unused = 0;
  piece_momentum(w, body, &p, held, &unused, &m_held);
  OK(w, mica_lpc_get_reaction(w, fixed, reaction));
  if (fabs(-reaction[1] - m_held * G) > 0.01 * m_held * G)
    fail_msg("the support carries %g N, the fixed half weighs %g N", -reaction[1], m_held * G);
  assert_true(fabs(m_held + m_free - mass) <= 1e-12 * mass);
  free_pieces(&p);
  mica_world_destroy(w);
}

static void test_cuts_off_the_faces_and_partial_cuts(void** state) {
  (void)state;
  mica_world* w = make_world(MICA_SOLVER_DIRECT, 1);
  const mica_body_id body = fixed_bar(w, NULL);
  const double mass = total_mass(w, body);
  int32_t faces = 0, added = 0;
  /* Halfway into the bar from y = 0: the faces it crosses open, the bar stays one piece. */
  OK(w, cut_at(w, body, 0.0337, 0.5, &faces, &added));
  assert_true(faces > 0 && added > 0);
  pieces p = get_pieces(w, body);
  assert_int_equal(p.pieces, 1);
  free_pieces(&p);
  int32_t surface_before = 0, surface_after = 0;
  /* The rest of the way: two pieces. */
  OK(w, mica_body_get_surface(w, body, NULL, 0, &surface_before));
  OK(w, cut_at(w, body, 0.0337, 1, &faces, &added));
  OK(w, mica_body_get_surface(w, body, NULL, 0, &surface_after));
  assert_true(surface_after > surface_before);
  p = get_pieces(w, body);
  assert_int_equal(p.pieces, 2);
  for (int32_t e = 0; e < p.m.tets; ++e) assert_true(signed_volume(p.m.rest, &p.m, e) > 0);
  free_pieces(&p);
  assert_true(fabs(total_mass(w, body) - mass) <= 1e-12 * mass);
  /* Cutting where it is already cut, or beside the bar, separates nothing: no change. */
  uint64_t version = 0;
  OK(w, mica_body_get_topology_version(w, body, &version));
  OK(w, cut_at(w, body, 0.0337, 1, &faces, &added));
  assert_int_equal(added, 0);
  OK(w, cut_at(w, body, 0.5, 1, &faces, &added));
  assert_int_equal(faces, 0);
  uint64_t again = 0;
  OK(w, mica_body_get_topology_version(w, body, &again));
  assert_true(again == version);
  step_n(w, 5);
  mica_world_destroy(w);
}

/* The 12 triangles of the closed box [lo, hi]. */
static void closed_box(const double lo[3], const double hi[3], double out[108]) {
  static const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  double corner[8][3];
  for (int k = 0; k < 8; ++k)
    for (int a = 0; a < 3; ++a) corner[k][a] = (k >> a) & 1 ? hi[a] : lo[a];
  for (int q = 0; q < 6; ++q) {
    const int t[6] = {quads[q][0], quads[q][1], quads[q][2], quads[q][0], quads[q][2], quads[q][3]};
    for (int k = 0; k < 6; ++k) memcpy(out + 18 * q + 3 * k, corner[t[k]], sizeof corner[0]);
  }
}

/* The fewest tets in a piece. */
static int32_t smallest_piece(const pieces* p) {
  int32_t smallest = p->m.tets;
  for (int32_t k = 0; k < p->pieces; ++k) {
    int32_t count = 0;
    for (int32_t e = 0; e < p->m.tets; ++e) count += p->piece[p->m.tet[4 * e]] == k;
    if (count < smallest) smallest = count;
  }
  return smallest;
}

/* A cut frees no piece of fewer than 12 tets (docs/cutting.md): a closed box around one tet's
 * centroid crosses the faces it shares, and the tet stays joined across one of them (without the
 * rule it is a piece of its own); a box around two cells' length of the bar (about 40 tets) frees
 * them. */
static void test_a_cut_frees_no_sliver(void** state) {
  (void)state;
  mica_world* w = make_world(MICA_SOLVER_DIRECT, 1);
  const mica_body_id body = fixed_bar(w, NULL);
  const double mass = total_mass(w, body);
  mesh m = get_mesh(w, body);
  const int32_t e = m.tets / 2;
  double c[3] = {0, 0, 0};
  for (int k = 0; k < 4; ++k)
    for (int a = 0; a < 3; ++a) c[a] += 0.25 * m.rest[3 * m.tet[4 * e + k] + a];
  free_mesh(&m);
  double box[108];
  const double lo[3] = {c[0] - 1e-3, c[1] - 1e-3, c[2] - 1e-3}, hi[3] = {c[0] + 1e-3, c[1] + 1e-3, c[2] + 1e-3};
  closed_box(lo, hi, box);
  int32_t faces = 0, added = 0;
  OK(w, mica_body_cut(w, body, box, 12, &faces, &added));
  assert_true(faces > 0); /* it opens, but stays joined across one face */
  pieces p = get_pieces(w, body);
  assert_int_equal(p.pieces, 1);
  free_pieces(&p);

  const double around_lo[3] = {0.035, -0.01, -0.01}, around_hi[3] = {0.055, 0.03, 0.03};
  closed_box(around_lo, around_hi, box);
  OK(w, mica_body_cut(w, body, box, 12, &faces, &added));
  p = get_pieces(w, body);
  assert_int_equal(p.pieces, 3);
  assert_true(smallest_piece(&p) >= 12);
  free_pieces(&p);
  assert_true(fabs(total_mass(w, body) - mass) <= 1e-12 * mass);
  step_n(w, 5);
  mica_world_destroy(w);
}

/* The cut body against a fresh one made from its mesh, state and constraint: one step each. */
static void check_cut_steps_as_fresh(int32_t solver, int32_t threads) {
  mica_world* a = make_world(solver, threads);
  mica_lpc_id fixed = 0;
  const mica_body_id cut = fixed_bar(a, &fixed);
  step_n(a, 5);
  OK(a, cut_at(a, cut, 0.062, 1, NULL, NULL));

  mica_world* b = make_world(solver, threads);
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = 1e5;
  bd.rayleigh_beta = 0.1;
  int32_t held = 0;
  const double worst = step_against_fresh(a, cut, fixed, b, &bd, 0.01, L, &held);
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

/* A blade far from the bar (it touches nothing): with it in the world the factored sweep keeps
 * what a bridge after a cut needs (docs/cutting.md, "The factor after a cut"). */
static void add_idle_blade(mica_world* w) {
  mica_tool_def td = mica_tool_def_default();
  td.shape = MICA_TOOL_CAPSULE;
  td.radius = 0.0005;
  td.half_length = 0.01;
  td.blade = 1;
  const double far[3] = {1, 1, 1};
  memcpy(td.position, far, sizeof far);
  mica_tool_id tool = 0;
  OK(w, mica_tool_create(w, &td, &tool));
}

static mica_world_stats stats_of(mica_world* w) {
  mica_world_stats st;
  memset(&st, 0, sizeof st);
  st.struct_size = sizeof st;
  OK(w, mica_world_get_stats(w, &st));
  return st;
}

/* With a factor to bridge, no step after a cut factors on the stepping thread: the first one
 * starts the cut body's factorization in the background (and makes none itself) and solves with
 * the bridge, as a fresh world does to 1e-9 of the bar's length; the next ones make or start
 * none (the factor is adopted on the fourth, in lockstep; whether that step waited for the
 * background thread depends on the machine's load, so it is not asserted), and afterwards the
 * cut body still steps as a fresh one. */
static void test_no_step_factors_after_a_cut(void** state) {
  (void)state;
  for (int32_t threads = 1; threads <= 2; ++threads) {
    mica_world* a = make_world(mica_world_def_default().solver, threads);
    add_idle_blade(a);
    mica_lpc_id fixed = 0;
    const mica_body_id cut = fixed_bar(a, &fixed);
    step_n(a, 5);
    OK(a, cut_at(a, cut, 0.062, 1, NULL, NULL));
    mica_body_def bd = mica_body_def_default();
    bd.youngs_modulus = 1e5;
    bd.rayleigh_beta = 0.1;
    int32_t held = 0;
    mica_world* b = make_world(mica_world_def_default().solver, threads);
    double worst = step_against_fresh(a, cut, fixed, b, &bd, 0.01, L, &held);
    mica_world_stats st = stats_of(a);
    assert_int_equal(st.factor_waits, 0);
    assert_int_equal(st.factorizations, 1); /* started in the background */
    if (worst > 1e-9) fail_msg("%d threads: the bridged step differs from a fresh one by %g (relative)", threads, worst);
    for (int k = 0; k < 6; ++k) {
      OK(a, mica_step(a, 0.01));
      st = stats_of(a);
      assert_int_equal(st.factorizations, 0);
    }
    mica_world_destroy(b);
    b = make_world(mica_world_def_default().solver, threads);
    worst = step_against_fresh(a, cut, fixed, b, &bd, 0.01, L, &held);
    if (worst > 1e-9) fail_msg("%d threads: after the adoption the cut body differs from a fresh one by %g", threads, worst);
    mica_world_destroy(a);
    mica_world_destroy(b);
  }
}

/* A state saved while the factor bridges a cut (right after it, and a step later with the cut
 * body's factor in the making) restores into the world and steps the same bits. */
static void test_a_state_saved_during_a_bridge_restores_bit_for_bit(void** state) {
  (void)state;
  mica_world* w = make_world(mica_world_def_default().solver, 1);
  add_idle_blade(w);
  const mica_body_id body = fixed_bar(w, NULL);
  step_n(w, 5);
  OK(w, cut_at(w, body, 0.062, 1, NULL, NULL));
  for (int after = 0; after < 2; ++after) {
    if (after) OK(w, mica_step(w, 0.01));
    size_t bytes = 0;
    uint8_t* saved = save(w, &bytes);
    step_n(w, 8); /* past the adoption */
    int32_t n = 0, m = 0;
    double* first = get_positions(w, body, &n);
    OK(w, mica_world_restore_state(w, saved, bytes));
    step_n(w, 8);
    double* again = get_positions(w, body, &m);
    assert_int_equal(n, m);
    assert_memory_equal(first, again, sizeof(double) * 3 * (size_t)n);
    OK(w, mica_world_restore_state(w, saved, bytes));
    free(first), free(again), free(saved);
  }
  mica_world_destroy(w);
}

static void test_a_grasp_across_the_cut_holds_both_sides(void** state) {
  (void)state;
  mica_world* w = make_world(MICA_SOLVER_DIRECT, 1);
  const mica_body_id body = fixed_bar(w, NULL);
  const double centre[3] = {0.05, 0.01, 0.02};
  mica_lpc_id grasp = 0;
  OK(w, mica_lpc_grab(w, body, centre, 0.0075, 0, &grasp));
  int32_t before[64], held_before = 0, after[64], held_after = 0, added = 0;
  OK(w, mica_lpc_get_nodes(w, grasp, before, 64, &held_before));
  int32_t on_plane = 0;
  int32_t n = 0;
  double* x = get_positions(w, body, &n);
  for (int32_t k = 0; k < held_before; ++k) on_plane += fabs(x[3 * before[k]] - 0.05) < 1e-12;
  assert_true(on_plane > 0);
  OK(w, cut_at(w, body, 0.05, 1, NULL, &added));
  OK(w, mica_lpc_get_nodes(w, grasp, after, 64, &held_after));
  assert_int_equal(held_after, held_before + on_plane); /* each held node of the section: both copies */
  /* The grasp holds both halves where they were while the body steps. */
  step_n(w, 3);
  double* y = get_positions(w, body, &n);
  const mesh m = get_mesh(w, body);
  for (int32_t k = 0; k < held_after; ++k) {
    const int32_t i = after[k];
    for (int c = 0; c < 3; ++c) assert_true(fabs(y[3 * i + c] - m.rest[3 * i + c]) < 1e-9);
  }
  mesh mm = m;
  free_mesh(&mm);
  free(x), free(y);
  mica_world_destroy(w);
}

static void expect_refused(mica_world* w, mica_body_id body, const double* t, int32_t count, mica_status status,
                           const char* words) {
  size_t before_bytes = 0, after_bytes = 0;
  uint8_t* before = save(w, &before_bytes);
  int32_t faces = -1;
  assert_int_equal(mica_body_cut(w, body, t, count, &faces, NULL), status);
  if (!strstr(mica_world_last_error(w), words)) fail_msg("message \"%s\" lacks \"%s\"", mica_world_last_error(w), words);
  assert_int_equal(faces, -1);
  uint8_t* after = save(w, &after_bytes);
  assert_int_equal(before_bytes, after_bytes);
  assert_memory_equal(before, after, before_bytes);
  free(before), free(after);
}

static void test_bad_input_changes_nothing(void** state) {
  (void)state;
  mica_world* w = make_world(MICA_SOLVER_DIRECT, 1);
  const mica_body_id body = fixed_bar(w, NULL);
  step_n(w, 2);
  double t[18];
  cross_section(0.05, 1, t);
  t[13] = NAN;
  expect_refused(w, body, t, 2, MICA_ERR_INVALID_ARGUMENT, "cut triangle 1 has a corner that is not finite");
  cross_section(0.05, 1, t);
  expect_refused(w, body, NULL, 2, MICA_ERR_NULL_ARGUMENT, "triangles");
  expect_refused(w, body, t, -1, MICA_ERR_INVALID_ARGUMENT, "triangle_count");
  expect_refused(w, 0, t, 2, MICA_ERR_STALE_ID, "body id");
  assert_int_equal(mica_body_cut(NULL, body, t, 2, NULL, NULL), MICA_ERR_NULL_ARGUMENT);
  OK(w, mica_body_cut(w, body, NULL, 0, NULL, NULL)); /* nothing to cut */
  mica_world_destroy(w);
}

static void test_saved_states_and_recordings_across_cuts(void** state) {
  (void)state;
  const char* path = "test_cut.micarec";
  mica_world* w = make_world(mica_world_def_default().solver, 1);
  OK(w, mica_world_record_start(w, path));
  const mica_body_id body = fixed_bar(w, NULL);
  step_n(w, 3);
  OK(w, cut_at(w, body, 0.0437, 0.6, NULL, NULL));
  step_n(w, 2);
  size_t bytes = 0;
  uint8_t* cut_state = save(w, &bytes);
  OK(w, cut_at(w, body, 0.0837, 1, NULL, NULL));
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
  int32_t n2 = 0;
  double* x2 = get_positions(replayed, body, &n2);
  assert_int_equal(n, n2);
  assert_memory_equal(x, x2, sizeof(double) * 3 * (size_t)n);
  mica_replay_close(r);
  remove(path);

  /* The state saved between the two cuts restores into a world cut the same way. */
  mica_world* w2 = make_world(mica_world_def_default().solver, 1);
  const mica_body_id other = fixed_bar(w2, NULL);
  assert_int_equal(mica_world_restore_state(w2, cut_state, bytes), MICA_ERR_INVALID_ARGUMENT); /* uncut: another shape */
  OK(w2, cut_at(w2, other, 0.0437, 0.6, NULL, NULL));
  OK(w2, mica_world_restore_state(w2, cut_state, bytes));
  OK(w2, cut_at(w2, other, 0.0837, 1, NULL, NULL));
  step_n(w2, 2);
  double* x3 = get_positions(w2, other, &n2);
  assert_int_equal(n, n2);
  assert_memory_equal(x, x3, sizeof(double) * 3 * (size_t)n);
  free(x), free(x2), free(x3), free(cut_state);
  mica_world_destroy(w);
  mica_world_destroy(w2);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_a_bar_cut_through_parts_in_two),
      cmocka_unit_test(test_cuts_off_the_faces_and_partial_cuts),
      cmocka_unit_test(test_a_cut_frees_no_sliver),
      cmocka_unit_test(test_cut_body_steps_as_a_fresh_one),
      cmocka_unit_test(test_no_step_factors_after_a_cut),
      cmocka_unit_test(test_a_state_saved_during_a_bridge_restores_bit_for_bit),
      cmocka_unit_test(test_a_grasp_across_the_cut_holds_both_sides),
      cmocka_unit_test(test_bad_input_changes_nothing),
      cmocka_unit_test(test_saved_states_and_recordings_across_cuts),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
