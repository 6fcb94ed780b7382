/* SPDX-License-Identifier: Apache-2.0 */
/* Embedded meshes through the C ABI: a fine surface over the nidus follows it under a pressing
 * tool, its normals within a degree of the normals of its moved triangles; vertices outside the
 * body are projected within the radius and unbound beyond it (a warning naming them, and left as
 * they were by the update); a vertex that is not finite is refused by index; a destroyed body or
 * embedding is detected; the def and the arguments are checked; mica_world_get_ids lists the live
 * embeddings; a resection under the mesh keeps the vertices of kept tets to the bit and binds the
 * others again. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include <mica/mica.h>

#include "capi_ok.h"
#include "fine_surface.h"
#include "press_scene.h"

#define NIDUS MICA_TEST_DATA_DIR "/../../data/nidus/nidus.msh"

/* The area-weighted normals of `triangles` at xyz, computed here the plain way. */
static void plain_normals(const double* xyz, int32_t n, const int32_t* triangles, int32_t t, double* normals) {
  memset(normals, 0, sizeof(double) * 3 * (size_t)n);
  for (int32_t f = 0; f < t; ++f) {
    const double *a = xyz + 3 * triangles[3 * f], *b = xyz + 3 * triangles[3 * f + 1], *c = xyz + 3 * triangles[3 * f + 2];
    double face[3];
    face[0] = (b[1] - a[1]) * (c[2] - a[2]) - (b[2] - a[2]) * (c[1] - a[1]);
    face[1] = (b[2] - a[2]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[2] - a[2]);
    face[2] = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    for (int k = 0; k < 3; ++k)
      for (int a2 = 0; a2 < 3; ++a2) normals[3 * triangles[3 * f + k] + a2] += face[a2];
  }
  for (int32_t i = 0; i < n; ++i) {
    double* v = normals + 3 * i;
    const double length = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int a = 0; a < 3; ++a) v[a] /= length;
  }
}

static double angle_degrees(const double* a, const double* b) {
  const double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  return atan2(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]), dot) * 180 / 3.14159265358979323846;
}

static double distance(const double* a, const double* b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

static void test_nidus_under_a_tool(void** state) {
  (void)state;
  const press_scene_def def = press_scene_nidus_touch_def(NIDUS, 0.1, 0.02);
  press_scene s;
  if (press_scene_create(&def, &s) != MICA_OK) fail_msg("%s", s.error);
  fine_surface fine;
  OK(s.world, fine_surface_of_body(s.world, s.body, 4, &fine));
  const int32_t n = fine.vertex_count;
  mica_embedding_def ed = mica_embedding_def_default();
  mica_embedding_id e = MICA_NULL_ID;
  OK(s.world, mica_embedding_create(s.world, s.body, &ed, fine.xyz, n, fine.triangles, fine.triangle_count, &e));
  int32_t count = 0, inside = 0, projected = 0, unbound = 0;
  OK(s.world, mica_embedding_get_counts(s.world, e, &count, &inside, &projected, &unbound));
  assert_int_equal(count, n);
  assert_int_equal(inside, n); /* on the surface: inside up to round-off */

  double* xyz = malloc(sizeof(double) * 3 * (size_t)n);
  double* normals = malloc(sizeof(double) * 3 * (size_t)n);
  double* expected = malloc(sizeof(double) * 3 * (size_t)n);
  OK(s.world, mica_embedding_update(s.world, e, xyz, normals));
  for (int32_t i = 0; i < n; ++i)
    if (distance(xyz + 3 * i, fine.xyz + 3 * i) > 1e-12) fail_msg("vertex %d moved at rest", i);

  double moved = 0, worst = 0;
  for (int32_t k = 1; k <= s.steps; ++k) {
    OK(s.world, press_scene_step(&s, k, NULL, NULL));
    OK(s.world, mica_embedding_update(s.world, e, xyz, normals));
    plain_normals(xyz, n, fine.triangles, fine.triangle_count, expected);
    for (int32_t i = 0; i < n; ++i) {
      const double a = angle_degrees(normals + 3 * i, expected + 3 * i);
      worst = a > worst ? a : worst;
    }
  }
  for (int32_t i = 0; i < n; ++i) {
    const double d = distance(xyz + 3 * i, fine.xyz + 3 * i);
    moved = d > moved ? d : moved;
  }
  print_message("nidus: %d vertices, the deepest moved %.2f mm, worst normal %.2g degrees\n", n, moved * 1e3, worst);
  assert_true(moved > 1e-3); /* the tool pressed the mesh in */
  assert_true(worst < 1.0);
  OK(s.world, mica_embedding_destroy(s.world, e));
  free(xyz);
  free(normals);
  free(expected);
  fine_surface_free(&fine);
  press_scene_destroy(&s);
}

/* The cube [0, 0.1]^3 of 4^3 cells. */
static mica_world* cube(mica_body_id* body) {
  mica_world_def wd = mica_world_def_default();
  mica_world* w = NULL;
  OK(NULL, mica_world_create(&wd, &w));
  const mica_body_def bd = mica_body_def_default();
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.1, 0.1};
  const int32_t cells[3] = {4, 4, 4};
  OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 5, body));
  return w;
}

