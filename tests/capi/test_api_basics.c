/* SPDX-License-Identifier: Apache-2.0 */
/* The happy paths through the C ABI, each checked against physics or against an independent
 * count, never against the library's own output alone:
 * - versions and defaults as documented in mica.h;
 * - box bodies: the generator's counts, the size-query protocol, rest = current before a step,
 *   the zero-copy view, a closed outward surface (divergence theorem gives the box volume);
 * - node selection by box and by plane picks exactly a face;
 * - free fall matches the closed-form backward-Euler drop; constraints hold, slide, move at the
 *   prescribed velocity, and let go when removed; destroying a body stales its constraints;
 * - VTK output; statistics; PCG agrees with the direct solver, and reports a capped solve.
 * Files go to a fresh directory under /tmp, removed at the end. */
#define _POSIX_C_SOURCE 200809L
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <mica/mica.h>

#include "press_scene.h"

/* ------------------------------------------------------------------------------------------ */
/* Helpers                                                                                     */

#define REQUIRE_OK(world, call)                                                                      \
  do {                                                                                               \
    const mica_status s_ = (call);                                                                   \
    if (s_ != MICA_OK) {                                                                             \
      print_error("%s:%d: %s returned %d (%s)\n  last error: %s\n", __FILE__, __LINE__, #call, s_,   \
                  mica_status_string(s_), mica_world_last_error(world));                             \
      _fail(__FILE__, __LINE__);                                                                     \
    }                                                                                                \
  } while (0)

/* |a - b| <= tol, with both values in the message. */
#define ASSERT_NEAR(a, b, tol)                                                                       \
  do {                                                                                               \
    const double a_ = (a), b_ = (b), t_ = (tol);                                                     \
    if (!(fabs(a_ - b_) <= t_)) {                                                                    \
      print_error("%s:%d: %s = %.17g, %s = %.17g, |difference| %.3g > %.3g\n", __FILE__, __LINE__, #a, a_, \
                  #b, b_, fabs(a_ - b_), t_);                                                        \
      _fail(__FILE__, __LINE__);                                                                     \
    }                                                                                                \
  } while (0)

#define ASSERT_REL(a, b, rel) ASSERT_NEAR((a), (b), (rel) * fabs(b))

static char g_dir[256];

static int group_setup(void** state) {
  (void)state;
  strcpy(g_dir, "/tmp/mica-capi-basics-XXXXXX");
  return mkdtemp(g_dir) ? 0 : -1;
}

static const char* const kFiles[] = {"body.vtk", "world.vtk", NULL};

static int group_teardown(void** state) {
  (void)state;
  char path[512];
  for (const char* const* f = kFiles; *f; ++f) {
    snprintf(path, sizeof path, "%s/%s", g_dir, *f);
    unlink(path);
  }
  rmdir(g_dir);
  return 0;
}

static mica_world* make_world(double gx, double gy, double gz, int32_t solver) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[0] = gx;
  wd.gravity[1] = gy;
  wd.gravity[2] = gz;
  wd.solver = solver;
  mica_world* w = NULL;
  if (mica_world_create(&wd, &w) != MICA_OK) {
    print_error("mica_world_create: %s\n", mica_world_last_error(NULL));
    return NULL;
  }
  return w;
}

static int32_t node_count(const mica_world* w, mica_body_id b) {
  int32_t n = -1;
  if (mica_body_get_counts(w, b, &n, NULL, NULL) != MICA_OK) return -1;
  return n;
}

/* Newly allocated copies of the body's arrays (3 doubles per node). */
typedef mica_status (*node_getter)(const mica_world*, mica_body_id, double*, int32_t, int32_t*);
static double* node_array(node_getter get, const mica_world* w, mica_body_id b) {
  const int32_t n = node_count(w, b);
  double* x = malloc(sizeof(double) * 3 * (size_t)n);
  if (get(w, b, x, n, NULL) != MICA_OK) {
    free(x);
    return NULL;
  }
  return x;
}
static double* positions(const mica_world* w, mica_body_id b) { return node_array(mica_body_get_positions, w, b); }
static double* velocities(const mica_world* w, mica_body_id b) { return node_array(mica_body_get_velocities, w, b); }
static double* rest_positions(const mica_world* w, mica_body_id b) {
  return node_array(mica_body_get_rest_positions, w, b);
}

/* The nodes on the plane through `point` with outward normal `normal` (rest positions):
 * (p - point) . normal <= tol. Allocated; *count set. */
static int32_t* select_plane(const mica_world* w, mica_body_id b, const double point[3], const double normal[3],
                             int32_t* count) {
  *count = 0;
  if (mica_body_select_nodes_by_plane(w, b, point, normal, 1e-9, 1, NULL, 0, count) != MICA_OK) return NULL;
  int32_t* nodes = malloc(sizeof(int32_t) * (size_t)(*count > 0 ? *count : 1));
  if (mica_body_select_nodes_by_plane(w, b, point, normal, 1e-9, 1, nodes, *count, count) != MICA_OK) {
    free(nodes);
    return NULL;
  }
  return nodes;
}

static mica_world_stats stats_of(const mica_world* w) {
  mica_world_stats s;
  memset(&s, 0, sizeof s);
  s.struct_size = sizeof s;
  if (mica_world_get_stats(w, &s) != MICA_OK) s.step_count = -1;
  return s;
}

/* ------------------------------------------------------------------------------------------ */
/* Version and defaults                                                                        */

static void test_version(void** state) {
  (void)state;
  assert_int_equal(mica_version(), MICA_VERSION_NUMBER);
  assert_int_equal(MICA_VERSION_NUMBER, MICA_VERSION_MAJOR * 10000 + MICA_VERSION_MINOR * 100 + MICA_VERSION_PATCH);
}

