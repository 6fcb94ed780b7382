/* SPDX-License-Identifier: Apache-2.0 */
/* A body's mesh and fields through the C API: tets, node masses, strain and von Mises stress
 * per tet, and the VTK cell data.
 *
 * - Patch test: a box whose surface nodes are held on a uniform stretch eps along x (interior
 *   nodes free, static solution) reads back the strain (eps, 0, 0, 0, 0, 0) in every tet and the
 *   von Mises stress of Hooke's law: 2 mu eps = E eps / (1 + nu) (E eps for nu = 0).
 * - A rigid rotation of a co-rotational body strains nothing (a linear body sees strain).
 * - Node masses are rho V / 4 per tet per node (an oracle from the tets and rest positions), and
 *   sum to density times volume, consistent or lumped.
 * - VTK output carries "von_mises" and "region" per cell. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <mica/mica.h>

#define OK(world, call)                                                                              \
  do {                                                                                               \
    const mica_status s_ = (call);                                                                   \
    if (s_ != MICA_OK) fail_msg("%s: %s (%s)", #call, mica_status_string(s_), mica_world_last_error(world)); \
  } while (0)

static mica_world* make_world(void) {
  mica_world_def wd = mica_world_def_default(); /* the default solver: MICA, factored sweep */
  wd.gravity[1] = 0;
  mica_world* w = NULL;
  assert_int_equal(mica_world_create(&wd, &w), MICA_OK);
  return w;
}

typedef struct {
  int32_t nodes, tets;
  double* rest;
  int32_t* tet;
} mesh;

static mesh read_mesh(mica_world* w, mica_body_id body) {
  mesh m;
  OK(w, mica_body_get_counts(w, body, &m.nodes, &m.tets, NULL));
  m.rest = malloc(sizeof(double) * 3 * (size_t)m.nodes);
  m.tet = malloc(sizeof(int32_t) * 4 * (size_t)m.tets);
  OK(w, mica_body_get_rest_positions(w, body, m.rest, m.nodes, NULL));
  int32_t count = 0;
  OK(w, mica_body_get_tets(w, body, m.tet, m.tets, &count));
  assert_int_equal(count, m.tets);
  return m;
}
static void free_mesh(mesh* m) { free(m->rest), free(m->tet); }

static double tet_volume(const mesh* m, int32_t e) {
  const double* p[4];
  for (int a = 0; a < 4; ++a) p[a] = m->rest + 3 * m->tet[4 * e + a];
  double u[3], v[3], q[3];
  for (int k = 0; k < 3; ++k) u[k] = p[1][k] - p[0][k], v[k] = p[2][k] - p[0][k], q[k] = p[3][k] - p[0][k];
  return (u[0] * (v[1] * q[2] - v[2] * q[1]) - u[1] * (v[0] * q[2] - v[2] * q[0]) + u[2] * (v[0] * q[1] - v[1] * q[0])) / 6;
}

/* Holds every node on the surface (or every node, all_nodes) at target(rest) with one fixed
 * constraint; returns it. */
static mica_lpc_id hold(mica_world* w, mica_body_id body, const mesh* m, int all_nodes,
                        void (*target)(const double* X, double* x, const void* arg), const void* arg) {
  int32_t tri = 0;
  OK(w, mica_body_get_counts(w, body, NULL, NULL, &tri));
  int32_t* surface = malloc(sizeof(int32_t) * 3 * (size_t)tri);
  OK(w, mica_body_get_surface(w, body, surface, tri, NULL));
  char* on = calloc((size_t)m->nodes, 1);
  for (int32_t k = 0; k < 3 * tri; ++k) on[surface[k]] = 1;
  int32_t* nodes = malloc(sizeof(int32_t) * (size_t)m->nodes);
  double* targets = malloc(sizeof(double) * 3 * (size_t)m->nodes);
  int32_t count = 0;
  for (int32_t i = 0; i < m->nodes; ++i) {
    if (!all_nodes && !on[i]) continue;
    target(m->rest + 3 * i, targets + 3 * count, arg);
    nodes[count++] = i;
  }
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc;
  OK(w, mica_add_lpc(w, body, nodes, count, &fixed, &lpc));
  OK(w, mica_lpc_set_targets(w, lpc, targets, count));
  free(surface), free(on), free(nodes), free(targets);
  return lpc;
}

/* ------------------------------------------------------------------------------------------ */
/* Patch test                                                                                  */

static void stretch_x(const double* X, double* x, const void* arg) {
  const double eps = *(const double*)arg;
  x[0] = X[0] * (1 + eps), x[1] = X[1], x[2] = X[2];
}