static void test_outside_vertices_are_projected_or_reported(void** state) {
  (void)state;
  mica_body_id body;
  mica_world* w = cube(&body);
  /* inside; 0.5 mm above the top (projected, radius 1 mm); 2 mm beside it (unbound) */
  const double xyz[9] = {0.05, 0.05, 0.05, 0.03, 0.1005, 0.07, 0.05, 0.05, -0.002};
  const mica_embedding_def def = mica_embedding_def_default();
  assert_true(def.radius == 0.001);
  mica_embedding_id e = MICA_NULL_ID;
  assert_int_equal(mica_embedding_create(w, body, &def, xyz, 3, NULL, 0, &e), MICA_WARN_UNBOUND_VERTICES);
  assert_true(e != MICA_NULL_ID);
  const char* message = mica_world_last_error(w);
  if (!strstr(message, "1 of 3 vertices") || !strstr(message, "vertex 2")) fail_msg("message: %s", message);
  int32_t kinds[3] = {-1, -1, -1}, count = 0;
  OK(w, mica_embedding_get_kinds(w, e, kinds, 3, &count));
  assert_int_equal(count, 3);
  assert_int_equal(kinds[0], MICA_EMBED_INSIDE);
  assert_int_equal(kinds[1], MICA_EMBED_PROJECTED);
  assert_int_equal(kinds[2], MICA_EMBED_UNBOUND);
  assert_int_equal(mica_embedding_get_kinds(w, e, kinds, 2, &count), MICA_ERR_BUFFER_TOO_SMALL);

  /* The body moved up 1 cm: the bound vertices follow, the unbound one keeps the host's value. */
  double x[3 * 125 * 2];
  int32_t nodes = 0;
  OK(w, mica_body_get_counts(w, body, &nodes, NULL, NULL));
  assert_true(nodes <= 250);
  OK(w, mica_body_get_rest_positions(w, body, x, nodes, NULL));
  for (int32_t i = 0; i < nodes; ++i) x[3 * i + 1] += 0.01;
  OK(w, mica_body_set_positions(w, body, x, nodes));
  double out[9] = {7, 7, 7, 7, 7, 7, 7, 7, 7};
  OK(w, mica_embedding_update(w, e, out, NULL));
  for (int k = 0; k < 6; ++k) assert_true(fabs(out[k] - (xyz[k] + (k % 3 == 1 ? 0.01 : 0))) < 1e-12);
  for (int k = 6; k < 9; ++k) assert_true(out[k] == 7);
  /* No triangles, so no normals. */
  double normals[9];
  assert_int_equal(mica_embedding_update(w, e, out, normals), MICA_ERR_WRONG_STATE);
  mica_world_destroy(w); /* frees the embedding with it */
}

static void test_a_vertex_not_finite_is_refused_by_index(void** state) {
  (void)state;
  mica_body_id body;
  mica_world* w = cube(&body);
  double xyz[12] = {0.05, 0.05, 0.05, 0.02, 0.02, 0.02, 0.03, 0.03, 0.03, 0.04, 0.04, 0.04};
  xyz[3 * 2 + 2] = NAN;
  const mica_embedding_def def = mica_embedding_def_default();
  mica_embedding_id e = MICA_NULL_ID;
  assert_int_equal(mica_embedding_create(w, body, &def, xyz, 4, NULL, 0, &e), MICA_ERR_INVALID_ARGUMENT);
  if (!strstr(mica_world_last_error(w), "vertex 2 is not finite")) fail_msg("message: %s", mica_world_last_error(w));
  assert_true(e == MICA_NULL_ID);
  xyz[3 * 2 + 2] = 0.03;
  const int32_t bad[3] = {0, 1, 4};
  assert_int_equal(mica_embedding_create(w, body, &def, xyz, 4, bad, 1, &e), MICA_ERR_OUT_OF_RANGE);
  if (!strstr(mica_world_last_error(w), "triangle 0 refers to vertex 4")) fail_msg("message: %s", mica_world_last_error(w));
  mica_world_destroy(w);
}