static void test_defaults(void** state) {
  (void)state;
  const mica_world_def wd = mica_world_def_default();
  assert_int_equal(wd.struct_size, sizeof(mica_world_def));
  assert_int_equal(wd.header_version, MICA_VERSION_NUMBER);
  assert_true(wd.gravity[0] == 0 && wd.gravity[1] == -9.81 && wd.gravity[2] == 0);
  /* Since 0.5 the default world is the haptic one: MICA with the factored sweep. */
  assert_int_equal(wd.solver, MICA_SOLVER_MICA);
  assert_int_equal(wd.mica_sweep, MICA_SWEEP_FACTORED);
  assert_int_equal(wd.max_iterations, 200);
  assert_true(wd.tolerance == 1e-8);
  assert_int_equal(wd.plan_all_stages, 0);
  assert_int_equal(wd.reserved0, 0);
  assert_null(wd.log);
  assert_null(wd.log_user);

  const mica_body_def bd = mica_body_def_default();
  assert_int_equal(bd.struct_size, sizeof(mica_body_def));
  assert_int_equal(bd.model, MICA_MODEL_COROTATIONAL);
  assert_int_equal(bd.mass, MICA_MASS_CONSISTENT);
  assert_int_equal(bd.is_static, 0);
  assert_true(bd.youngs_modulus == 1e4);
  assert_true(bd.poisson_ratio == 0.3);
  assert_true(bd.density == 1000);
  assert_true(bd.rayleigh_alpha == 0 && bd.rayleigh_beta == 0);
  for (int k = 0; k < 3; ++k) assert_true(bd.translation[k] == 0 && bd.velocity[k] == 0);

  const mica_lpc_def ld = mica_lpc_def_default();
  assert_int_equal(ld.struct_size, sizeof(mica_lpc_def));
  assert_int_equal(ld.kind, MICA_LPC_FIXED);
  for (int k = 0; k < 3; ++k) assert_true(ld.velocity[k] == 0);

  /* The FFI entry point gives the same values. */
  mica_world_def fw;
  memset(&fw, 0xff, sizeof fw);
  assert_int_equal(mica_world_def_init(&fw, (uint32_t)sizeof fw, MICA_VERSION_NUMBER), MICA_OK);
  assert_int_equal(fw.struct_size, sizeof fw);
  assert_int_equal(fw.header_version, MICA_VERSION_NUMBER);
  assert_true(fw.gravity[1] == -9.81 && fw.tolerance == 1e-8 && fw.max_iterations == 200);
  assert_int_equal(fw.solver, MICA_SOLVER_MICA);
  assert_int_equal(fw.mica_sweep, MICA_SWEEP_FACTORED);
  assert_null(fw.log);
  mica_body_def fb;
  memset(&fb, 0xff, sizeof fb);
  assert_int_equal(mica_body_def_init(&fb, (uint32_t)sizeof fb), MICA_OK);
  assert_true(fb.youngs_modulus == 1e4 && fb.poisson_ratio == 0.3 && fb.density == 1000 && fb.is_static == 0);
  mica_lpc_def fl;
  memset(&fl, 0xff, sizeof fl);
  assert_int_equal(mica_lpc_def_init(&fl, (uint32_t)sizeof fl), MICA_OK);
  assert_int_equal(fl.kind, MICA_LPC_FIXED);
  assert_true(fl.velocity[0] == 0 && fl.velocity[1] == 0 && fl.velocity[2] == 0);

  /* The default world is created and steps an empty scene. */
  mica_world* w = NULL;
  assert_int_equal(mica_world_create(&wd, &w), MICA_OK);
  assert_non_null(w);
  REQUIRE_OK(w, mica_step(w, 0.01));
  assert_string_equal(mica_world_last_error(w), "");
  assert_int_equal(stats_of(w).step_count, 1);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* Box bodies                                                                                  */

static void test_box_counts_and_readback(void** state) {
  (void)state;
  static const int32_t kCells[4][3] = {{1, 1, 1}, {3, 2, 4}, {2, 3, 1}, {5, 1, 2}};
  const double lo[3] = {-0.2, 0.1, 0.3}, hi[3] = {0.4, 0.25, 0.7};
  mica_world* w = make_world(0, -9.81, 0, MICA_SOLVER_DIRECT);
  assert_non_null(w);
  for (int c = 0; c < 4; ++c)
    for (int32_t tpc = 5; tpc <= 6; ++tpc) {
      const int32_t nx = kCells[c][0], ny = kCells[c][1], nz = kCells[c][2];
      mica_body_def bd = mica_body_def_default();
      bd.translation[0] = 1.5;
      bd.translation[2] = -0.25;
      bd.velocity[1] = 0.75;
      mica_body_id b = 0;
      REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, kCells[c], tpc, &b));
      assert_int_not_equal(b, MICA_NULL_ID);

      int32_t nodes = -1, tets = -1, tris = -1;
      REQUIRE_OK(w, mica_body_get_counts(w, b, &nodes, &tets, &tris));
      assert_int_equal(nodes, (nx + 1) * (ny + 1) * (nz + 1));
      assert_int_equal(tets, tpc * nx * ny * nz);
      assert_int_equal(tris, 4 * (nx * ny + ny * nz + nx * nz));

      /* Size query, then an exact and a larger buffer. */
      int32_t count = -1;
      REQUIRE_OK(w, mica_body_get_positions(w, b, NULL, 0, &count));
      assert_int_equal(count, nodes);
      count = -1;
      REQUIRE_OK(w, mica_body_get_surface(w, b, NULL, 0, &count));
      assert_int_equal(count, tris);
      double* x = malloc(sizeof(double) * 3 * (size_t)(nodes + 2));
      for (int32_t i = 0; i < 3 * (nodes + 2); ++i) x[i] = -999.0;
      count = -1;
      REQUIRE_OK(w, mica_body_get_positions(w, b, x, nodes + 2, &count));
      assert_int_equal(count, nodes);
      for (int32_t i = 3 * nodes; i < 3 * (nodes + 2); ++i) assert_true(x[i] == -999.0); /* only n written */
      double* x_exact = malloc(sizeof(double) * 3 * (size_t)nodes);
      REQUIRE_OK(w, mica_body_get_positions(w, b, x_exact, nodes, NULL));
      assert_memory_equal(x, x_exact, sizeof(double) * 3 * (size_t)nodes);

      /* The generator's lattice: every node on a grid point of the translated box, and the
       * translated corners present. Rest = current before any step, bitwise. */
      double* rest = rest_positions(w, b);
      assert_memory_equal(rest, x, sizeof(double) * 3 * (size_t)nodes);
      const double shift[3] = {1.5, 0, -0.25};
      int corner_lo = 0, corner_hi = 0;
      for (int32_t i = 0; i < nodes; ++i) {
        int at_lo = 1, at_hi = 1;
        for (int k = 0; k < 3; ++k) {
          const double p = x[3 * i + k] - shift[k];
          const double t = (p - lo[k]) / (hi[k] - lo[k]) * (double)kCells[c][k];
          ASSERT_NEAR(t, round(t), 1e-9);
          assert_true(t > -1e-9 && t < kCells[c][k] + 1e-9);
          at_lo = at_lo && x[3 * i + k] == lo[k] + shift[k];
          at_hi = at_hi && x[3 * i + k] == hi[k] + shift[k];
        }
        corner_lo += at_lo;
        corner_hi += at_hi;
      }
      assert_int_equal(corner_lo, 1);
      assert_int_equal(corner_hi, 1);

      /* Initial velocity of every node. */
      double* v = velocities(w, b);
      for (int32_t i = 0; i < nodes; ++i)
        assert_true(v[3 * i] == 0 && v[3 * i + 1] == 0.75 && v[3 * i + 2] == 0);

      /* The view shows the same numbers as the copy. */
      const double* view = NULL;
      int32_t view_count = -1;
      REQUIRE_OK(w, mica_body_positions_view(w, b, &view, &view_count));
      assert_non_null(view);
      assert_int_equal(view_count, nodes);
      assert_memory_equal(view, x, sizeof(double) * 3 * (size_t)nodes);

      /* Surface triangles index real nodes, each lies on a face of the box. */
      int32_t* tri = malloc(sizeof(int32_t) * 3 * (size_t)tris);
      REQUIRE_OK(w, mica_body_get_surface(w, b, tri, tris, NULL));
      for (int32_t t = 0; t < tris; ++t) {
        int on_face = 0;
        for (int k = 0; k < 3 && !on_face; ++k)
          for (int side = 0; side < 2 && !on_face; ++side) {
            const double plane = (side ? hi[k] : lo[k]) + shift[k];
            int all = 1;
            for (int a = 0; a < 3; ++a) {
              assert_in_range(tri[3 * t + a], 0, nodes - 1);
              all = all && x[3 * tri[3 * t + a] + k] == plane;
            }
            on_face = all;
          }
        assert_true(on_face);
      }
      free(tri);
      free(v);
      free(rest);
      free(x_exact);
      free(x);
      REQUIRE_OK(w, mica_body_destroy(w, b));
    }
  mica_world_destroy(w);
}

