/* SPDX-License-Identifier: Apache-2.0 */
/* Tissue regions through the C API: a material per tet (mica_body_set_materials) and the regions
 * of mesh files (mica_body_get_tet_regions).
 *
 * - A bar of two materials in series under an end load stretches by F L1/(E1 A) + F L2/(E2 A)
 *   and carries the same stress F/A in every tet (the analytic solution, which linear tets
 *   represent exactly when the interface is a mesh plane).
 * - A sphere pressed above a nodule 10x stiffer than the tissue around it meets a steeper
 *   force-depth curve than pressed beside it.
 * - A 1000x stiffness contrast stays stable and converged with the default solver (MICA, the
 *   factored sweep) and with the exact one (DIRECT), and the two agree on the force.
 * - Gmsh 2.2 and 4.1 physical tags and TetGen region attributes are read per tet. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <mica/mica.h>

#define OK(world, call)                                                                              \
  do {                                                                                               \
    const mica_status s_ = (call);                                                                   \
    if (s_ != MICA_OK) fail_msg("%s: %s (%s)", #call, mica_status_string(s_), mica_world_last_error(world)); \
  } while (0)

static mica_world* make_world(int32_t solver) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = 0;
  wd.solver = solver;
  mica_world* w = NULL;
  assert_int_equal(mica_world_create(&wd, &w), MICA_OK);
  return w;
}

/* Fixes the nodes of `body` with rest coordinate `axis` <= `value`. */
static void fix_below(mica_world* w, mica_body_id body, int axis, double value) {
  const double point[3] = {axis == 0 ? value : 0, axis == 1 ? value : 0, axis == 2 ? value : 0};
  const double normal[3] = {axis == 0, axis == 1, axis == 2};
  int32_t count = 0;
  OK(w, mica_body_select_nodes_by_plane(w, body, point, normal, 1e-9, 1, NULL, 0, &count));
  int32_t* nodes = malloc(sizeof(int32_t) * (size_t)count);
  OK(w, mica_body_select_nodes_by_plane(w, body, point, normal, 1e-9, 1, nodes, count, &count));
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc;
  OK(w, mica_add_lpc(w, body, nodes, count, &fixed, &lpc));
  free(nodes);
}

/* Per tet, its rest centroid (3 doubles a tet); returns the tet count. The caller frees *out. */
static int32_t rest_centroids(mica_world* w, mica_body_id body, double** out) {
  int32_t n = 0, t = 0;
  OK(w, mica_body_get_counts(w, body, &n, &t, NULL));
  double* rest = malloc(sizeof(double) * 3 * (size_t)n);
  int32_t* tets = malloc(sizeof(int32_t) * 4 * (size_t)t);
  OK(w, mica_body_get_rest_positions(w, body, rest, n, NULL));
  OK(w, mica_body_get_tets(w, body, tets, t, NULL));
  double* c = calloc(3 * (size_t)t, sizeof(double));
  for (int32_t e = 0; e < t; ++e)
    for (int a = 0; a < 4; ++a)
      for (int k = 0; k < 3; ++k) c[3 * e + k] += 0.25 * rest[3 * tets[4 * e + a] + k];
  free(rest);
  free(tets);
  *out = c;
  return t;
}

/* ------------------------------------------------------------------------------------------ */
/* Two materials in series                                                                     */

