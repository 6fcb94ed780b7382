/* SPDX-License-Identifier: Apache-2.0 */
/* MICA_MODEL_NEO_HOOKEAN through the public API: uniaxial compression against the closed-form
 * stable neo-Hookean answer, volume kept under bonded compression (beside the co-rotational
 * figure), recovery from an inverted block, a rigid motion that moves no node, Hertz contact beside
 * the co-rotational body on the same mesh, and the model's value refused or accepted. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <mica/mica.h>

#include "capi_ok.h"
#include "node_selection.h"
#include "uniaxial_scene.h"

/* ------------------------------------------------------------------------------------------ */
/* Helpers                                                                                     */

static mica_world* make_world(int32_t solver) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[0] = wd.gravity[1] = wd.gravity[2] = 0;
  wd.solver = solver;
  mica_world* w = NULL;
  OK(NULL, mica_world_create(&wd, &w));
  return w;
}

static double* positions(mica_world* w, mica_body_id b, int32_t* n) {
  OK(w, mica_body_get_positions(w, b, NULL, 0, n));
  double* x = malloc(sizeof(double) * 3 * (size_t)*n);
  OK(w, mica_body_get_positions(w, b, x, *n, n));
  return x;
}

static double tet_volume(const double* x, const int32_t* t) {
  const double* a = x + 3 * t[0];
  double u[3], v[3], q[3];
  for (int k = 0; k < 3; ++k) {
    u[k] = x[3 * t[1] + k] - a[k];
    v[k] = x[3 * t[2] + k] - a[k];
    q[k] = x[3 * t[3] + k] - a[k];
  }
  return (u[0] * (v[1] * q[2] - v[2] * q[1]) - u[1] * (v[0] * q[2] - v[2] * q[0]) + u[2] * (v[0] * q[1] - v[1] * q[0])) /
         6.0;
}

/* The body's volume and its smallest tet volume (negative: an inverted tet). */
static double body_volume(mica_world* w, mica_body_id b, double* smallest) {
  int32_t n = 0, nt = 0;
  double* x = positions(w, b, &n);
  OK(w, mica_body_get_tets(w, b, NULL, 0, &nt));
  int32_t* t = malloc(sizeof(int32_t) * 4 * (size_t)nt);
  OK(w, mica_body_get_tets(w, b, t, nt, &nt));
  double sum = 0, low = INFINITY;
  for (int32_t e = 0; e < nt; ++e) {
    const double v = tet_volume(x, t + 4 * e);
    sum += v;
    low = fmin(low, v);
  }
  if (smallest) *smallest = low;
  free(x);
  free(t);
  return sum;
}

static mica_lpc_id add_plane_lpc(mica_world* w, mica_body_id b, const double point[3], const double normal[3],
                                 int32_t kind) {
  int32_t n = 0;
  int32_t* sel = scene_select_plane(w, b, point, normal, 1e-9, &n);
  assert_non_null(sel);
  assert_true(n > 0);
  mica_lpc_def d = mica_lpc_def_default();
  d.kind = kind;
  for (int k = 0; k < 3; ++k) d.direction[0][k] = normal[k] < 0 ? -normal[k] : normal[k];
  mica_lpc_id id = MICA_NULL_ID;
  OK(w, mica_add_lpc(w, b, sel, n, &d, &id));
  free(sel);
  return id;
}

/* ------------------------------------------------------------------------------------------ */
/* Uniaxial compression                                                                        */

/* A cube of side L on frictionless ends (scenes/uniaxial_scene.h: the base and the top slide in
 * their planes; the planes x = 0 and y = 0 are symmetry planes), compressed by its top plate in
 * 5 % increments to 30 %, each held until the body is at rest (h = 1 s: the mass is 1e-3 of the
 * stiffness, so each step is a Newton step of the static problem). The deformation is
 * homogeneous, which linear tets represent exactly: the plate's reaction over the rest area must
 * be the closed-form nominal stress, at every increment, on a coarse and a fine mesh. */