/* The view follows the state: after a step it shows the new positions. */
static void test_view_after_step(void** state) {
  (void)state;
  mica_world* w = make_world(0, -9.81, 0, MICA_SOLVER_DIRECT);
  const double lo[3] = {0, 0, 0}, hi[3] = {0.2, 0.1, 0.1};
  const int32_t cells[3] = {2, 1, 1};
  const mica_body_def bd = mica_body_def_default();
  mica_body_id b = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &b));
  REQUIRE_OK(w, mica_step(w, 0.01));
  const double* view = NULL;
  int32_t n = 0;
  REQUIRE_OK(w, mica_body_positions_view(w, b, &view, &n));
  double* x = positions(w, b);
  double* rest = rest_positions(w, b);
  assert_memory_equal(view, x, sizeof(double) * 3 * (size_t)n);
  assert_true(x[1] < rest[1]); /* it fell */
  free(x);
  free(rest);
  mica_world_destroy(w);
}

/* Sum over triangles of (1/3) c . n_area (c the centroid, n_area the area-weighted outward
 * normal) is the enclosed volume when the surface is closed and oriented outward. */
static double enclosed_volume(const double* x, const int32_t* tri, int32_t tris) {
  double volume = 0;
  for (int32_t t = 0; t < tris; ++t) {
    const double* a = x + 3 * tri[3 * t];
    const double* b = x + 3 * tri[3 * t + 1];
    const double* c = x + 3 * tri[3 * t + 2];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double n[3] = {0.5 * (u[1] * v[2] - u[2] * v[1]), 0.5 * (u[2] * v[0] - u[0] * v[2]),
                         0.5 * (u[0] * v[1] - u[1] * v[0])};
    const double centroid[3] = {(a[0] + b[0] + c[0]) / 3, (a[1] + b[1] + c[1]) / 3, (a[2] + b[2] + c[2]) / 3};
    volume += (centroid[0] * n[0] + centroid[1] * n[1] + centroid[2] * n[2]) / 3.0;
  }
  return volume;
}

/* Every directed edge appears once and its reverse once: closed, consistently oriented. */
static int edges_paired(const int32_t* tri, int32_t tris) {
  for (int32_t t = 0; t < tris; ++t)
    for (int e = 0; e < 3; ++e) {
      const int32_t p = tri[3 * t + e], q = tri[3 * t + (e + 1) % 3];
      int same = 0, reverse = 0;
      for (int32_t s = 0; s < tris; ++s)
        for (int f = 0; f < 3; ++f) {
          const int32_t r = tri[3 * s + f], u = tri[3 * s + (f + 1) % 3];
          same += r == p && u == q;
          reverse += r == q && u == p;
        }
      if (same != 1 || reverse != 1) return 0;
    }
  return 1;
}

static void test_surface_closed_and_outward(void** state) {
  (void)state;
  mica_world* w = make_world(0, -9.81, 0, MICA_SOLVER_DIRECT);
  const double lo[3] = {0.1, -0.2, 0.3}, hi[3] = {1.1, 0.3, 0.55};
  const double box_volume = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
  static const int32_t kCells[3][3] = {{1, 1, 1}, {4, 2, 3}, {3, 3, 1}};
  for (int c = 0; c < 3; ++c)
    for (int32_t tpc = 5; tpc <= 6; ++tpc) {
      const mica_body_def bd = mica_body_def_default();
      mica_body_id b = 0;
      REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, kCells[c], tpc, &b));
      int32_t tris = 0;
      REQUIRE_OK(w, mica_body_get_counts(w, b, NULL, NULL, &tris));
      int32_t* tri = malloc(sizeof(int32_t) * 3 * (size_t)tris);
      REQUIRE_OK(w, mica_body_get_surface(w, b, tri, tris, NULL));
      double* x = positions(w, b);
      ASSERT_REL(enclosed_volume(x, tri, tris), box_volume, 1e-12);
      assert_true(edges_paired(tri, tris));
      free(x);
      free(tri);
      REQUIRE_OK(w, mica_body_destroy(w, b));
    }

  /* A body from arrays: two tets sharing a face, volumes 1/6 and 1/3. */
  const double nodes[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
  const int32_t tets[8] = {0, 1, 2, 3, 1, 2, 3, 4};
  const mica_body_def bd = mica_body_def_default();
  mica_body_id b = 0;
  REQUIRE_OK(w, mica_body_create(w, &bd, nodes, 5, tets, 2, &b));
  int32_t n = 0, t = 0, tris = 0;
  REQUIRE_OK(w, mica_body_get_counts(w, b, &n, &t, &tris));
  assert_int_equal(n, 5);
  assert_int_equal(t, 2);
  assert_int_equal(tris, 6);
  int32_t tri[18];
  REQUIRE_OK(w, mica_body_get_surface(w, b, tri, 6, NULL));
  double* x = positions(w, b);
  assert_memory_equal(x, nodes, sizeof nodes); /* the arrays are copied as given */
  ASSERT_REL(enclosed_volume(x, tri, 6), 0.5, 1e-14);
  assert_true(edges_paired(tri, 6));
  free(x);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* Selection                                                                                   */

static int cmp_int(const void* a, const void* b) {
  const int32_t x = *(const int32_t*)a, y = *(const int32_t*)b;
  return (x > y) - (x < y);
}

/* The nodes whose coordinate k equals `value` exactly, found by scanning. */
static int32_t scan_face(const double* x, int32_t n, int k, double value, int32_t* out) {
  int32_t count = 0;
  for (int32_t i = 0; i < n; ++i)
    if (x[3 * i + k] == value) out[count++] = i;
  return count;
}

static void test_select_faces(void** state) {
  (void)state;
  mica_world* w = make_world(0, 0, -9.81, MICA_SOLVER_DIRECT);
  const double lo[3] = {-0.3, 0.2, 0.0}, hi[3] = {0.3, 0.5, 0.8};
  const int32_t cells[3] = {3, 2, 4};
  const mica_body_def bd = mica_body_def_default();
  mica_body_id b = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 5, &b));
  const int32_t n = node_count(w, b);
  double* x = positions(w, b);
  int32_t* expected = malloc(sizeof(int32_t) * (size_t)n);
  int32_t* got = malloc(sizeof(int32_t) * (size_t)n);
  const double eps = 1e-9;

  for (int k = 0; k < 3; ++k)
    for (int side = 0; side < 2; ++side) {
      const int32_t face_count = (k == 0   ? (cells[1] + 1) * (cells[2] + 1)
                                  : k == 1 ? (cells[0] + 1) * (cells[2] + 1)
                                           : (cells[0] + 1) * (cells[1] + 1));
      const double value = side ? hi[k] : lo[k];
      const int32_t want = scan_face(x, n, k, value, expected);
      assert_int_equal(want, face_count);

      /* A thin box around the face. */
      double blo[3], bhi[3];
      for (int a = 0; a < 3; ++a) {
        blo[a] = lo[a] - 1;
        bhi[a] = hi[a] + 1;
      }
      blo[k] = value - eps;
      bhi[k] = value + eps;
      for (int32_t use_rest = 0; use_rest <= 1; ++use_rest) {
        int32_t count = -1;
        REQUIRE_OK(w, mica_body_select_nodes_in_box(w, b, blo, bhi, use_rest, NULL, 0, &count));
        assert_int_equal(count, face_count);
        REQUIRE_OK(w, mica_body_select_nodes_in_box(w, b, blo, bhi, use_rest, got, n, &count));
        assert_int_equal(count, face_count);
        qsort(got, (size_t)count, sizeof *got, cmp_int);
        assert_memory_equal(got, expected, sizeof(int32_t) * (size_t)count);
      }
      /* The plane through the face with its normal pointing into the body: the selection
       * (p - point) . normal <= eps is the face itself and nothing inside. */
      double point[3] = {0, 0, 0}, normal[3] = {0, 0, 0};
      point[k] = value;
      normal[k] = side ? -1.0 : 1.0;
      int32_t count = -1;
      REQUIRE_OK(w, mica_body_select_nodes_by_plane(w, b, point, normal, eps, 1, NULL, 0, &count));
      assert_int_equal(count, face_count);
      REQUIRE_OK(w, mica_body_select_nodes_by_plane(w, b, point, normal, eps, 1, got, n, &count));
      qsort(got, (size_t)count, sizeof *got, cmp_int);
      assert_memory_equal(got, expected, sizeof(int32_t) * (size_t)count);
      /* A normal of any length means the same plane. */
      normal[k] *= 7.5;
      REQUIRE_OK(w, mica_body_select_nodes_by_plane(w, b, point, normal, eps, 0, NULL, 0, &count));
      assert_int_equal(count, face_count);
    }

  /* The whole body and nothing. */
  int32_t count = -1;
  REQUIRE_OK(w, mica_body_select_nodes_in_box(w, b, lo, hi, 1, NULL, 0, &count));
  assert_int_equal(count, n);
  const double far_lo[3] = {10, 10, 10}, far_hi[3] = {11, 11, 11};
  REQUIRE_OK(w, mica_body_select_nodes_in_box(w, b, far_lo, far_hi, 1, got, n, &count));
  assert_int_equal(count, 0);

  /* After the body falls, rest selection still finds the bottom face; current does not. */
  for (int s = 0; s < 5; ++s) REQUIRE_OK(w, mica_step(w, 0.01));
  double blo[3] = {lo[0] - 1, lo[1] - 1, lo[2] - eps}, bhi[3] = {hi[0] + 1, hi[1] + 1, lo[2] + eps};
  REQUIRE_OK(w, mica_body_select_nodes_in_box(w, b, blo, bhi, 1, NULL, 0, &count));
  assert_int_equal(count, (cells[0] + 1) * (cells[1] + 1));
  REQUIRE_OK(w, mica_body_select_nodes_in_box(w, b, blo, bhi, 0, NULL, 0, &count));
  assert_int_equal(count, 0);

  free(expected);
  free(got);
  free(x);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* Free fall                                                                                   */