static void test_bar_of_two_materials_in_series(void** state) {
  (void)state;
  const double L = 0.1, a = 0.02, A = a * a, E1 = 1e4, E2 = 1e5, F = 0.01;
  mica_world* w = make_world(MICA_SOLVER_DIRECT);
  mica_body_def bd = mica_body_def_default();
  bd.poisson_ratio = 0; /* uniaxial stress is then uniaxial strain: the fixed end constrains nothing more */
  const double lo[3] = {0, 0, 0}, hi[3] = {L, a, a};
  const int32_t cells[3] = {10, 2, 2};
  mica_body_id bar;
  OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &bar));
  fix_below(w, bar, 0, 0.0);

  /* E1 for x < L/2, E2 beyond: the interface x = L/2 is a plane of the mesh. */
  double* centroid = NULL;
  const int32_t t = rest_centroids(w, bar, &centroid);
  double* E = malloc(sizeof(double) * (size_t)t);
  for (int32_t e = 0; e < t; ++e) E[e] = centroid[3 * e] < L / 2 ? E1 : E2;
  OK(w, mica_body_set_materials(w, bar, E, NULL, NULL, t));

  /* The end load as the traction F/A on the end face, lumped to its nodes by the surface
   * triangles (area / 3 each): the consistent load of a uniform traction on linear triangles. */
  int32_t n = 0, tri = 0;
  OK(w, mica_body_get_counts(w, bar, &n, NULL, &tri));
  double* rest = malloc(sizeof(double) * 3 * (size_t)n);
  int32_t* surface = malloc(sizeof(int32_t) * 3 * (size_t)tri);
  OK(w, mica_body_get_rest_positions(w, bar, rest, n, NULL));
  OK(w, mica_body_get_surface(w, bar, surface, tri, NULL));
  double* fx = calloc((size_t)n, sizeof(double));
  double loaded_area = 0;
  for (int32_t k = 0; k < tri; ++k) {
    const int32_t* v = surface + 3 * k;
    if (fabs(rest[3 * v[0]] - L) > 1e-12 || fabs(rest[3 * v[1]] - L) > 1e-12 || fabs(rest[3 * v[2]] - L) > 1e-12)
      continue;
    double u[3], q[3];
    for (int c = 0; c < 3; ++c) u[c] = rest[3 * v[1] + c] - rest[3 * v[0] + c], q[c] = rest[3 * v[2] + c] - rest[3 * v[0] + c];
    const double area = 0.5 * fabs(u[1] * q[2] - u[2] * q[1]);
    loaded_area += area;
    for (int c = 0; c < 3; ++c) fx[v[c]] += F / A * area / 3;
  }
  assert_true(fabs(loaded_area - A) < 1e-12 * A);
  int32_t* nodes = malloc(sizeof(int32_t) * (size_t)n);
  double* forces = calloc(3 * (size_t)n, sizeof(double));
  int32_t loaded = 0;
  for (int32_t i = 0; i < n; ++i)
    if (fx[i] != 0) nodes[loaded] = i, forces[3 * loaded] = fx[i], ++loaded;
  OK(w, mica_body_set_node_forces(w, bar, nodes, forces, loaded));

  /* Static solution: implicit steps of 1 s, against the bar's ~0.1 s period, settle it. */
  for (int k = 0; k < 30; ++k) OK(w, mica_step(w, 1.0));

  double* x = malloc(sizeof(double) * 3 * (size_t)n);
  OK(w, mica_body_get_positions(w, bar, x, n, NULL));
  double stretch = 0;
  int32_t end_nodes = 0;
  for (int32_t i = 0; i < n; ++i)
    if (fabs(rest[3 * i] - L) < 1e-12) stretch += x[3 * i] - rest[3 * i], ++end_nodes;
  stretch /= end_nodes;
  const double expected = F * (L / 2) / (E1 * A) + F * (L / 2) / (E2 * A);
  const double single = F * L / (E1 * A); /* what one material (E1) would give */
  printf("two materials in series: stretch %.9e m, analytic F L1/(E1 A) + F L2/(E2 A) = %.9e m (E1 alone %.3e m)\n",
         stretch, expected, single);
  assert_true(fabs(stretch - expected) < 1e-6 * expected);

  /* The same stress F/A in every tet; the strain F/(E_i A) of its own material. */
  double* vm = malloc(sizeof(double) * (size_t)t);
  double* strain = malloc(sizeof(double) * 6 * (size_t)t);
  OK(w, mica_body_get_von_mises(w, bar, vm, t, NULL));
  OK(w, mica_body_get_strains(w, bar, strain, t, NULL));
  double worst_stress = 0, worst_strain = 0;
  for (int32_t e = 0; e < t; ++e) {
    worst_stress = fmax(worst_stress, fabs(vm[e] - F / A) / (F / A));
    const double eps = F / (E[e] * A);
    worst_strain = fmax(worst_strain, fabs(strain[6 * e] - eps) / eps);
    for (int c = 1; c < 6; ++c) worst_strain = fmax(worst_strain, fabs(strain[6 * e + c]) / eps);
  }
  printf("  von Mises vs F/A = %.4g Pa: worst relative error %.2e; strain vs F/(E_i A): %.2e\n", F / A, worst_stress,
         worst_strain);
  assert_true(worst_stress < 1e-6);
  assert_true(worst_strain < 1e-6);
  free(centroid), free(E), free(rest), free(surface), free(fx), free(nodes), free(forces), free(x), free(vm), free(strain);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* A nodule under the surface                                                                  */

/* The tissue block [-W, W] x [0, H] x [-D, D], fixed at y = 0, with a spherical nodule of
 * radius kNoduleR centred kNoduleDepth below the top face above x = kNoduleX (the tets whose
 * rest centroid lies inside) `contrast` times stiffer than the tissue. */
static const double W = 0.04, H = 0.03, D = 0.02, kSoftE = 1e4, kNoduleX = -0.02, kNoduleR = 0.008,
                    kNoduleDepth = 0.011, kSphereR = 0.01, kDt = 0.01;

typedef struct {
  mica_world* world;
  mica_body_id body;
  mica_tool_id sphere;
  int32_t nodule_tets;
} press;

