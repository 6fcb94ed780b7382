/* SPDX-License-Identifier: Apache-2.0 */
/* Random cuts and removals (mica_body_cut, mica_body_remove_tets), 100 through the 10 cm cube and
 * 100 through the nidus, with a sphere pressing the top and a grab holding a patch of it, gravity
 * on, each followed by a step: blades of random place, direction and size (through the grabbed
 * nodes and the contacts too), removals of random tets (pieces of single tets are left behind).
 * After every change and step:
 * - no step fails, and every position and velocity is finite;
 * - every tet keeps a positive rest volume, and the smallest tet quality (a cut makes no element)
 *   stays the mesh's own;
 * - the mass is the mass before less what the removals reported (1e-12 relative). */
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
#include "press_scene.h"
#include "topology_scene.h"

#define NIDUS MICA_TEST_DATA_DIR "/../../data/nidus/nidus.msh"

static uint64_t rng = 0x2545F4914F6CDD1Dull;
static double uniform(void) { /* xorshift64*, in [0, 1) */
  rng ^= rng >> 12, rng ^= rng << 25, rng ^= rng >> 27;
  return (double)((rng * 0x2545F4914F6CDD1Dull) >> 11) * 0x1.0p-53;
}

/* The volume over the cube of the rms edge (1 for a regular tet after the factor), at rest. */
static double quality(const mesh* m, int32_t e) {
  const int32_t* t = m->tet + 4 * e;
  double sum = 0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b)
      for (int c = 0; c < 3; ++c) {
        const double d = m->rest[3 * t[a] + c] - m->rest[3 * t[b] + c];
        sum += d * d;
      }
  const double rms = sqrt(sum / 6);
  return 6 * sqrt(2.0) * signed_volume(m->rest, m, e) / (rms * rms * rms);
}

static double smallest_quality(const mesh* m) {
  double q = HUGE_VAL;
  for (int32_t e = 0; e < m->tets; ++e) q = fmin(q, quality(m, e));
  return q;
}

static void random_changes(mica_world* w, mica_body_id body, int count, const char* name) {
  mesh m = get_mesh(w, body);
  double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (int32_t i = 0; i < m.nodes; ++i)
    for (int c = 0; c < 3; ++c) lo[c] = fmin(lo[c], m.rest[3 * i + c]), hi[c] = fmax(hi[c], m.rest[3 * i + c]);
  const double q0 = smallest_quality(&m);
  free_mesh(&m);
  double mass = total_mass(w, body);
  int cuts = 0, removals = 0;
  for (int k = 0; k < count; ++k) {
    mesh now = get_mesh(w, body);
    if (uniform() < 0.75 || now.tets < 10) {
      /* A blade: a random quad through a random point of the body's box, 5 to 40 mm a side. */
      double p[3], u[3], v[3];
      for (int c = 0; c < 3; ++c) p[c] = lo[c] + (hi[c] - lo[c]) * uniform();
      for (int c = 0; c < 3; ++c) u[c] = uniform() - 0.5, v[c] = uniform() - 0.5;
      const double a = 0.005 + 0.035 * uniform(), b = 0.005 + 0.035 * uniform();
      const double nu = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]) + 1e-12, nv = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) + 1e-12;
      double q[4][3];
      for (int c = 0; c < 3; ++c) {
        q[0][c] = p[c] - a * u[c] / nu - b * v[c] / nv;
        q[1][c] = p[c] + a * u[c] / nu - b * v[c] / nv;
        q[2][c] = p[c] + a * u[c] / nu + b * v[c] / nv;
        q[3][c] = p[c] - a * u[c] / nu + b * v[c] / nv;
      }
      const double t[18] = {q[0][0], q[0][1], q[0][2], q[1][0], q[1][1], q[1][2], q[2][0], q[2][1], q[2][2],
                            q[0][0], q[0][1], q[0][2], q[2][0], q[2][1], q[2][2], q[3][0], q[3][1], q[3][2]};
      const mica_status s = mica_body_cut(w, body, t, 2, NULL, NULL);
      if (s < 0) fail_msg("%s, change %d: the cut failed: %s", name, k, mica_world_last_error(w));
      ++cuts;
    } else {
      /* A removal of 1 to 5 random tets. */
      int32_t tets[5];
      const int32_t n = 1 + (int32_t)(5 * uniform());
      int32_t got = 0;
      while (got < n) {
        const int32_t e = (int32_t)(now.tets * uniform());
        int seen = 0;
        for (int32_t j = 0; j < got; ++j) seen |= tets[j] == e;
        if (!seen) tets[got++] = e;
      }
      double removed = 0;
      const mica_status s = mica_body_remove_tets(w, body, tets, n, &removed);
      if (s < 0) fail_msg("%s, change %d: the removal failed: %s", name, k, mica_world_last_error(w));
      mass -= removed;
      ++removals;
    }
    free_mesh(&now);
    const mica_status s = mica_step(w, 0.01);
    if (s < 0) fail_msg("%s, step after change %d: %s", name, k, mica_world_last_error(w));
    mesh after = get_mesh(w, body);
    double* x = get_positions(w, body, &after.nodes);
    double* v = malloc(sizeof(double) * 3 * (size_t)after.nodes);
    OK(w, mica_body_get_velocities(w, body, v, after.nodes, NULL));
    for (int32_t i = 0; i < 3 * after.nodes; ++i)
      if (!isfinite(x[i]) || !isfinite(v[i])) fail_msg("%s, change %d: node %d is not finite", name, k, i / 3);
    for (int32_t e = 0; e < after.tets; ++e)
      if (!(signed_volume(after.rest, &after, e) > 0)) fail_msg("%s, change %d: tet %d has no volume", name, k, e);
    const double q = smallest_quality(&after);
    if (q < q0 * (1 - 1e-12)) fail_msg("%s, change %d: the smallest quality fell from %g to %g", name, k, q0, q);
    const double now_mass = total_mass(w, body);
    if (fabs(now_mass - mass) > 1e-12 * mass) fail_msg("%s, change %d: mass %.17g kg, expected %.17g", name, k, now_mass, mass);
    free(x), free(v);
    free_mesh(&after);
  }
  int32_t nodes = 0, tets = 0;
  OK(w, mica_body_get_counts(w, body, &nodes, &tets, NULL));
  print_message("%s: %d cuts and %d removals, %d nodes and %d tets left\n", name, cuts, removals, nodes, tets);
}