/* Backward Euler at velocity level on a free body under gravity g: v_k = v_{k-1} + g h, so
 * v_n = g n h and x_n - x_0 = h sum_{k=1..n} v_k = g h^2 n (n + 1) / 2. A rigid translation
 * has no elastic force, so every node follows this exactly, whatever the model or mass. */
static void test_free_fall(void** state) {
  (void)state;
  const double g = -9.81, h = 0.01;
  const int steps = 10;
  const double drop = g * h * h * steps * (steps + 1) / 2.0;
  const double speed = g * steps * h;
  const int32_t models[3] = {MICA_MODEL_COROTATIONAL, MICA_MODEL_LINEAR, MICA_MODEL_NEO_HOOKEAN};
  const int32_t masses[2] = {MICA_MASS_CONSISTENT, MICA_MASS_LUMPED};
  for (int m = 0; m < 3; ++m)
    for (int k = 0; k < 2; ++k)
      for (int32_t tpc = 5; tpc <= 6; ++tpc) {
        mica_world* w = make_world(0, 0, g, MICA_SOLVER_DIRECT);
        assert_non_null(w);
        mica_body_def bd = mica_body_def_default();
        bd.model = models[m];
        bd.mass = masses[k];
        const double lo[3] = {0, 0, 1}, hi[3] = {0.3, 0.2, 1.1};
        const int32_t cells[3] = {3, 2, 1};
        mica_body_id b = 0;
        REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, tpc, &b));
        double* x0 = positions(w, b);
        for (int s = 0; s < steps; ++s) REQUIRE_OK(w, mica_step(w, h));
        double* x = positions(w, b);
        double* v = velocities(w, b);
        const int32_t n = node_count(w, b);
        for (int32_t i = 0; i < n; ++i) {
          ASSERT_REL(x[3 * i + 2] - x0[3 * i + 2], drop, 1e-9);
          ASSERT_NEAR(x[3 * i], x0[3 * i], 1e-9 * fabs(drop));
          ASSERT_NEAR(x[3 * i + 1], x0[3 * i + 1], 1e-9 * fabs(drop));
          ASSERT_REL(v[3 * i + 2], speed, 1e-9);
          ASSERT_NEAR(v[3 * i], 0, 1e-9 * fabs(speed));
          ASSERT_NEAR(v[3 * i + 1], 0, 1e-9 * fabs(speed));
        }
        /* Kinetic energy of the whole mass rho V moving at g n h; no strain energy. */
        double kinetic = -1, elastic = -1;
        REQUIRE_OK(w, mica_body_get_energy(w, b, &kinetic, &elastic, NULL));
        const double mass = bd.density * 0.3 * 0.2 * 0.1;
        ASSERT_REL(kinetic, 0.5 * mass * speed * speed, 1e-9);
        ASSERT_NEAR(elastic, 0, 1e-12 * kinetic);
        free(x0);
        free(x);
        free(v);
        mica_world_destroy(w);
      }
}

/* The potential energy is -sum m_i g . x_i: it falls by m g dz as the body drops. */
static void test_energy_bookkeeping(void** state) {
  (void)state;
  mica_world* w = make_world(0, 0, -9.81, MICA_SOLVER_DIRECT);
  const double lo[3] = {0, 0, 0}, hi[3] = {0.2, 0.2, 0.2};
  const int32_t cells[3] = {2, 2, 2};
  mica_body_def bd = mica_body_def_default();
  bd.density = 500;
  mica_body_id b = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &b));
  double p0 = 0, p1 = 0;
  REQUIRE_OK(w, mica_body_get_energy(w, b, NULL, NULL, &p0));
  const double mass = 500 * 0.008;
  ASSERT_REL(p0, mass * 9.81 * 0.1, 1e-12); /* centre of mass at z = 0.1 */
  for (int s = 0; s < 4; ++s) REQUIRE_OK(w, mica_step(w, 0.02));
  REQUIRE_OK(w, mica_body_get_energy(w, b, NULL, NULL, &p1));
  const double dz = -9.81 * 0.02 * 0.02 * 4 * 5 / 2.0;
  ASSERT_REL(p1 - p0, mass * 9.81 * dz, 1e-9);
  mica_world_destroy(w);
}