static void compress_cube(int32_t cells, int32_t solver, double* worst_error) {
  mica_world* w = make_world(solver);
  uniaxial_scene_def def = uniaxial_scene_def_default();
  def.body.model = MICA_MODEL_NEO_HOOKEAN;
  def.cells = cells;
  const double L = def.side, E = def.body.youngs_modulus, nu = def.body.poisson_ratio;
  uniaxial_scene sc;
  OK(w, uniaxial_scene_create(w, &def, &sc));
  const double h = 1.0;
  int32_t warned = 0;
  *worst_error = 0;
  printf("cube %d^3 cells x 6 tets, E %.0f Pa, nu %.2f:\n  strain  stretch  P_zz FEM (Pa)  closed form (Pa)  error   lateral FEM / closed form\n",
         cells, E, nu);
  for (int inc = 1; inc <= 6; ++inc) {
    const double v[3] = {0, 0, -0.05 * L / h};
    OK(w, mica_lpc_set_velocity(w, sc.plate, v));
    mica_status st = mica_step(w, h);
    warned += st == MICA_WARN_NOT_CONVERGED;
    OK(w, st);
    const double still[3] = {0, 0, 0};
    OK(w, mica_lpc_set_velocity(w, sc.plate, still));
    for (int k = 0; k < 6; ++k) {
      st = mica_step(w, h);
      warned += st == MICA_WARN_NOT_CONVERGED;
      OK(w, st);
    }
    /* The stretches the body reached: the top's height, the far side's width. */
    double s = 0, width = 0, got = 0, t = 0;
    OK(w, uniaxial_scene_measure(w, &sc, &s, &width, &got));
    const double want = uniaxial_neo_hookean_nominal_stress(E, nu, s, &t);
    const double err = fabs(got - want) / fabs(want);
    *worst_error = fmax(*worst_error, err);
    printf("  %4.0f %%  %.5f  %12.4f  %16.4f  %.2e  %.6f / %.6f\n", 100 * (1 - s), s, got, want, err, width, t);
    assert_true(fabs(s - (1 - 0.05 * inc)) < 1e-9);
    assert_true(err < 0.01);
    assert_true(fabs(width - t) < 1e-3 * t);
  }
  printf("  steps that reported MICA_WARN_NOT_CONVERGED: %d of %d\n", warned, 6 * 7);
  mica_world_destroy(w);
}

static void test_uniaxial_compression_matches_closed_form(void** state) {
  (void)state;
  double coarse = 0, fine = 0;
  compress_cube(2, MICA_SOLVER_DIRECT, &coarse);
  compress_cube(6, MICA_SOLVER_DIRECT, &fine);
  printf("largest error of the nominal stress, 0-30 %%: coarse %.2e, fine %.2e\n", coarse, fine);
}

static void test_uniaxial_compression_with_the_factored_mica_sweep(void** state) {
  (void)state;
  double err = 0;
  compress_cube(4, MICA_SOLVER_MICA, &err);
  printf("factored MICA sweep: largest error %.2e\n", err);
}

/* ------------------------------------------------------------------------------------------ */
/* Volume under bonded compression                                                             */

static double bonded_volume_change_cells(int32_t model, double nu, int32_t cells, int32_t tets_per_cell,
                                         int32_t* warned) {
  const double L = 0.1;
  mica_world* w = make_world(MICA_SOLVER_DIRECT);
  mica_body_def bd = mica_body_def_default();
  bd.model = model;
  bd.youngs_modulus = 1e4;
  bd.poisson_ratio = nu;
  const double lo[3] = {0, 0, 0}, hi[3] = {L, L, L};
  const int32_t c[3] = {cells, cells, cells};
  mica_body_id b = MICA_NULL_ID;
  OK(w, mica_body_create_box(w, &bd, lo, hi, c, tets_per_cell, &b));
  const double v0 = body_volume(w, b, NULL);
  const double base[3] = {0, 0, 0}, down[3] = {0, 0, -1}, top[3] = {0, 0, L};
  mica_lpc_id fixed = MICA_NULL_ID;
  OK(w, scene_fix_plane(w, b, base, (const double[3]){0, 0, 1}, 1e-9, NULL, &fixed));
  const mica_lpc_id plate = add_plane_lpc(w, b, top, down, MICA_LPC_FIXED); /* bonded: no sliding */
  for (int inc = 1; inc <= 4; ++inc) {
    const double v[3] = {0, 0, -0.05 * L};
    OK(w, mica_lpc_set_velocity(w, plate, v));
    mica_status st = mica_step(w, 1.0);
    *warned += st == MICA_WARN_NOT_CONVERGED;
    OK(w, st);
    const double still[3] = {0, 0, 0};
    OK(w, mica_lpc_set_velocity(w, plate, still));
    for (int k = 0; k < 6; ++k) {
      st = mica_step(w, 1.0);
      *warned += st == MICA_WARN_NOT_CONVERGED;
      OK(w, st);
    }
  }
  const double v1 = body_volume(w, b, NULL);
  mica_world_destroy(w);
  return v1 / v0 - 1;
}

