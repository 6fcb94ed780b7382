/* SPDX-License-Identifier: Apache-2.0 */
/* Blades through the C API (mica_tool_def.blade, mica_body_def.cutting_resistance).
 *
 * - A blade pressed into a block: the tissue bears it until the force across the edge reaches
 *   the cutting resistance times the edge in the tissue, then parts (the topology changes) and the
 *   force falls; twice the resistance, about twice the force. A blade never cuts a body whose
 *   resistance it cannot reach; a capsule that is not a blade never cuts.
 * - Pushed on, the blade cuts the block through: two pieces, the mass kept.
 * - A recording of blade cuts replays bit for bit (the cuts are the steps').
 * - Bad input: a blade that is not a capsule, a resistance that is negative or not finite. */
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

#define H 0.01       /* s */
#define SPEED 0.01   /* m/s, the blade's descent */
#define WIDTH 0.02   /* m, the block's extent along the blade */

/* The blade's edge along z, its plane the x-y plane: its local x (the way it cuts) is -y. */
static const double kDown[4] = {0.70710678118654752, 0, 0, -0.70710678118654752};

typedef struct {
  mica_world* w;
  mica_body_id block;
  mica_tool_id blade;
  double y;  /* the blade's height */
} scene;

/* A block 4 x 2 x 2 cm held at its two ends (x = 0, x = 0.04), a blade along z above the middle
 * of its top. */
static scene make_scene(double resistance, int32_t blade, const char* record) {
  scene s;
  mica_world_def wd = mica_world_def_default();
  OK(NULL, mica_world_create(&wd, &s.w));
  if (record) OK(s.w, mica_world_record_start(s.w, record));
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = 5e4;
  bd.cutting_resistance = resistance;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.04, 0.02, WIDTH};
  const int32_t cells[3] = {8, 4, 4};
  OK(s.w, mica_body_create_box(s.w, &bd, lo, hi, cells, 5, &s.block));
  const double left[3] = {0, 0, 0}, right[3] = {0.04, 0, 0}, normal[3] = {1, 0, 0}, inward[3] = {-1, 0, 0};
  int32_t nodes[128], count = 0, more = 0;
  OK(s.w, mica_body_select_nodes_by_plane(s.w, s.block, left, normal, 1e-9, 1, nodes, 128, &count));
  OK(s.w, mica_body_select_nodes_by_plane(s.w, s.block, right, inward, 1e-9, 1, nodes + count, 128 - count, &more));
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id ends = 0;
  OK(s.w, mica_add_lpc(s.w, s.block, nodes, count + more, &fixed, &ends));
  mica_tool_def td = mica_tool_def_default();
  td.shape = MICA_TOOL_CAPSULE;
  td.radius = 0.0005;
  td.half_length = 0.03; /* longer than the block is wide */
  s.y = 0.02 + td.radius + 0.0002;
  const double position[3] = {0.0201, s.y, 0.01};
  memcpy(td.position, position, sizeof position);
  memcpy(td.orientation, kDown, sizeof kDown);
  td.blade = blade;
  OK(s.w, mica_tool_create(s.w, &td, &s.blade));
  return s;
}

/* Lowers the blade one step; returns the force on it along y. */
static double lower(scene* s) {
  s->y -= SPEED * H;
  const double position[3] = {0.0201, s->y, 0.01};
  OK(s->w, mica_tool_set_pose(s->w, s->blade, position, kDown));
  OK(s->w, mica_step(s->w, H));
  double force[3];
  OK(s->w, mica_tool_get_force(s->w, s->blade, force, NULL, NULL));
  return force[1];
}

static uint64_t version(const scene* s) {
  uint64_t v = 0;
  OK(s->w, mica_body_get_topology_version(s->w, s->block, &v));
  return v;
}

/* The force on the blade at the step that first cut, and the next step's; -1 if none in `steps`. */
static double force_at_first_cut(scene* s, int steps, double* after) {
  for (int k = 0; k < steps; ++k) {
    const double f = lower(s);
    if (version(s) > 0) {
      *after = lower(s);
      return f;
    }
  }
  return -1;
}

static void test_the_tissue_bears_then_parts(void** state) {
  (void)state;
  const double r = 50; /* N/m */
  scene s = make_scene(r, 1, NULL);
  double after = 0;
  const double f = force_at_first_cut(&s, 400, &after);
  /* The edge in contact is the block's width: the force across it reached r * WIDTH, and not
   * much more (one step's rise at most). */
  if (!(f >= r * WIDTH && f < 1.3 * r * WIDTH)) fail_msg("the tissue parted at %g N, expected %g N", f, r * WIDTH);
  if (!(after < f)) fail_msg("the force went from %g N to %g N when the tissue parted", f, after);

  scene t = make_scene(2 * r, 1, NULL);
  const double f2 = force_at_first_cut(&t, 600, &after);
  if (!(fabs(f2 / f - 2) < 0.3)) fail_msg("twice the resistance parts at %g N against %g N", f2, f);
  mica_world_destroy(s.w);
  mica_world_destroy(t.w);
}