/* A static body never moves. */
static void test_static_body(void** state) {
  (void)state;
  mica_world* w = make_world(0, -9.81, 0, MICA_SOLVER_DIRECT);
  mica_body_def bd = mica_body_def_default();
  bd.is_static = 1;
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 0.1, 1};
  const int32_t cells[3] = {2, 1, 2};
  mica_body_id b = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &b));
  double* x0 = positions(w, b);
  for (int s = 0; s < 3; ++s) REQUIRE_OK(w, mica_step(w, 0.01));
  double* x = positions(w, b);
  assert_memory_equal(x, x0, sizeof(double) * 3 * (size_t)node_count(w, b));
  free(x0);
  free(x);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* Linear projection constraints                                                               */

static void test_lpc_fixed_holds(void** state) {
  (void)state;
  mica_world* w = make_world(0, -9.81, 0, MICA_SOLVER_DIRECT);
  const double lo[3] = {0, 0, 0}, hi[3] = {0.4, 0.1, 0.1};
  const int32_t cells[3] = {4, 1, 1};
  const mica_body_def bd = mica_body_def_default();
  mica_body_id b = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &b));
  const double normal[3] = {1, 0, 0};
  int32_t count = 0;
  int32_t* face = select_plane(w, b, lo, normal, &count);
  assert_int_equal(count, 4);
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc = 0;
  REQUIRE_OK(w, mica_add_lpc(w, b, face, count, &fixed, &lpc));
  assert_int_not_equal(lpc, MICA_NULL_ID);
  assert_int_not_equal(lpc, b);
  double* rest = rest_positions(w, b);
  for (int s = 0; s < 20; ++s) REQUIRE_OK(w, mica_step(w, 0.01));
  double* x = positions(w, b);
  double* v = velocities(w, b);
  for (int32_t i = 0; i < count; ++i)
    for (int k = 0; k < 3; ++k) {
      const int32_t j = 3 * face[i] + k;
      if (x[j] != rest[j] || v[j] != 0) {
        print_error("fixed node %d, axis %d: x %.17g (rest %.17g), v %.3g\n", face[i], k, x[j], rest[j], v[j]);
        fail();
      }
    }
  /* The free end sags. */
  const int32_t n = node_count(w, b);
  assert_true(x[3 * (n - 1) + 1] < rest[3 * (n - 1) + 1] - 1e-4);
  free(face);
  free(rest);
  free(x);
  free(v);
  mica_world_destroy(w);
}

static void test_lpc_plane_slides(void** state) {
  (void)state;
  /* Gravity pushes into the floor (z) and along it (x); the floor is frictionless. */
  mica_world* w = make_world(3.0, 0, -9.81, MICA_SOLVER_DIRECT);
  const double lo[3] = {0, 0, 0}, hi[3] = {0.2, 0.2, 0.1};
  const int32_t cells[3] = {2, 2, 1};
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = 1e5;
  mica_body_id b = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &b));
  const double up[3] = {0, 0, 1};
  int32_t count = 0;
  int32_t* bottom = select_plane(w, b, lo, up, &count);
  assert_int_equal(count, 9);
  mica_lpc_def plane = mica_lpc_def_default();
  plane.kind = MICA_LPC_PLANE;
  plane.direction[0][0] = 0;
  plane.direction[0][1] = 0;
  plane.direction[0][2] = 2.0; /* normalised by the library */
  mica_lpc_id lpc = 0;
  REQUIRE_OK(w, mica_add_lpc(w, b, bottom, count, &plane, &lpc));
  double* rest = rest_positions(w, b);
  const int steps = 10;
  const double h = 0.01;
  for (int s = 0; s < steps; ++s) REQUIRE_OK(w, mica_step(w, h));
  double* x = positions(w, b);
  double mean_dx = 0;
  for (int32_t i = 0; i < count; ++i) {
    const int32_t j = 3 * bottom[i];
    ASSERT_NEAR(x[j + 2], rest[j + 2], 1e-12); /* held on the floor */
    mean_dx += (x[j] - rest[j]) / count;
  }
  /* The body slides at a = 3 m/s^2 (no friction); its base also spreads a little under the
   * load (Poisson), so the mean slide of the base is close to, not exactly, the rigid one. */
  const double slide = 3.0 * h * h * steps * (steps + 1) / 2.0;
  ASSERT_REL(mean_dx, slide, 1e-2);
  for (int32_t i = 0; i < count; ++i) assert_true(x[3 * bottom[i]] - rest[3 * bottom[i]] > 0.9 * slide);
  /* The free top falls onto the supported base: it moved down a little, not in free fall. */
  const int32_t n = node_count(w, b);
  const double free_drop = 9.81 * h * h * steps * (steps + 1) / 2.0;
  assert_true(x[3 * (n - 1) + 2] < rest[3 * (n - 1) + 2]);
  assert_true(rest[3 * (n - 1) + 2] - x[3 * (n - 1) + 2] < 0.5 * free_drop);
  free(bottom);
  free(rest);
  free(x);
  mica_world_destroy(w);

  /* With every node on the plane nothing deforms: the body slides rigidly, each node by the
   * closed-form backward-Euler distance, and no z changes at all. */
  w = make_world(3.0, 0, -9.81, MICA_SOLVER_DIRECT);
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 5, &b));
  const int32_t n_all = node_count(w, b);
  assert_true(n_all > 0);
  int32_t* all = malloc(sizeof(int32_t) * (size_t)(n_all > 0 ? n_all : 1));
  for (int32_t i = 0; i < n_all; ++i) all[i] = i;
  REQUIRE_OK(w, mica_add_lpc(w, b, all, n_all, &plane, &lpc));
  rest = rest_positions(w, b);
  for (int s = 0; s < steps; ++s) REQUIRE_OK(w, mica_step(w, h));
  x = positions(w, b);
  double* v = velocities(w, b);
  for (int32_t i = 0; i < n_all; ++i) {
    ASSERT_REL(x[3 * i] - rest[3 * i], slide, 1e-9);
    ASSERT_NEAR(x[3 * i + 1], rest[3 * i + 1], 1e-12);
    ASSERT_NEAR(x[3 * i + 2], rest[3 * i + 2], 1e-12);
    ASSERT_REL(v[3 * i], 3.0 * h * steps, 1e-9);
  }
  free(all);
  free(rest);
  free(x);
  free(v);
  mica_world_destroy(w);
}

static void test_lpc_prescribed_velocity(void** state) {
  (void)state;
  mica_world* w = make_world(0, -9.81, 0, MICA_SOLVER_DIRECT);
  const double lo[3] = {0, 0, 0}, hi[3] = {0.3, 0.1, 0.1};
  const int32_t cells[3] = {3, 1, 1};
  const mica_body_def bd = mica_body_def_default();
  mica_body_id b = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &b));
  const double normal[3] = {1, 0, 0};
  int32_t count = 0;
  int32_t* face = select_plane(w, b, lo, normal, &count);
  mica_lpc_def moving = mica_lpc_def_default();
  moving.velocity[2] = 0.1;
  mica_lpc_id lpc = 0;
  REQUIRE_OK(w, mica_add_lpc(w, b, face, count, &moving, &lpc));
  const double h = 0.02;
  double* before = positions(w, b);
  for (int s = 0; s < 8; ++s) {
    REQUIRE_OK(w, mica_step(w, h));
    double* after = positions(w, b);
    double* v = velocities(w, b);
    for (int32_t i = 0; i < count; ++i) {
      const int32_t j = 3 * face[i];
      ASSERT_NEAR(after[j + 2] - before[j + 2], 0.1 * h, 1e-15);
      ASSERT_NEAR(after[j], before[j], 1e-15);
      ASSERT_NEAR(after[j + 1], before[j + 1], 1e-15);
      ASSERT_NEAR(v[j + 2], 0.1, 1e-14);
      ASSERT_NEAR(v[j], 0, 1e-14);
      ASSERT_NEAR(v[j + 1], 0, 1e-14);
    }
    free(before);
    free(v);
    before = after;
  }
  free(before);
  free(face);
  mica_world_destroy(w);
}