/* The goal (issue 36): within 1 % at nu = 0.49. The loss sits in the tets at the bonded rim and falls
 * with the mesh (6 tets per cell: -1.46, -1.20, -1.08 % on 8, 12, 16 cells a side; 5 tets per cell:
 * -1.21, -1.02, -0.94, -0.90 % on 8, 12, 16, 20), toward about -0.8 % (the homogeneous answer is
 * -0.5 %). Asserted: at nu = 0.49 on 16 cells a side x 5 tets within 1 % and under a third of the
 * co-rotational loss; at nu = 0.495 on 8 cells x 6 tets within 1 %. */
static void test_volume_kept_under_bonded_compression(void** state) {
  (void)state;
  const double nus[2] = {0.49, 0.495};
  const int32_t cells[2] = {16, 8}, tets_per_cell[2] = {5, 6};
  double neo[2] = {0, 0}, corot[2] = {0, 0};
  for (int a = 0; a < 2; ++a) {
    int32_t warned = 0, corot_warned = 0;
    neo[a] = bonded_volume_change_cells(MICA_MODEL_NEO_HOOKEAN, nus[a], cells[a], tets_per_cell[a], &warned);
    corot[a] = bonded_volume_change_cells(MICA_MODEL_COROTATIONAL, nus[a], cells[a], tets_per_cell[a], &corot_warned);
    printf("20 %% bonded compression, nu %.3f, %d^3 cells x %d tets: volume change neo-Hookean %+.3f %% (%d steps not "
           "converged), co-rotational %+.3f %%\n",
           nus[a], cells[a], tets_per_cell[a], 100 * neo[a], warned, 100 * corot[a]);
    assert_int_equal(warned, 0);
  }
  assert_true(fabs(neo[0]) < 0.01);
  assert_true(fabs(neo[0]) < fabs(corot[0]) / 3);
  assert_true(fabs(neo[1]) < 0.01);
}

/* ------------------------------------------------------------------------------------------ */
/* Inversion                                                                                   */

/* A block squashed through zero volume (z -> -0.3 z: every tet inverted) and released with mass
 * damping: every step succeeds, no value is NaN, and every tet comes back to its rest shape. */
static void test_inverted_block_recovers(void** state) {
  (void)state;
  mica_world* w = make_world(MICA_SOLVER_MICA);
  mica_body_def bd = mica_body_def_default();
  bd.model = MICA_MODEL_NEO_HOOKEAN;
  bd.youngs_modulus = 1e4;
  bd.poisson_ratio = 0.45;
  bd.rayleigh_alpha = 20;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.1, 0.05};
  const int32_t c[3] = {4, 4, 2};
  mica_body_id b = MICA_NULL_ID;
  OK(w, mica_body_create_box(w, &bd, lo, hi, c, 6, &b));
  int32_t n = 0;
  double* rest = positions(w, b, &n);
  double* x = malloc(sizeof(double) * 3 * (size_t)n);
  memcpy(x, rest, sizeof(double) * 3 * (size_t)n);
  for (int32_t i = 0; i < n; ++i) x[3 * i + 2] = -0.3 * rest[3 * i + 2];
  OK(w, mica_body_set_positions(w, b, x, n));
  double smallest = 0;
  body_volume(w, b, &smallest);
  assert_true(smallest < 0);
  int32_t failed = 0, warned = 0;
  for (int k = 0; k < 300; ++k) {
    const mica_status st = mica_step(w, 0.01);
    failed += st < 0;
    warned += st == MICA_WARN_NOT_CONVERGED;
  }
  free(x);
  x = positions(w, b, &n);
  /* The rest shape up to a rigid motion: compare edge vectors through the strain readout. */
  int32_t nt = 0;
  OK(w, mica_body_get_strains(w, b, NULL, 0, &nt));
  double* strain = malloc(sizeof(double) * 6 * (size_t)nt);
  OK(w, mica_body_get_strains(w, b, strain, nt, &nt));
  double largest = 0;
  int finite = 1;
  for (int32_t k = 0; k < 6 * nt; ++k) {
    finite = finite && isfinite(strain[k]);
    largest = fmax(largest, fabs(strain[k]));
  }
  for (int32_t k = 0; k < 3 * n; ++k) finite = finite && isfinite(x[k]);
  body_volume(w, b, &smallest);
  printf("inverted block released: %d failed steps, %d not converged of 300; largest Green strain after 3 s %.2e, "
         "smallest tet volume %.3e m^3\n",
         failed, warned, largest, smallest);
  assert_int_equal(failed, 0);
  assert_true(finite);
  assert_true(smallest > 0);
  assert_true(largest < 1e-3);
  free(strain);
  free(rest);
  free(x);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* Rigid motion                                                                                */