static void stretch_patch(double nu) {
  const double E = 2e4, eps = 1e-3;
  mica_world* w = make_world();
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = E;
  bd.poisson_ratio = nu;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.08, 0.06};
  const int32_t cells[3] = {4, 3, 3}; /* interior nodes: 3 x 2 x 2, free */
  mica_body_id box;
  OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 5, &box));
  mesh m = read_mesh(w, box);
  hold(w, box, &m, 0, stretch_x, &eps);
  for (int k = 0; k < 40; ++k) OK(w, mica_step(w, 0.5)); /* static: steps far above the box's periods */

  double* strain = malloc(sizeof(double) * 6 * (size_t)m.tets);
  double* vm = malloc(sizeof(double) * (size_t)m.tets);
  int32_t count = 0;
  OK(w, mica_body_get_strains(w, box, strain, m.tets, &count));
  assert_int_equal(count, m.tets);
  OK(w, mica_body_get_von_mises(w, box, vm, m.tets, &count));
  assert_int_equal(count, m.tets);
  /* Uniaxial strain: sigma_xx = (lambda + 2 mu) eps, sigma_yy = sigma_zz = lambda eps, so
   * von Mises = |sigma_xx - sigma_yy| = 2 mu eps. */
  const double mu = E / (2 * (1 + nu)), expected_vm = 2 * mu * eps;
  double worst_strain = 0, worst_vm = 0;
  for (int32_t e = 0; e < m.tets; ++e) {
    const double want[6] = {eps, 0, 0, 0, 0, 0};
    for (int c = 0; c < 6; ++c) worst_strain = fmax(worst_strain, fabs(strain[6 * e + c] - want[c]));
    worst_vm = fmax(worst_vm, fabs(vm[e] - expected_vm));
  }
  printf("stretch patch, nu = %.2f, %d tets: strain error %.2e (of eps %.0e), von Mises %.6g Pa (analytic %.6g Pa), "
         "error %.2e Pa\n",
         nu, m.tets, worst_strain, eps, vm[0], expected_vm, worst_vm);
  assert_true(worst_strain < 1e-6 * eps);
  assert_true(worst_vm < 1e-6 * expected_vm);
  free(strain), free(vm), free_mesh(&m);
  mica_world_destroy(w);
}

static void test_stretch_patch_nu0_reads_E_times_strain(void** state) {
  (void)state;
  stretch_patch(0.0);
}
static void test_stretch_patch_reads_hookes_law(void** state) {
  (void)state;
  stretch_patch(0.3);
}

/* ------------------------------------------------------------------------------------------ */
/* Rigid rotation                                                                              */

/* 90 degrees about the axis (1, 1, 1) / sqrt 3 through the origin: x -> (z, x, y). */
static void rotate(const double* X, double* x, const void* arg) {
  (void)arg;
  x[0] = X[2], x[1] = X[0], x[2] = X[1];
}

/* Largest |strain component| of a box turned rigidly by 90 degrees, as its model sees it. */
static double strain_after_rotation(int32_t model) {
  mica_world* w = make_world();
  mica_body_def bd = mica_body_def_default();
  bd.model = model;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.05, 0.05};
  const int32_t cells[3] = {4, 2, 2};
  mica_body_id box;
  OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &box));
  mesh m = read_mesh(w, box);
  hold(w, box, &m, 1, rotate, NULL);
  OK(w, mica_step(w, 0.01)); /* every node held: one step reaches the targets */
  double* x = malloc(sizeof(double) * 3 * (size_t)m.nodes);
  OK(w, mica_body_get_positions(w, box, x, m.nodes, NULL));
  for (int32_t i = 0; i < m.nodes; ++i) {
    double want[3];
    rotate(m.rest + 3 * i, want, NULL);
    for (int k = 0; k < 3; ++k) assert_true(fabs(x[3 * i + k] - want[k]) < 1e-12);
  }
  double* strain = malloc(sizeof(double) * 6 * (size_t)m.tets);
  OK(w, mica_body_get_strains(w, box, strain, m.tets, NULL));
  double worst = 0;
  for (int32_t k = 0; k < 6 * m.tets; ++k) worst = fmax(worst, fabs(strain[k]));
  free(x), free(strain), free_mesh(&m);
  mica_world_destroy(w);
  return worst;
}

static void test_rigid_rotation_has_no_corotated_strain(void** state) {
  (void)state;
  const double corotational = strain_after_rotation(MICA_MODEL_COROTATIONAL);
  const double linear = strain_after_rotation(MICA_MODEL_LINEAR);
  printf("rigid rotation by 90 degrees: largest strain component, co-rotational %.2e, linear %.3f\n", corotational,
         linear);
  assert_true(corotational < 1e-10);
  assert_true(linear > 0.5); /* sym(Q) - I: the linear model sees the rotation as strain */
}

/* ------------------------------------------------------------------------------------------ */
/* Node masses                                                                                 */