static void test_lpc_remove(void** state) {
  (void)state;
  mica_world* w = make_world(0, -9.81, 0, MICA_SOLVER_DIRECT);
  const double lo[3] = {0, 0, 0}, hi[3] = {0.3, 0.1, 0.1};
  const int32_t cells[3] = {3, 1, 1};
  const mica_body_def bd = mica_body_def_default();
  mica_body_id b = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &b));
  const double normal[3] = {1, 0, 0};
  int32_t count = 0;
  int32_t* face = select_plane(w, b, lo, normal, &count);
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc = 0;
  REQUIRE_OK(w, mica_add_lpc(w, b, face, count, &fixed, &lpc));
  for (int s = 0; s < 5; ++s) REQUIRE_OK(w, mica_step(w, 0.01));
  double* held = positions(w, b);
  double* rest = rest_positions(w, b);
  for (int32_t i = 0; i < count; ++i) ASSERT_NEAR(held[3 * face[i] + 1], rest[3 * face[i] + 1], 1e-15);

  REQUIRE_OK(w, mica_lpc_remove(w, lpc));
  assert_int_equal(mica_lpc_remove(w, lpc), MICA_ERR_STALE_ID);
  for (int s = 0; s < 5; ++s) REQUIRE_OK(w, mica_step(w, 0.01));
  double* x = positions(w, b);
  for (int32_t i = 0; i < count; ++i) assert_true(x[3 * face[i] + 1] < held[3 * face[i] + 1] - 1e-5);
  free(held);
  free(rest);
  free(x);
  free(face);
  mica_world_destroy(w);
}

static void test_destroy_body_stales_its_lpcs(void** state) {
  (void)state;
  mica_world* w = make_world(0, -9.81, 0, MICA_SOLVER_DIRECT);
  const double lo[3] = {0, 0, 0}, hi[3] = {0.3, 0.1, 0.1};
  const int32_t cells[3] = {3, 1, 1};
  const mica_body_def bd = mica_body_def_default();
  mica_body_def moved = bd;
  moved.translation[1] = 1.0;
  mica_body_id a = 0, b = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &a));
  REQUIRE_OK(w, mica_body_create_box(w, &moved, lo, hi, cells, 5, &b));
  assert_int_not_equal(a, b);
  const int32_t nodes[2] = {0, 1};
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_def plane = mica_lpc_def_default();
  plane.kind = MICA_LPC_PLANE;
  mica_lpc_id a1 = 0, a2 = 0, b1 = 0;
  REQUIRE_OK(w, mica_add_lpc(w, a, nodes, 2, &fixed, &a1));
  REQUIRE_OK(w, mica_add_lpc(w, a, nodes, 2, &plane, &a2));
  REQUIRE_OK(w, mica_add_lpc(w, b, nodes, 2, &fixed, &b1));
  REQUIRE_OK(w, mica_step(w, 0.01));

  REQUIRE_OK(w, mica_body_destroy(w, a));
  assert_int_equal(mica_lpc_remove(w, a1), MICA_ERR_STALE_ID);
  assert_int_equal(mica_lpc_remove(w, a2), MICA_ERR_STALE_ID);
  assert_int_equal(mica_body_get_counts(w, a, NULL, NULL, NULL), MICA_ERR_STALE_ID);
  assert_int_equal(mica_body_destroy(w, a), MICA_ERR_STALE_ID);

  /* A new body may reuse the slot; the old ids stay stale. */
  mica_body_id c = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &c));
  assert_int_not_equal(c, a);
  mica_lpc_id c1 = 0;
  REQUIRE_OK(w, mica_add_lpc(w, c, nodes, 2, &fixed, &c1));
  assert_int_not_equal(c1, a1);
  assert_int_not_equal(c1, a2);
  assert_int_equal(mica_body_get_counts(w, a, NULL, NULL, NULL), MICA_ERR_STALE_ID);
  assert_int_equal(mica_lpc_remove(w, a1), MICA_ERR_STALE_ID);

  /* The other body's constraint still holds and is removable once. */
  REQUIRE_OK(w, mica_step(w, 0.01));
  double* xb = positions(w, b);
  double* rb = rest_positions(w, b);
  assert_memory_equal(xb, rb, 6 * sizeof(double));
  REQUIRE_OK(w, mica_lpc_remove(w, b1));
  assert_int_equal(mica_lpc_remove(w, b1), MICA_ERR_STALE_ID);
  REQUIRE_OK(w, mica_lpc_remove(w, c1));
  free(xb);
  free(rb);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* VTK output                                                                                  */

/* Reads the file; checks the header and the POINTS line, and compares the points with `x`. */
static void check_vtk(const char* path, long points, const double* x) {
  FILE* f = fopen(path, "rb");
  assert_non_null(f);
  char line[512];
  assert_non_null(fgets(line, sizeof line, f));
  assert_true(strncmp(line, "# vtk DataFile Version", 22) == 0);
  long n = -1;
  char type[32] = "";
  while (fgets(line, sizeof line, f))
    if (sscanf(line, "POINTS %ld %31s", &n, type) == 2) break;
  assert_int_equal(n, points);
  assert_string_equal(type, "double");
  for (long i = 0; i < 3 * n; ++i) {
    double value = 0;
    assert_int_equal(fscanf(f, "%lf", &value), 1);
    if (x && value != x[i]) {
      print_error("%s: point %ld coordinate %ld is %.17g, the body has %.17g\n", path, i / 3, i % 3, value, x[i]);
      fail();
    }
  }
  fclose(f);
}