/* The rest shape turned by 120 degrees and moved: a step leaves it where it is (no strain, no
 * force), to 1e-10 of its size. */
static void test_rigid_motion_moves_nothing(void** state) {
  (void)state;
  mica_world* w = make_world(MICA_SOLVER_DIRECT);
  mica_body_def bd = mica_body_def_default();
  bd.model = MICA_MODEL_NEO_HOOKEAN;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.08, 0.06};
  const int32_t c[3] = {3, 3, 2};
  mica_body_id b = MICA_NULL_ID;
  OK(w, mica_body_create_box(w, &bd, lo, hi, c, 5, &b));
  int32_t n = 0;
  double* x = positions(w, b, &n);
  /* Rotation by 120 degrees about (1, 1, 1): x -> z -> y. */
  for (int32_t i = 0; i < n; ++i) {
    const double p0 = x[3 * i], p1 = x[3 * i + 1], p2 = x[3 * i + 2];
    x[3 * i] = p2 + 1, x[3 * i + 1] = p0 - 2, x[3 * i + 2] = p1 + 0.5;
  }
  OK(w, mica_body_set_positions(w, b, x, n));
  for (int k = 0; k < 3; ++k) OK(w, mica_step(w, 0.01));
  double* y = positions(w, b, &n);
  double moved = 0;
  for (int32_t k = 0; k < 3 * n; ++k) moved = fmax(moved, fabs(y[k] - x[k]));
  printf("rigid motion, 3 steps: largest node movement %.2e m\n", moved);
  assert_true(moved < 1e-10 * 0.1);
  free(x);
  free(y);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* Hertz                                                                                       */

/* The Hertz scene of bench/study/study_anchors.c (a sphere R = 1 cm pushed 0.5 mm, d / R = 0.05,
 * into a quarter of a 0.1 m block, symmetry planes, base fixed; graded tensor grid, 5 tets per
 * cell), on one mesh, with a co-rotational and a neo-Hookean body side by side. At this small
 * indentation the two models must agree (within 10 %); against Hertz's formula the mesh limits
 * both alike (docs/accuracy-vs-time.md: +24 % on this mesh, +9.5 % at 69k tets). */
static int graded(int n, double k, double length, double* out) {
  for (int i = 0; i <= n; ++i) out[i] = length * sinh(k * i / n) / sinh(k);
  return n + 1;
}
static const int cut_even[5][4] = {{0, 3, 5, 6}, {1, 0, 3, 5}, {2, 0, 6, 3}, {4, 0, 5, 6}, {7, 3, 6, 5}};
static const int cut_odd[5][4] = {{1, 2, 4, 7}, {0, 1, 4, 2}, {3, 1, 2, 7}, {5, 1, 7, 4}, {6, 2, 4, 7}};