static void test_a_destroyed_body_or_embedding_is_detected(void** state) {
  (void)state;
  mica_body_id body;
  mica_world* w = cube(&body);
  const double xyz[3] = {0.05, 0.05, 0.05};
  const mica_embedding_def def = mica_embedding_def_default();
  mica_embedding_id e = MICA_NULL_ID;
  OK(w, mica_embedding_create(w, body, &def, xyz, 1, NULL, 0, &e));
  double out[3];
  OK(w, mica_embedding_update(w, e, out, NULL));
  OK(w, mica_body_destroy(w, body));
  assert_int_equal(mica_embedding_update(w, e, out, NULL), MICA_ERR_STALE_ID);
  if (!strstr(mica_world_last_error(w), "embedding's body")) fail_msg("message: %s", mica_world_last_error(w));
  assert_int_equal(mica_embedding_create(w, body, &def, xyz, 1, NULL, 0, &e), MICA_ERR_STALE_ID);
  OK(w, mica_embedding_destroy(w, e));
  assert_int_equal(mica_embedding_update(w, e, out, NULL), MICA_ERR_STALE_ID);
  assert_int_equal(mica_embedding_destroy(w, e), MICA_ERR_STALE_ID);
  assert_int_equal(mica_embedding_get_counts(w, body, NULL, NULL, NULL, NULL), MICA_ERR_STALE_ID); /* a body's id */
  assert_int_equal(mica_embedding_get_counts(w, MICA_NULL_ID, NULL, NULL, NULL, NULL), MICA_ERR_STALE_ID);
  mica_world_destroy(w);
}

static void test_def_and_arguments(void** state) {
  (void)state;
  mica_body_id body;
  mica_world* w = cube(&body);
  const double xyz[3] = {0.05, 0.05, 0.05};
  mica_embedding_def def = mica_embedding_def_default();
  mica_embedding_id e = MICA_NULL_ID;
  assert_int_equal(mica_embedding_def_init(NULL, sizeof def), MICA_ERR_NULL_ARGUMENT);
  assert_int_equal(mica_embedding_def_init(&def, sizeof def + 8), MICA_ERR_STRUCT_SIZE);
  def.struct_size = 4;
  assert_int_equal(mica_embedding_create(w, body, &def, xyz, 1, NULL, 0, &e), MICA_ERR_STRUCT_SIZE);
  def = mica_embedding_def_default();
  def.radius = -1;
  assert_int_equal(mica_embedding_create(w, body, &def, xyz, 1, NULL, 0, &e), MICA_ERR_INVALID_ARGUMENT);
  def.radius = 0;
  assert_int_equal(mica_embedding_create(NULL, body, &def, xyz, 1, NULL, 0, &e), MICA_ERR_NULL_ARGUMENT);
  assert_int_equal(mica_embedding_create(w, body, NULL, xyz, 1, NULL, 0, &e), MICA_ERR_NULL_ARGUMENT);
  assert_int_equal(mica_embedding_create(w, body, &def, NULL, 1, NULL, 0, &e), MICA_ERR_NULL_ARGUMENT);
  assert_int_equal(mica_embedding_create(w, body, &def, xyz, 1, NULL, 1, &e), MICA_ERR_NULL_ARGUMENT);
  assert_int_equal(mica_embedding_create(w, body, &def, xyz, 1, NULL, 0, NULL), MICA_ERR_NULL_ARGUMENT);
  assert_int_equal(mica_embedding_create(w, body, &def, xyz, 0, NULL, 0, &e), MICA_ERR_INVALID_ARGUMENT);
  assert_int_equal(mica_embedding_create(w, body, &def, xyz, 1, NULL, -1, &e), MICA_ERR_INVALID_ARGUMENT);
  OK(w, mica_embedding_create(w, body, &def, xyz, 1, NULL, 0, &e));
  assert_int_equal(mica_embedding_update(w, e, NULL, NULL), MICA_ERR_NULL_ARGUMENT);
  assert_int_equal(mica_embedding_update(NULL, e, NULL, NULL), MICA_ERR_NULL_ARGUMENT);
  const int32_t triangle[3] = {0, 0, 0};
  mica_embedding_id with_triangles = MICA_NULL_ID;
  OK(w, mica_embedding_create(w, body, &def, xyz, 1, triangle, 1, &with_triangles));
  double both[6];
  assert_int_equal(mica_embedding_update(w, with_triangles, both, both + 2), MICA_ERR_INVALID_ARGUMENT);
  OK(w, mica_embedding_update(w, with_triangles, both, both + 3));
  assert_true(both[3] == 0 && both[4] == 0 && both[5] == 0); /* a triangle without area: no normal */
  assert_int_equal(mica_embedding_get_kinds(w, e, NULL, 0, NULL), MICA_ERR_NULL_ARGUMENT);
  mica_world_destroy(w);
}