static void test_what_does_not_cut(void** state) {
  (void)state;
  scene tough = make_scene(1e6, 1, NULL), dull = make_scene(50, 0, NULL);
  for (int k = 0; k < 300; ++k) {
    lower(&tough);
    lower(&dull);
  }
  assert_true(version(&tough) == 0);
  assert_true(version(&dull) == 0);
  mica_world_destroy(tough.w);
  mica_world_destroy(dull.w);
}

static void test_a_blade_cuts_through(void** state) {
  (void)state;
  scene s = make_scene(20, 1, NULL);
  const double mass = total_mass(s.w, s.block);
  while (s.y > -0.002) lower(&s);
  mesh m = get_mesh(s.w, s.block);
  int32_t* piece = malloc(sizeof(int32_t) * (size_t)m.nodes);
  const int32_t pieces = find_pieces(&m, piece);
  if (pieces != 2) fail_msg("the blade left %d pieces (topology version %llu)", pieces, (unsigned long long)version(&s));
  for (int32_t e = 0; e < m.tets; ++e) assert_true(signed_volume(m.rest, &m, e) > 0);
  assert_true(fabs(total_mass(s.w, s.block) - mass) <= 1e-12 * mass);
  free(piece);
  free_mesh(&m);
  mica_world_destroy(s.w);
}

static void test_blade_cuts_replay_bit_for_bit(void** state) {
  (void)state;
  const char* path = "test_blade.micarec";
  scene s = make_scene(20, 1, path);
  int steps = 0;
  while (version(&s) < 3 && steps < 600) {
    lower(&s);
    ++steps;
  }
  assert_true(version(&s) >= 3);
  OK(s.w, mica_world_record_stop(s.w));
  int32_t n = 0;
  double* x = get_positions(s.w, s.block, &n);

  mica_replay* r = NULL;
  OK(NULL, mica_replay_open(path, &r));
  mica_world* replayed = mica_replay_world(r);
  int32_t stepped = 1;
  while (stepped) OK(replayed, mica_replay_step(r, &stepped));
  int32_t n2 = 0;
  double* x2 = get_positions(replayed, s.block, &n2);
  assert_int_equal(n, n2);
  assert_memory_equal(x, x2, sizeof(double) * 3 * (size_t)n);
  mica_replay_close(r);
  remove(path);
  free(x), free(x2);
  mica_world_destroy(s.w);
}

static void test_bad_input(void** state) {
  (void)state;
  scene s = make_scene(20, 1, NULL);
  mica_tool_def td = mica_tool_def_default();
  td.blade = 1; /* a sphere */
  mica_tool_id tool = 0;
  assert_int_equal(mica_tool_create(s.w, &td, &tool), MICA_ERR_INVALID_ARGUMENT);
  assert_non_null(strstr(mica_world_last_error(s.w), "not a capsule"));
  int32_t tets = 0;
  OK(s.w, mica_body_get_counts(s.w, s.block, NULL, &tets, NULL));
  double* r = calloc((size_t)tets, sizeof(double));
  r[7] = -1;
  assert_int_equal(mica_body_set_cutting_resistance(s.w, s.block, r, tets), MICA_ERR_INVALID_ARGUMENT);
  assert_non_null(strstr(mica_world_last_error(s.w), "tet 7 is -1"));
  r[7] = NAN;
  assert_int_equal(mica_body_set_cutting_resistance(s.w, s.block, r, tets), MICA_ERR_INVALID_ARGUMENT);
  assert_int_equal(mica_body_set_cutting_resistance(s.w, s.block, r, tets - 1), MICA_ERR_INVALID_ARGUMENT);
  r[7] = 0;
  OK(s.w, mica_body_set_cutting_resistance(s.w, s.block, r, tets));
  mica_body_def bd = mica_body_def_default();
  bd.cutting_resistance = INFINITY;
  const double lo[3] = {1, 1, 1}, hi[3] = {1.01, 1.01, 1.01};
  const int32_t cells[3] = {1, 1, 1};
  mica_body_id other = 0;
  assert_int_equal(mica_body_create_box(s.w, &bd, lo, hi, cells, 5, &other), MICA_ERR_INVALID_ARGUMENT);
  assert_non_null(strstr(mica_world_last_error(s.w), "def->cutting_resistance"));
  free(r);
  mica_world_destroy(s.w);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_the_tissue_bears_then_parts),
      cmocka_unit_test(test_what_does_not_cut),
      cmocka_unit_test(test_a_blade_cuts_through),
      cmocka_unit_test(test_blade_cuts_replay_bit_for_bit),
      cmocka_unit_test(test_bad_input),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