static press make_press(int32_t solver, double contrast, double press_x) {
  press p;
  p.world = make_world(solver);
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = kSoftE;
  bd.poisson_ratio = 0.3;
  bd.rayleigh_beta = 0.01; /* damps the body's modes, so that each hold settles */
  const double lo[3] = {-W, 0, -D}, hi[3] = {W, H, D};
  const int32_t cells[3] = {16, 6, 8}; /* 5 mm cells; x = +-0.02 sit on like cells of the pattern */
  OK(p.world, mica_body_create_box(p.world, &bd, lo, hi, cells, 5, &p.body));
  fix_below(p.world, p.body, 1, 0.0);
  double* centroid = NULL;
  const int32_t t = rest_centroids(p.world, p.body, &centroid);
  double* E = malloc(sizeof(double) * (size_t)t);
  p.nodule_tets = 0;
  for (int32_t e = 0; e < t; ++e) {
    const double dx = centroid[3 * e] - kNoduleX, dy = centroid[3 * e + 1] - (H - kNoduleDepth), dz = centroid[3 * e + 2];
    const int inside = dx * dx + dy * dy + dz * dz < kNoduleR * kNoduleR;
    E[e] = inside ? contrast * kSoftE : kSoftE;
    p.nodule_tets += inside;
  }
  OK(p.world, mica_body_set_materials(p.world, p.body, E, NULL, NULL, t));
  free(centroid);
  free(E);
  mica_tool_def td = mica_tool_def_default();
  td.radius = kSphereR;
  td.position[0] = press_x;
  td.position[1] = H + kSphereR + 0.001;
  OK(p.world, mica_tool_create(p.world, &td, &p.sphere));
  return p;
}

/* Lowers the sphere 0.5 mm a step to each depth (m below the undeformed top face) and holds it
 * there 30 steps; force[k] is the upward force at depth k, stable[k] whether every step of that
 * went converged and the body came to rest (kinetic energy below 1e-6 of the elastic). */
static void force_depth_curve(press* p, double press_x, const double* depths, int count, double* force, int* stable) {
  double y = H + kSphereR + 0.001;
  const double q[4] = {1, 0, 0, 0};
  for (int k = 0; k < count; ++k) {
    const double target = H + kSphereR - depths[k];
    stable[k] = 1;
    for (int step = 0; step < 30 || y > target; ++step) {
      y = fmax(target, y - 0.0005);
      const double pos[3] = {press_x, y, 0};
      OK(p->world, mica_tool_set_pose(p->world, p->sphere, pos, q));
      const mica_status s = mica_step(p->world, kDt);
      if (s != MICA_OK) stable[k] = 0;
      if (s < 0) fail_msg("mica_step: %s (%s)", mica_status_string(s), mica_world_last_error(p->world));
    }
    double f[3], kinetic = 0, elastic = 0;
    OK(p->world, mica_tool_get_force(p->world, p->sphere, f, NULL, NULL));
    OK(p->world, mica_body_get_energy(p->world, p->body, &kinetic, &elastic, NULL));
    force[k] = f[1];
    if (!(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2])) || !(kinetic < 1e-6 * elastic)) stable[k] = 0;
  }
}

static void test_nodule_steepens_the_force_depth_curve(void** state) {
  (void)state;
  const double depths[4] = {0.001, 0.002, 0.003, 0.004};
  double above[4], beside[4];
  int stable_above[4], stable_beside[4];
  press p = make_press(MICA_SOLVER_MICA, 10, kNoduleX);
  assert_true(p.nodule_tets > 20);
  force_depth_curve(&p, kNoduleX, depths, 4, above, stable_above);
  mica_world_destroy(p.world);
  press q = make_press(MICA_SOLVER_MICA, 10, -kNoduleX);
  force_depth_curve(&q, -kNoduleX, depths, 4, beside, stable_beside);
  mica_world_destroy(q.world);
  printf("nodule 10x stiffer, %d tets: depth (mm), force above / beside (N)\n", p.nodule_tets);
  for (int k = 0; k < 4; ++k) {
    printf("  %.1f  %.6f  %.6f\n", 1e3 * depths[k], above[k], beside[k]);
    assert_true(stable_above[k] && stable_beside[k]);
    assert_true(above[k] > 0 && beside[k] > 0);
  }
  /* The slope over the last 2 mm, where the stress field of the contact reaches the nodule. */
  const double slope_above = (above[3] - above[1]) / 0.002, slope_beside = (beside[3] - beside[1]) / 0.002;
  printf("  slope 2-4 mm: above %.3f N/m, beside %.3f N/m, ratio %.3f\n", slope_above, slope_beside,
         slope_above / slope_beside);
  assert_true(slope_above > 1.2 * slope_beside);
}