/* MICA_OBJECT_EMBEDDING: the live embeddings in creation order, a destroyed one gone, and only
 * embeddings (no body among them, no embedding among the bodies). */
static void test_ids_list_the_embeddings(void** state) {
  (void)state;
  mica_body_id body;
  mica_world* w = cube(&body);
  const double xyz[3] = {0.05, 0.05, 0.05};
  const mica_embedding_def def = mica_embedding_def_default();
  mica_embedding_id e[3];
  uint64_t ids[4];
  int32_t count = -1;
  OK(w, mica_world_get_ids(w, MICA_OBJECT_EMBEDDING, NULL, 0, &count));
  assert_int_equal(count, 0);
  for (int k = 0; k < 3; ++k) OK(w, mica_embedding_create(w, body, &def, xyz, 1, NULL, 0, &e[k]));
  OK(w, mica_world_get_ids(w, MICA_OBJECT_EMBEDDING, ids, 4, &count));
  assert_int_equal(count, 3);
  for (int k = 0; k < 3; ++k) assert_true(ids[k] == e[k]);
  assert_int_equal(mica_world_get_ids(w, MICA_OBJECT_EMBEDDING, ids, 2, &count), MICA_ERR_BUFFER_TOO_SMALL);
  assert_int_equal(count, 3);
  OK(w, mica_embedding_destroy(w, e[1]));
  OK(w, mica_world_get_ids(w, MICA_OBJECT_EMBEDDING, ids, 4, &count));
  assert_int_equal(count, 2);
  assert_true(ids[0] == e[0] && ids[1] == e[2]);
  OK(w, mica_world_get_ids(w, MICA_OBJECT_BODY, ids, 4, &count));
  assert_int_equal(count, 1);
  assert_true(ids[0] == body);
  assert_int_equal(mica_world_get_ids(w, MICA_OBJECT_EMBEDDING + 1, ids, 4, &count), MICA_ERR_INVALID_ARGUMENT);
  mica_world_destroy(w);
}


/* Resection under an embedded mesh: the fine surface of the cube [0, 0.1]^3 and points inside it;
 * the cells with x > 0.075 removed. Vertices with x < 0.05 are in kept tets: placed as before, to
 * the bit. Those in the removed cells are bound again: on the new face (x = 0.075) inside a kept tet,
 * deep in the removed part (x > 0.08) more than the radius from what is left, unbound, left as they
 * were, and the call warns. */