static void test_vtk_output(void** state) {
  (void)state;
  mica_world* w = make_world(0, -9.81, 0, MICA_SOLVER_DIRECT);
  const double lo[3] = {0, 0, 0}, hi[3] = {0.3, 0.1, 0.1};
  const int32_t cells[3] = {3, 1, 1}, cells2[3] = {2, 2, 2};
  const mica_body_def bd = mica_body_def_default();
  mica_body_def moved = bd;
  moved.translation[0] = 1.0;
  mica_body_id a = 0, b = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &a));
  REQUIRE_OK(w, mica_body_create_box(w, &moved, lo, hi, cells2, 5, &b));
  for (int s = 0; s < 3; ++s) REQUIRE_OK(w, mica_step(w, 0.01));
  const int32_t na = node_count(w, a), nb = node_count(w, b);
  assert_int_equal(na, 16);
  assert_int_equal(nb, 27);

  char body_path[512], world_path[512], bad_path[512];
  snprintf(body_path, sizeof body_path, "%s/body.vtk", g_dir);
  snprintf(world_path, sizeof world_path, "%s/world.vtk", g_dir);
  snprintf(bad_path, sizeof bad_path, "%s/no-such-dir/out.vtk", g_dir);

  double* xa = positions(w, a);
  double* xb = positions(w, b);
  REQUIRE_OK(w, mica_body_write_vtk(w, a, body_path));
  check_vtk(body_path, na, xa); /* current positions, written exactly */
  REQUIRE_OK(w, mica_world_write_vtk(w, world_path));
  double* both = malloc(sizeof(double) * 3 * (size_t)(na + nb));
  memcpy(both, xa, sizeof(double) * 3 * (size_t)na);
  memcpy(both + 3 * na, xb, sizeof(double) * 3 * (size_t)nb);
  check_vtk(world_path, na + nb, both);

  assert_int_equal(mica_body_write_vtk(w, a, bad_path), MICA_ERR_IO);
  assert_non_null(strstr(mica_world_last_error(w), bad_path));
  assert_int_equal(mica_world_write_vtk(w, bad_path), MICA_ERR_IO);
  assert_non_null(strstr(mica_world_last_error(w), bad_path));

  /* An empty world writes an empty grid. */
  REQUIRE_OK(w, mica_body_destroy(w, a));
  REQUIRE_OK(w, mica_body_destroy(w, b));
  REQUIRE_OK(w, mica_world_write_vtk(w, world_path));
  check_vtk(world_path, 0, NULL);
  free(both);
  free(xa);
  free(xb);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* Statistics and solvers                                                                      */

static void test_stats(void** state) {
  (void)state;
  mica_world* w = make_world(0, -9.81, 0, MICA_SOLVER_DIRECT);
  mica_world_stats s = stats_of(w);
  assert_int_equal(s.step_count, 0);
  assert_int_equal(s.struct_size, sizeof s);
  const double lo[3] = {0, 0, 0}, hi[3] = {0.3, 0.1, 0.1};
  const int32_t cells[3] = {3, 1, 1};
  const mica_body_def bd = mica_body_def_default();
  mica_body_id b = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &b));
  const int steps = 6;
  for (int k = 0; k < steps; ++k) {
    assert_int_equal(mica_step(w, 0.01), MICA_OK);
    s = stats_of(w);
    assert_int_equal(s.step_count, k + 1);
    assert_int_equal(s.stages[MICA_STAGE_SOLVE].runs_last_step, 1);
    assert_int_equal(s.stages[MICA_STAGE_SOLVE].runs_total, k + 1);
    assert_int_equal(s.stages[MICA_STAGE_INTEGRATE].runs_total, k + 1);
    assert_int_equal(s.stages[MICA_STAGE_GRAVITY].runs_total, k + 1);
    assert_int_equal(s.stages[MICA_STAGE_ROTATIONS].runs_total, k + 1); /* co-rotational */
    /* Effects absent from the scene are not in the plan. */
    assert_int_equal(s.stages[MICA_STAGE_DAMPING].runs_total, 0);
    assert_int_equal(s.stages[MICA_STAGE_CONSTRAINTS].runs_total, 0);
    assert_int_equal(s.converged, 1);
    assert_int_equal(s.solver_iterations, 1);
    assert_true(s.solver_residual >= 0 && s.solver_residual < 1e-10);
    assert_true(s.ms_last_step >= 0);
    for (int stage = 0; stage < MICA_STAGE_COUNT; ++stage) {
      assert_true(s.stages[stage].ms_last_step >= 0);
      assert_true(s.stages[stage].ms_total >= s.stages[stage].ms_last_step);
    }
  }
  /* A constraint puts its stage in the plan. */
  const int32_t nodes[1] = {0};
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc = 0;
  REQUIRE_OK(w, mica_add_lpc(w, b, nodes, 1, &fixed, &lpc));
  REQUIRE_OK(w, mica_step(w, 0.01));
  s = stats_of(w);
  assert_int_equal(s.stages[MICA_STAGE_CONSTRAINTS].runs_last_step, 1);
  assert_int_equal(s.stages[MICA_STAGE_CONSTRAINTS].runs_total, 1);
  assert_int_equal(s.stages[MICA_STAGE_SOLVE].runs_total, steps + 1);

  /* An older caller's shorter struct: the library writes only up to the stages. */
  union {
    mica_world_stats s;
    unsigned char bytes[sizeof(mica_world_stats)];
  } short_stats;
  memset(&short_stats, 0xab, sizeof short_stats);
  short_stats.s.struct_size = (uint32_t)offsetof(mica_world_stats, stages);
  REQUIRE_OK(w, mica_world_get_stats(w, &short_stats.s));
  assert_int_equal(short_stats.s.step_count, steps + 1);
  for (size_t i = offsetof(mica_world_stats, stages); i < sizeof short_stats.bytes; ++i)
    assert_int_equal(short_stats.bytes[i], 0xab);
  mica_world_destroy(w);
}

/* The stats' solves and factorizations, per step of a sphere pressed into a small co-rotational
 * cube: the exact solver factors every step (a new matrix each step) in one solve per Solve
 * stage run; the factored sweep factors at the first solve, then only when a solve drags on
 * (100 iterations) or, with a refresh interval L, at solves 2, 2 + L, 2 + 2L, ... (started in
 * the background, adopted L solves later); its solves are its rounds, at least one per Solve
 * stage run and at most one per iteration. */
static void test_stats_count_solves_and_factorizations(void** state) {
  (void)state;
  static const struct {
    const char* name;
    int32_t solver, refactor_interval;
  } cases[] = {
      {"exact", MICA_SOLVER_DIRECT, 0},
      {"factored sweep", MICA_SOLVER_MICA, 0},
      {"factored sweep, refreshed every 3 steps", MICA_SOLVER_MICA, 3},
  };
  for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
    press_scene_def def = press_scene_def_default();
    def.cells = 4;
    def.solver = cases[c].solver;
    def.tolerance = 1e-8;
    def.load_time = 0.1;
    def.hold_time = 0.1;
    def.refactor_interval = cases[c].refactor_interval;
    press_scene s;
    if (press_scene_create(&def, &s) != MICA_OK) fail_msg("%s", s.error);
    int32_t most_contacts = 0, most_solves = 0;
    for (int32_t k = 1; k <= s.steps; ++k) {
      int32_t contacts = 0;
      if (press_scene_step(&s, k, NULL, &contacts) != MICA_OK) fail_msg("%s", s.error);
      const mica_world_stats st = stats_of(s.world);
      const int32_t solve_runs = st.stages[MICA_STAGE_SOLVE].runs_last_step;
      int32_t factors;
      if (cases[c].solver == MICA_SOLVER_DIRECT) {
        assert_int_equal(st.solves, solve_runs);
        factors = solve_runs;
      } else {
        assert_true(st.solves >= solve_runs);
        assert_true(st.solves <= st.solver_iterations);
        const int32_t interval = cases[c].refactor_interval;
        factors = k == 1 || st.solver_iterations >= 100;
        for (int64_t n = st.stages[MICA_STAGE_SOLVE].runs_total - solve_runs + 1;
             n <= st.stages[MICA_STAGE_SOLVE].runs_total; ++n)
          factors += interval > 0 && n >= 2 && (n - 2) % interval == 0;
      }
      if (st.factorizations != factors)
        fail_msg("%s, step %d: %d factorizations, expected %d (%d iterations, %d solves)", cases[c].name, k,
                 st.factorizations, factors, st.solver_iterations, st.solves);
      if (contacts > most_contacts) most_contacts = contacts;
      if (st.solves > most_solves) most_solves = st.solves;
    }
    print_message("%s: %d steps, at most %d contacts and %d solves in a step\n", cases[c].name, s.steps,
                  most_contacts, most_solves);
    assert_true(most_contacts > 0);  /* the sphere pressed */
    press_scene_destroy(&s);
  }
}