static mica_world* make_world(void) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = -9.81;
  mica_world* w = NULL;
  OK(NULL, mica_world_create(&wd, &w));
  return w;
}

/* A sphere resting 2 mm into the body's top at `top`, and a grab of the nodes within 6 mm of a
 * point 1 cm beside it. */
static void press_and_grab(mica_world* w, mica_body_id body, const double top[3]) {
  mica_tool_def td = mica_tool_def_default();
  td.radius = 0.005;
  td.position[0] = top[0], td.position[1] = top[1] + 0.003, td.position[2] = top[2];
  mica_tool_id tool = 0;
  OK(w, mica_tool_create(w, &td, &tool));
  const double grab[3] = {top[0] + 0.01, top[1], top[2]};
  mica_lpc_id lpc = 0;
  OK(w, mica_lpc_grab(w, body, grab, 0.006, MICA_NULL_ID, &lpc));
}

static void test_random_cuts_through_the_cube(void** state) {
  (void)state;
  mica_world* w = make_world();
  mica_body_def bd = mica_body_def_default();
  bd.rayleigh_alpha = 2;
  const double lo[3] = {-0.05, 0, -0.05}, hi[3] = {0.05, 0.1, 0.05};
  const int32_t cells[3] = {10, 10, 10};
  mica_body_id body = 0;
  OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 5, &body));
  const double point[3] = {0, 0, 0}, normal[3] = {0, 1, 0};
  int32_t base[256], count = 0;
  OK(w, mica_body_select_nodes_by_plane(w, body, point, normal, 1e-9, 1, base, 256, &count));
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc = 0;
  OK(w, mica_add_lpc(w, body, base, count, &fixed, &lpc));
  const double top[3] = {0, 0.1, 0};
  press_and_grab(w, body, top);
  random_changes(w, body, 100, "cube");
  mica_world_destroy(w);
}

static void test_random_cuts_through_the_nidus(void** state) {
  (void)state;
  mica_world* w = make_world();
  mica_body_def bd = mica_body_def_default();
  bd.rayleigh_alpha = 2;
  mica_body_id body = 0;
  OK(w, mica_body_create_from_file(w, &bd, NIDUS, &body));
  double lo[3], hi[3], top[3];
  OK(w, press_scene_top(w, body, lo, hi, top));
  /* Held by its lowest fifth, as in the benchmarks. */
  const double cut[3] = {0, lo[1] + 0.2 * (hi[1] - lo[1]), 0}, normal[3] = {0, 1, 0};
  int32_t held[4096], count = 0;
  OK(w, mica_body_select_nodes_by_plane(w, body, cut, normal, 0, 1, held, 4096, &count));
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc = 0;
  OK(w, mica_add_lpc(w, body, held, count, &fixed, &lpc));
  press_and_grab(w, body, top);
  random_changes(w, body, 100, "nidus");
  mica_world_destroy(w);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_random_cuts_through_the_cube),
      cmocka_unit_test(test_random_cuts_through_the_nidus),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