static double hertz_force(int32_t model, int cells) {
  const double R = 0.01, D = 0.0005, E = 1e4, nu = 0.3, W = 0.1;
  double g[64];
  const int nx = graded(cells, 4.0, W, g);
  const int32_t nodes = nx * nx * nx;
  double* p = malloc(sizeof(double) * 3 * (size_t)nodes);
  int32_t* t = malloc(sizeof(int32_t) * 20 * (size_t)(nx - 1) * (nx - 1) * (nx - 1));
  for (int k = 0; k < nx; ++k)
    for (int j = 0; j < nx; ++j)
      for (int i = 0; i < nx; ++i) {
        double* q = p + 3 * ((size_t)(k * nx + j) * nx + i);
        q[0] = g[i], q[1] = -g[nx - 1 - j], q[2] = g[k];
      }
  int32_t ntet = 0;
  for (int k = 0; k + 1 < nx; ++k)
    for (int j = 0; j + 1 < nx; ++j)
      for (int i = 0; i + 1 < nx; ++i) {
        int32_t c[8];
        for (int m = 0; m < 8; ++m) c[m] = ((k + ((m >> 2) & 1)) * nx + (j + ((m >> 1) & 1))) * nx + (i + (m & 1));
        const int(*cut)[4] = ((i + j + k) % 2 == 0) ? cut_even : cut_odd;
        for (int e = 0; e < 5; ++e) {
          int32_t* o = t + 4 * (size_t)ntet++;
          for (int v = 0; v < 4; ++v) o[v] = c[cut[e][v]];
          if (tet_volume(p, o) < 0) {
            const int32_t s = o[2];
            o[2] = o[3], o[3] = s;
          }
        }
      }
  mica_world* w = make_world(MICA_SOLVER_DIRECT);
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = E;
  bd.poisson_ratio = nu;
  bd.model = model;
  mica_body_id body = MICA_NULL_ID;
  OK(w, mica_body_create(w, &bd, p, nodes, t, ntet, &body));
  const double o[3] = {0, 0, 0}, ex[3] = {1, 0, 0}, ez[3] = {0, 0, 1}, bottom[3] = {0, -W, 0}, up[3] = {0, 1, 0};
  add_plane_lpc(w, body, o, ex, MICA_LPC_PLANE);
  add_plane_lpc(w, body, o, ez, MICA_LPC_PLANE);
  mica_lpc_id base = MICA_NULL_ID;
  OK(w, scene_fix_plane(w, body, bottom, up, 1e-9, NULL, &base));
  mica_tool_def td = mica_tool_def_default();
  td.radius = R;
  td.margin = 1e-4;
  td.position[1] = R + 1e-4;
  mica_tool_id tool = MICA_NULL_ID;
  OK(w, mica_tool_create(w, &td, &tool));
  const double q[4] = {1, 0, 0, 0};
  double f[3] = {0, 0, 0}, mean = 0;
  for (int inc = 1; inc <= 4; ++inc) {
    const double pos[3] = {0, R - D * inc / 4, 0};
    OK(w, mica_tool_set_pose(w, tool, pos, q));
    const int steps = inc == 4 ? 5 : 2;
    for (int s = 0; s < steps; ++s) {
      OK(w, mica_step(w, 1.0));
      OK(w, mica_tool_get_force(w, tool, f, NULL, NULL));
      if (inc == 4 && s >= 2) mean += 4 * f[1] / 3;
    }
  }
  mica_world_destroy(w);
  free(p);
  free(t);
  return mean;
}

static void test_hertz_beside_the_corotational_body(void** state) {
  (void)state;
  const double R = 0.01, D = 0.0005, E = 1e4, nu = 0.3;
  const double hertz = 4.0 / 3.0 * E / (1 - nu * nu) * sqrt(R) * pow(D, 1.5);
  const double corot = hertz_force(MICA_MODEL_COROTATIONAL, 12);
  const double neo = hertz_force(MICA_MODEL_NEO_HOOKEAN, 12);
  printf("Hertz, d / R = 0.05, 8640 tets: theory %.5f N; co-rotational %.5f N (%+.1f %%), neo-Hookean %.5f N (%+.1f %%); "
         "neo-Hookean against co-rotational %+.2f %%\n",
         hertz, corot, 100 * (corot / hertz - 1), neo, 100 * (neo / hertz - 1), 100 * (neo / corot - 1));
  assert_true(fabs(neo / corot - 1) < 0.10);
  assert_true(fabs(neo / hertz - 1) < fabs(corot / hertz - 1) + 0.05); /* no worse than the mesh allows */
}

/* ------------------------------------------------------------------------------------------ */
/* The model value                                                                             */

static void test_model_value_is_checked(void** state) {
  (void)state;
  mica_world* w = make_world(MICA_SOLVER_MICA);
  mica_body_def bd = mica_body_def_default();
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.1, 0.1};
  const int32_t c[3] = {1, 1, 1};
  mica_body_id b = MICA_NULL_ID;
  bd.model = 3;
  assert_int_equal(mica_body_create_box(w, &bd, lo, hi, c, 5, &b), MICA_ERR_INVALID_ARGUMENT);
  assert_non_null(strstr(mica_world_last_error(w), "NEO_HOOKEAN 2"));
  bd.model = MICA_MODEL_NEO_HOOKEAN;
  bd.poisson_ratio = 0.495;
  OK(w, mica_body_create_box(w, &bd, lo, hi, c, 5, &b));
  mica_world_destroy(w);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_model_value_is_checked),
      cmocka_unit_test(test_uniaxial_compression_matches_closed_form),
      cmocka_unit_test(test_uniaxial_compression_with_the_factored_mica_sweep),
      cmocka_unit_test(test_volume_kept_under_bonded_compression),
      cmocka_unit_test(test_inverted_block_recovers),
      cmocka_unit_test(test_rigid_motion_moves_nothing),
      cmocka_unit_test(test_hertz_beside_the_corotational_body),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