static void test_removal_keeps_the_kept_and_rebinds_the_rest(void** state) {
  (void)state;
  mica_body_id body;
  mica_world* w = cube(&body);
  fine_surface fine;
  OK(w, fine_surface_of_body(w, body, 3, &fine));
  const int32_t n = fine.vertex_count;
  int32_t nodes = 0, tet_count = 0;
  OK(w, mica_body_get_counts(w, body, &nodes, &tet_count, NULL));
  /* A bend, so that each vertex depends on its own tet. */
  double* x = malloc(sizeof(double) * 3 * (size_t)nodes);
  OK(w, mica_body_get_rest_positions(w, body, x, nodes, NULL));
  for (int32_t i = 0; i < nodes; ++i) x[3 * i + 1] += 0.3 * x[3 * i] * x[3 * i] + 0.1 * x[3 * i + 2] * x[3 * i];
  OK(w, mica_body_set_positions(w, body, x, nodes));
  const mica_embedding_def ed = mica_embedding_def_default();
  mica_embedding_id e = MICA_NULL_ID;
  OK(w, mica_embedding_create(w, body, &ed, fine.xyz, n, fine.triangles, fine.triangle_count, &e));
  double* before = malloc(sizeof(double) * 3 * (size_t)n);
  double* after = malloc(sizeof(double) * 3 * (size_t)n);
  double* normals = malloc(sizeof(double) * 3 * (size_t)n);
  OK(w, mica_embedding_update(w, e, before, normals));
  memcpy(after, before, sizeof(double) * 3 * (size_t)n);

  /* The tets whose centroid has x > 0.075. */
  double* rest = malloc(sizeof(double) * 3 * (size_t)nodes);
  int32_t* tets = malloc(sizeof(int32_t) * 4 * (size_t)tet_count);
  int32_t* removed = malloc(sizeof(int32_t) * (size_t)tet_count);
  OK(w, mica_body_get_rest_positions(w, body, rest, nodes, NULL));
  OK(w, mica_body_get_tets(w, body, tets, tet_count, NULL));
  int32_t count = 0;
  for (int32_t t = 0; t < tet_count; ++t) {
    double cx = 0;
    for (int k = 0; k < 4; ++k) cx += rest[3 * tets[4 * t + k]] / 4;
    if (cx > 0.075) removed[count++] = t;
  }
  assert_int_equal(mica_body_remove_tets(w, body, removed, count, NULL), MICA_WARN_UNBOUND_VERTICES);
  const char* message = mica_world_last_error(w);
  if (!strstr(message, "mica_body_remove_tets") || !strstr(message, "unbound")) fail_msg("message: %s", message);
  OK(w, mica_embedding_update(w, e, after, normals));
  int32_t* kinds = malloc(sizeof(int32_t) * (size_t)n);
  OK(w, mica_embedding_get_kinds(w, e, kinds, n, NULL));
  int32_t kept = 0, deep = 0, counted[3] = {0, 0, 0};
  for (int32_t i = 0; i < n; ++i) {
    const double vx = fine.xyz[3 * i];
    ++counted[kinds[i]];
    if (vx < 0.05 - 1e-9) {
      ++kept;
      assert_int_equal(kinds[i], MICA_EMBED_INSIDE);
      if (memcmp(after + 3 * i, before + 3 * i, 3 * sizeof(double)) != 0) fail_msg("kept vertex %d moved", i);
    } else if (fabs(vx - 0.075) < 1e-9) {
      assert_int_equal(kinds[i], MICA_EMBED_INSIDE); /* on the new face: found in a kept tet */
    } else if (vx > 0.08) {
      ++deep;
      assert_int_equal(kinds[i], MICA_EMBED_UNBOUND);
      if (memcmp(after + 3 * i, before + 3 * i, 3 * sizeof(double)) != 0) fail_msg("unbound vertex %d was written", i);
    }
  }
  int32_t inside = 0, projected = 0, unbound = 0;
  OK(w, mica_embedding_get_counts(w, e, NULL, &inside, &projected, &unbound));
  assert_int_equal(inside, counted[MICA_EMBED_INSIDE]);
  assert_int_equal(projected, counted[MICA_EMBED_PROJECTED]);
  assert_int_equal(unbound, counted[MICA_EMBED_UNBOUND]);
  print_message("removal: %d of %d vertices kept to the bit, %d deep in the removed part unbound (%d unbound, %d projected)\n",
                kept, n, deep, unbound, projected);
  assert_true(kept > n / 3 && deep > 0);
  /* And the body steps on with the mesh on it. */
  OK(w, mica_step(w, 0.01));
  OK(w, mica_embedding_update(w, e, after, normals));
  free(x);
  free(before);
  free(after);
  free(normals);
  free(rest);
  free(tets);
  free(removed);
  free(kinds);
  fine_surface_free(&fine);
  mica_world_destroy(w);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_nidus_under_a_tool),
      cmocka_unit_test(test_outside_vertices_are_projected_or_reported),
      cmocka_unit_test(test_a_vertex_not_finite_is_refused_by_index),
      cmocka_unit_test(test_a_destroyed_body_or_embedding_is_detected),
      cmocka_unit_test(test_def_and_arguments),
      cmocka_unit_test(test_ids_list_the_embeddings),
      cmocka_unit_test(test_removal_keeps_the_kept_and_rebinds_the_rest),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