static void masses(int32_t mass_kind) {
  const double rho = 1100, a = 0.1, b = 0.04, c = 0.03;
  mica_world* w = make_world();
  mica_body_def bd = mica_body_def_default();
  bd.density = rho;
  bd.mass = mass_kind;
  const double lo[3] = {0, 0, 0}, hi[3] = {a, b, c};
  const int32_t cells[3] = {5, 2, 3};
  mica_body_id box;
  OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 6, &box));
  mesh m = read_mesh(w, box);
  /* Two densities: rho in the first half of the tets, 3 rho in the rest. */
  double* density = malloc(sizeof(double) * (size_t)m.tets);
  for (int32_t e = 0; e < m.tets; ++e) density[e] = e < m.tets / 2 ? rho : 3 * rho;

  for (int pass = 0; pass < 2; ++pass) {
    if (pass == 1) OK(w, mica_body_set_materials(w, box, NULL, NULL, density, m.tets));
    double* oracle = calloc((size_t)m.nodes, sizeof(double));
    double expected_total = 0;
    for (int32_t e = 0; e < m.tets; ++e) {
      const double rv = (pass ? density[e] : rho) * tet_volume(&m, e);
      expected_total += rv;
      for (int k = 0; k < 4; ++k) oracle[m.tet[4 * e + k]] += rv / 4;
    }
    if (pass == 0) assert_true(fabs(expected_total - rho * a * b * c) < 1e-12 * expected_total);
    double* mass = malloc(sizeof(double) * (size_t)m.nodes);
    int32_t count = 0;
    OK(w, mica_body_get_node_masses(w, box, mass, m.nodes, &count));
    assert_int_equal(count, m.nodes);
    double total = 0;
    for (int32_t i = 0; i < m.nodes; ++i) {
      total += mass[i];
      assert_true(fabs(mass[i] - oracle[i]) < 1e-12 * oracle[i]);
    }
    printf("node masses (%s, %s): total %.9g kg, density x volume %.9g kg\n",
           mass_kind == MICA_MASS_LUMPED ? "lumped" : "consistent", pass ? "two densities" : "one density", total,
           expected_total);
    assert_true(fabs(total - expected_total) < 1e-12 * expected_total);
    free(oracle), free(mass);
  }
  free(density), free_mesh(&m);
  mica_world_destroy(w);
}

static void test_node_masses_sum_to_density_times_volume(void** state) {
  (void)state;
  masses(MICA_MASS_CONSISTENT);
  masses(MICA_MASS_LUMPED);
}

/* ------------------------------------------------------------------------------------------ */
/* VTK                                                                                         */

/* The values of the CELL_DATA scalar `name` in the file at `path` (count of them returned). */
static int read_cell_scalar(const char* path, const char* name, double* out, int capacity) {
  FILE* f = fopen(path, "r");
  assert_non_null(f);
  char line[256], header[128];
  snprintf(header, sizeof header, "SCALARS %s double 1", name);
  int found = 0, count = 0;
  while (fgets(line, sizeof line, f)) {
    if (strncmp(line, header, strlen(header)) == 0) {
      found = 1;
      assert_non_null(fgets(line, sizeof line, f)); /* LOOKUP_TABLE default */
      while (count < capacity && fscanf(f, "%lf", &out[count]) == 1) ++count;
      break;
    }
  }
  fclose(f);
  assert_true(found);
  return count;
}

static void test_vtk_carries_stress_and_region(void** state) {
  (void)state;
  const double eps = 2e-3;
  mica_world* w = make_world();
  mica_body_def bd = mica_body_def_default();
  bd.poisson_ratio = 0;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.05, 0.05};
  const int32_t cells[3] = {2, 1, 1};
  mica_body_id box;
  OK(w, mica_body_create_box(w, &bd, lo, hi, cells, 5, &box));
  mesh m = read_mesh(w, box);
  hold(w, box, &m, 1, stretch_x, &eps);
  OK(w, mica_step(w, 0.01));
  double vm[16];
  OK(w, mica_body_get_von_mises(w, box, vm, 16, NULL));
  char path[] = "/tmp/mica-fields-XXXXXX";
  const int fd = mkstemp(path);
  assert_true(fd >= 0);
  close(fd);
  OK(w, mica_body_write_vtk(w, box, path));
  double written[32], region[32];
  assert_int_equal(read_cell_scalar(path, "von_mises", written, 32), m.tets);
  assert_int_equal(read_cell_scalar(path, "region", region, 32), m.tets);
  for (int32_t e = 0; e < m.tets; ++e) {
    assert_true(written[e] == vm[e]); /* 17 digits: read back exactly */
    assert_true(fabs(written[e] - 1e4 * eps) < 1e-9 * 1e4 * eps);
    assert_true(region[e] == 0);
  }
  OK(w, mica_world_write_vtk(w, path));
  assert_int_equal(read_cell_scalar(path, "von_mises", written, 32), m.tets);
  unlink(path);
  free_mesh(&m);
  mica_world_destroy(w);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_stretch_patch_nu0_reads_E_times_strain),
      cmocka_unit_test(test_stretch_patch_reads_hookes_law),
      cmocka_unit_test(test_rigid_rotation_has_no_corotated_strain),
      cmocka_unit_test(test_node_masses_sum_to_density_times_volume),
      cmocka_unit_test(test_vtk_carries_stress_and_region),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