/* A block clamped at x = 0 sagging under gravity, `steps` steps of 0.01 s. */
static double* clamped_block(mica_world* w, int steps) {
  const double lo[3] = {0, 0, 0}, hi[3] = {0.4, 0.1, 0.1};
  const int32_t cells[3] = {8, 2, 2};
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = 1e5;
  mica_body_id b = 0;
  if (mica_body_create_box(w, &bd, lo, hi, cells, 6, &b) != MICA_OK) return NULL;
  const double normal[3] = {1, 0, 0};
  int32_t count = 0;
  int32_t* face = select_plane(w, b, lo, normal, &count);
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc = 0;
  if (!face || mica_add_lpc(w, b, face, count, &fixed, &lpc) != MICA_OK) return NULL;
  free(face);
  for (int s = 0; s < steps; ++s)
    if (mica_step(w, 0.01) != MICA_OK) {
      print_error("step %d: %s\n", s, mica_world_last_error(w));
      return NULL;
    }
  return positions(w, b);
}

static void test_pcg_matches_direct(void** state) {
  (void)state;
  mica_world* direct = make_world(0, -9.81, 0, MICA_SOLVER_DIRECT);
  mica_world_def wd = mica_world_def_default();
  wd.solver = MICA_SOLVER_PCG;
  wd.tolerance = 1e-10;
  wd.max_iterations = 2000;
  mica_world* pcg = NULL;
  REQUIRE_OK(NULL, mica_world_create(&wd, &pcg));
  double* xd = clamped_block(direct, 20);
  double* xp = clamped_block(pcg, 20);
  assert_non_null(xd);
  assert_non_null(xp);
  const mica_world_stats sp = stats_of(pcg);
  assert_int_equal(sp.converged, 1);
  assert_true(sp.solver_iterations > 1);
  assert_true(sp.solver_residual <= 1e-10);
  const int32_t n = 9 * 3 * 3;
  double worst = 0, sag = 0;
  for (int32_t i = 0; i < 3 * n; ++i) worst = fmax(worst, fabs(xd[i] - xp[i]));
  /* the comparison means something: the tip sagged by millimetres */
  sag = 0.1 - xd[3 * (n - 1) + 1];
  assert_true(sag > 1e-3);
  if (!(worst <= 1e-8)) {
    print_error("PCG and DIRECT differ by %.3g m after 20 steps (tip sag %.3g m)\n", worst, sag);
    fail();
  }
  free(xd);
  free(xp);
  mica_world_destroy(direct);
  mica_world_destroy(pcg);
}

static void test_pcg_not_converged(void** state) {
  (void)state;
  mica_world_def wd = mica_world_def_default();
  wd.solver = MICA_SOLVER_PCG;
  wd.tolerance = 1e-14;
  wd.max_iterations = 1;
  mica_world* w = NULL;
  REQUIRE_OK(NULL, mica_world_create(&wd, &w));
  const double lo[3] = {0, 0, 0}, hi[3] = {0.4, 0.1, 0.1};
  const int32_t cells[3] = {8, 2, 2};
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = 1e5;
  mica_body_id b = 0;
  REQUIRE_OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &b));
  const double normal[3] = {1, 0, 0};
  int32_t count = 0;
  int32_t* face = select_plane(w, b, lo, normal, &count);
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc = 0;
  REQUIRE_OK(w, mica_add_lpc(w, b, face, count, &fixed, &lpc));
  double* x0 = positions(w, b);
  assert_int_equal(mica_step(w, 0.01), MICA_WARN_NOT_CONVERGED);
  const mica_world_stats s = stats_of(w);
  assert_int_equal(s.converged, 0);
  assert_int_equal(s.step_count, 1); /* the step is kept */
  assert_int_equal(s.solver_iterations, 1);
  assert_true(s.solver_residual > 1e-14);
  double* x = positions(w, b);
  const int32_t n = node_count(w, b);
  int moved = 0;
  for (int32_t i = 0; i < 3 * n; ++i) {
    assert_true(isfinite(x[i]));
    moved += x[i] != x0[i];
  }
  assert_true(moved > 0);
  free(face);
  free(x0);
  free(x);
  mica_world_destroy(w);
}

/* A sliver (aspect ratio ~1e3) is accepted, and the host is warned through the log callback. */
typedef struct {
  int warnings;
  char last[512];
} log_capture;

static void capture_log(int32_t level, const char* message, void* user) {
  log_capture* c = user;
  if (level == MICA_LOG_WARNING) {
    c->warnings++;
    snprintf(c->last, sizeof c->last, "%s", message);
  }
}

static void test_sliver_is_reported(void** state) {
  (void)state;
  log_capture capture = {0, ""};
  mica_world_def wd = mica_world_def_default();
  wd.log = capture_log;
  wd.log_user = &capture;
  mica_world* w = NULL;
  assert_int_equal(mica_world_create(&wd, &w), MICA_OK);
  /* A regular-ish tet and a flat one: its apex sits 1e-3 above the base plane. */
  const double nodes[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.3, 0.3, -1e-3};
  const int32_t tets[] = {0, 1, 2, 3, 0, 2, 1, 4};
  const mica_body_def bd = mica_body_def_default();
  mica_body_id body = 0;
  assert_int_equal(mica_body_create(w, &bd, nodes, 5, tets, 2, &body), MICA_OK);
  assert_int_equal(capture.warnings, 1);
  assert_non_null(strstr(capture.last, "sliver"));
  assert_non_null(strstr(capture.last, "tet 1"));
  mica_world_destroy(w);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_version),
      cmocka_unit_test(test_defaults),
      cmocka_unit_test(test_box_counts_and_readback),
      cmocka_unit_test(test_view_after_step),
      cmocka_unit_test(test_surface_closed_and_outward),
      cmocka_unit_test(test_select_faces),
      cmocka_unit_test(test_free_fall),
      cmocka_unit_test(test_energy_bookkeeping),
      cmocka_unit_test(test_static_body),
      cmocka_unit_test(test_lpc_fixed_holds),
      cmocka_unit_test(test_lpc_plane_slides),
      cmocka_unit_test(test_lpc_prescribed_velocity),
      cmocka_unit_test(test_lpc_remove),
      cmocka_unit_test(test_destroy_body_stales_its_lpcs),
      cmocka_unit_test(test_vtk_output),
      cmocka_unit_test(test_stats),
      cmocka_unit_test(test_stats_count_solves_and_factorizations),
      cmocka_unit_test(test_pcg_matches_direct),
      cmocka_unit_test(test_pcg_not_converged),
      cmocka_unit_test(test_sliver_is_reported),
  };
  return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