static void test_thousandfold_contrast_is_stable_and_converged(void** state) {
  (void)state;
  const double depths[3] = {0.001, 0.002, 0.003};
  double mica_force[3], exact_force[3];
  int mica_stable[3], exact_stable[3];
  press p = make_press(MICA_SOLVER_MICA, 1000, kNoduleX);
  force_depth_curve(&p, kNoduleX, depths, 3, mica_force, mica_stable);
  mica_world_destroy(p.world);
  press q = make_press(MICA_SOLVER_DIRECT, 1000, kNoduleX);
  force_depth_curve(&q, kNoduleX, depths, 3, exact_force, exact_stable);
  mica_world_destroy(q.world);
  printf("nodule 1000x stiffer: depth (mm), force MICA / DIRECT (N)\n");
  for (int k = 0; k < 3; ++k) {
    printf("  %.1f  %.6f  %.6f\n", 1e3 * depths[k], mica_force[k], exact_force[k]);
    assert_true(mica_stable[k] && exact_stable[k]);
    assert_true(fabs(mica_force[k] - exact_force[k]) < 0.02 * exact_force[k]);
  }
}

/* ------------------------------------------------------------------------------------------ */
/* Regions of mesh files                                                                       */

static void expect_regions(const char* file, const int32_t* expected, int32_t count) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", MICA_TEST_DATA_DIR, file);
  mica_world* w = make_world(MICA_SOLVER_MICA);
  const mica_body_def bd = mica_body_def_default();
  mica_body_id body;
  OK(w, mica_body_create_from_file(w, &bd, path, &body));
  int32_t regions[64], n = 0;
  OK(w, mica_body_get_tet_regions(w, body, regions, 64, &n));
  assert_int_equal(n, count);
  for (int32_t e = 0; e < n; ++e) {
    if (regions[e] != expected[e]) fail_msg("%s: tet %d has region %d, want %d", file, e, regions[e], expected[e]);
  }
  mica_world_destroy(w);
}

static void test_regions_from_mesh_files(void** state) {
  (void)state;
  /* two_regions_*: the six tets of the unit cube, three in physical volume 7, two in 9, one in none. */
  const int32_t two[6] = {7, 7, 7, 9, 9, 0};
  expect_regions("two_regions_v22.msh", two, 6);
  expect_regions("two_regions_v41.msh", two, 6);
  expect_regions("two_regions.ele", two, 6);
  /* cube_*: every tet in physical volume 2 ("body"); the TetGen cube's attribute is 1. */
  const int32_t body[6] = {2, 2, 2, 2, 2, 2}, one[6] = {1, 1, 1, 1, 1, 1};
  expect_regions("cube_v22.msh", body, 6);
  expect_regions("cube_v41.msh", body, 6);
  expect_regions("cube.node", one, 6);
}

/* The regions map to materials: the body's node masses follow the density given per region. A
 * box made by the generator has region 0 everywhere. */
static void test_materials_by_region_set_the_mass(void** state) {
  (void)state;
  char path[1024];
  snprintf(path, sizeof path, "%s/two_regions_v41.msh", MICA_TEST_DATA_DIR);
  mica_world* w = make_world(MICA_SOLVER_MICA);
  const mica_body_def bd = mica_body_def_default();
  mica_body_id body;
  OK(w, mica_body_create_from_file(w, &bd, path, &body));
  int32_t regions[6];
  OK(w, mica_body_get_tet_regions(w, body, regions, 6, NULL));
  double rho[6];
  for (int e = 0; e < 6; ++e) rho[e] = regions[e] == 9 ? 3000 : 1000; /* each Kuhn tet has volume 1/6 */
  OK(w, mica_body_set_materials(w, body, NULL, NULL, rho, 6));
  double mass[8], total = 0;
  OK(w, mica_body_get_node_masses(w, body, mass, 8, NULL));
  for (int i = 0; i < 8; ++i) total += mass[i];
  assert_true(fabs(total - (4 * 1000 + 2 * 3000) / 6.0) < 1e-12 * total);
  const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
  const int32_t cells[3] = {2, 1, 1};
  mica_body_id box;
  OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 5, &box));
  int32_t box_regions[10], n = 0;
  OK(w, mica_body_get_tet_regions(w, box, box_regions, 10, &n));
  assert_int_equal(n, 10);
  for (int e = 0; e < n; ++e) assert_int_equal(box_regions[e], 0);
  mica_world_destroy(w);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_bar_of_two_materials_in_series),
      cmocka_unit_test(test_nodule_steepens_the_force_depth_curve),
      cmocka_unit_test(test_thousandfold_contrast_is_stable_and_converged),
      cmocka_unit_test(test_regions_from_mesh_files),
      cmocka_unit_test(test_materials_by_region_set_the_mass),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
