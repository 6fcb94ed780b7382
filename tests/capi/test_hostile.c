/* SPDX-License-Identifier: Apache-2.0 */
/* What an adversarial run against 0.4.0 found (issue 16), through the C API: a mesh whose tets
 * repeat, device poses that are not unit or not finite once mapped, time steps too small for
 * double precision, a failed step that was not undone whole, and loaders given a FIFO, a device
 * or a huge file. Then a hostile device: a callback table that returns NaN, infinite and huge
 * poses, non-unit and flipped orientations, stalls, fails after some calls, or claims absurd
 * figures; each case gets a status, a bounded force and no crash.
 *
 * Files are written only to a fresh directory under /tmp, removed at the end. */
#define _POSIX_C_SOURCE 200809L
#include <float.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <time.h>
#include <unistd.h>

#include <mica/mica.h>
#include <mica/mica_device.h>

/* ------------------------------------------------------------------------------------------ */
/* Helpers                                                                                    */

static char g_dir[256];

static int group_setup(void** state) {
  (void)state;
  strcpy(g_dir, "/tmp/mica-capi-hostile-XXXXXX");
  return mkdtemp(g_dir) ? 0 : -1;
}

static int group_teardown(void** state) {
  (void)state;
  char cmd[300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", g_dir);
  return system(cmd) == 0 ? 0 : -1;
}

static const char* tmp_path(const char* name, char* out, size_t size) {
  snprintf(out, size, "%s/%s", g_dir, name);
  return out;
}

static void write_text(const char* path, const char* text) {
  FILE* f = fopen(path, "wb");
  assert_non_null(f);
  fputs(text, f);
  fclose(f);
}

static mica_world* make_world(int32_t solver) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = 0;
  wd.solver = solver;
  wd.mica_sweep = MICA_SWEEP_GAUSS_SEIDEL; /* MICA: the paper's sweep */
  wd.max_iterations = 2000;
  wd.tolerance = 1e-8;
  mica_world* w = NULL;
  assert_int_equal(mica_world_create(&wd, &w), MICA_OK);
  return w;
}

/* A 0.1 m block with its top at y = 0, held at its bottom. */
static mica_body_id add_block_of(mica_world* w, double density, double youngs_modulus) {
  mica_body_def bd = mica_body_def_default();
  bd.density = density;
  bd.youngs_modulus = youngs_modulus;
  bd.rayleigh_alpha = 1;
  const double lo[3] = {-0.05, -0.1, -0.05}, hi[3] = {0.05, 0, 0.05};
  const int32_t cells[3] = {3, 3, 3};
  mica_body_id body = 0;
  assert_int_equal(mica_body_create_box(w, &bd, lo, hi, cells, 6, &body), MICA_OK);
  int32_t base[64], n = 0;
  const double o[3] = {0, -0.1, 0}, up[3] = {0, 1, 0};
  assert_int_equal(mica_body_select_nodes_by_plane(w, body, o, up, 1e-9, 1, base, 64, &n), MICA_OK);
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc;
  assert_int_equal(mica_add_lpc(w, body, base, n, &fixed, &lpc), MICA_OK);
  return body;
}

static mica_body_id add_block(mica_world* w) { return add_block_of(w, 1000, 1e4); }

/* A 1 cm sphere whose bottom is `depth` m into the block's top. */
static mica_tool_id add_sphere(mica_world* w, double depth) {
  mica_tool_def td = mica_tool_def_default();
  td.radius = 0.01;
  td.position[0] = 0.003;
  td.position[1] = 0.01 - depth;
  td.position[2] = 0.002;
  mica_tool_id tool = 0;
  assert_int_equal(mica_tool_create(w, &td, &tool), MICA_OK);
  return tool;
}

static int contains(const char* text, const char* part) { return text && strstr(text, part) != NULL; }

static double norm3(const double v[3]) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/* ------------------------------------------------------------------------------------------ */
/* Defect 1: repeated tets                                                                    */

static const double kTetNodes[12] = {0, 0, 0, 0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1};

static void test_duplicate_tets_are_refused(void** state) {
  (void)state;
  mica_world* w = make_world(MICA_SOLVER_DIRECT);
  const mica_body_def bd = mica_body_def_default();
  mica_body_id body = 0;
  /* The same four nodes twice, also in another order: status OK and no surface in 0.4. */
  const int32_t twice[8] = {0, 1, 2, 3, 0, 1, 2, 3};
  assert_int_equal(mica_body_create(w, &bd, kTetNodes, 4, twice, 2, &body), MICA_ERR_BAD_MESH);
  assert_true(contains(mica_world_last_error(w), "same four nodes as tet 0"));
  const int32_t permuted[8] = {0, 1, 2, 3, 1, 0, 3, 2};
  assert_int_equal(mica_body_create(w, &bd, kTetNodes, 4, permuted, 2, &body), MICA_ERR_BAD_MESH);
  assert_true(contains(mica_world_last_error(w), "duplicate"));
  assert_int_equal(body, 0);
  /* Three tets on one face. */
  const double five[18] = {0, 0, 0, 0.1, 0, 0, 0, 0.1, 0, 0, 0, 0.1, 0.01, 0.01, 0.1, 0.02, 0.01, 0.12};
  const int32_t fan[12] = {0, 1, 2, 3, 0, 1, 2, 4, 0, 1, 2, 5};
  assert_int_equal(mica_body_create(w, &bd, five, 6, fan, 3, &body), MICA_ERR_BAD_MESH);
  assert_true(contains(mica_world_last_error(w), "belongs to 3 tets"));

  /* Both loaders. */
  char path[512];
  write_text(tmp_path("twice.msh", path, sizeof path),
             "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 0.1 0 0\n3 0 0.1 0\n4 0 0 0.1\n$EndNodes\n"
             "$Elements\n2\n1 4 2 1 1 1 2 3 4\n2 4 2 1 1 1 2 3 4\n$EndElements\n");
  assert_int_equal(mica_body_create_from_file(w, &bd, path, &body), MICA_ERR_BAD_MESH);
  assert_true(contains(mica_world_last_error(w), "same four nodes"));
  char node_path[512], ele_path[512];
  write_text(tmp_path("twice.node", node_path, sizeof node_path),
             "4 3 0 0\n0 0 0 0\n1 0.1 0 0\n2 0 0.1 0\n3 0 0 0.1\n");
  write_text(tmp_path("twice.ele", ele_path, sizeof ele_path), "2 4 0\n0 0 1 2 3\n1 0 1 2 3\n");
  assert_int_equal(mica_body_create_from_file(w, &bd, node_path, &body), MICA_ERR_BAD_MESH);
  assert_true(contains(mica_world_last_error(w), "same four nodes"));

  /* The crash of 0.4: a second body and a step (the empty surface's bounds were read). */
  add_block(w);
  assert_true(mica_step(w, 0.01) >= 0);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* A scripted callback device                                                                 */

typedef struct hostile {
  double position[3];
  double orientation[4];
  double timestamp;
  int fail_after;         /* > 0: read_state fails from this call on */
  int reads, writes;
  double sent[3];
  mica_device_info info;  /* what info() reports */
  int has_info;
} hostile;

static mica_status hostile_read(void* user, mica_device_state* out) {
  hostile* h = user;
  h->reads++;
  if (h->fail_after > 0 && h->reads >= h->fail_after) return MICA_ERR_DEVICE;
  for (int k = 0; k < 3; ++k) out->position[k] = h->position[k];
  for (int k = 0; k < 4; ++k) out->orientation[k] = h->orientation[k];
  h->timestamp += 0.001;
  out->timestamp = h->timestamp;
  return MICA_OK;
}

static mica_status hostile_write(void* user, const double force[3], const double torque[3]) {
  (void)torque;
  hostile* h = user;
  for (int k = 0; k < 3; ++k) h->sent[k] = force[k];
  h->writes++;
  return MICA_OK;
}

static mica_status hostile_info(void* user, mica_device_info* out) {
  hostile* h = user;
  if (!h->has_info) return MICA_ERR_UNSUPPORTED;
  const uint32_t size = out->struct_size;
  *out = h->info;
  out->struct_size = size;
  return MICA_OK;
}

static void hostile_init(hostile* h) {
  memset(h, 0, sizeof *h);
  h->orientation[0] = 1;
}

/* A device definition driving `tool` through h's callbacks (the table is copied at creation). */
static mica_device_def hostile_def(hostile* h, mica_tool_id tool) {
  static mica_device_callbacks cb;
  cb = (mica_device_callbacks){sizeof cb, 0, h, NULL, NULL, hostile_info, hostile_read, hostile_write};
  mica_device_def dd = mica_device_def_default();
  dd.backend = MICA_DEVICE_CALLBACKS;
  dd.callbacks = &cb;
  dd.tool = tool;
  return dd;
}

static mica_status add_hostile(mica_world* w, hostile* h, mica_tool_id tool, double scale, mica_device_id* out) {
  mica_device_def dd = hostile_def(h, tool);
  dd.scale = scale;
  return mica_device_create(w, &dd, out);
}

/* A block, a 1 cm sphere resting on it, and a fresh hostile device state. */
static mica_world* hostile_scene(int32_t solver, mica_tool_id* tool, hostile* h) {
  mica_world* w = make_world(solver);
  add_block(w);
  *tool = add_sphere(w, 0.0);
  hostile_init(h);
  return w;
}

static void assert_unit_pose(mica_world* w, mica_tool_id tool) {
  double p[3], q[4];
  assert_int_equal(mica_tool_get_pose(w, tool, p, q), MICA_OK);
  for (int k = 0; k < 3; ++k) assert_true(isfinite(p[k]));
  const double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  assert_true(fabs(n - 1) < 1e-12);
}

/* ------------------------------------------------------------------------------------------ */
/* Defect 4: device poses validated after mapping                                             */

static void test_device_poses_are_validated(void** state) {
  (void)state;
  hostile h;
  mica_tool_id tool = 0;
  mica_world* w = hostile_scene(MICA_SOLVER_DIRECT, &tool, &h);
  h.position[1] = 0.01 - 0.01; /* the sphere 1 cm deep */
  mica_device_id device = 0;
  assert_int_equal(add_hostile(w, &h, tool, 1.0, &device), MICA_OK);
  mica_device_state ds = {sizeof ds};
  double f[3];

  /* Slightly off unit (rounding in a driver): normalised, accepted. */
  h.orientation[0] = 1 + 1e-4;
  assert_int_equal(mica_device_poll(w, device, &ds, f), MICA_OK);
  assert_true(fabs(ds.orientation[0] - 1) < 1e-12);
  assert_int_equal(mica_step(w, 0.01), MICA_OK);
  assert_unit_pose(w, tool);
  int32_t contacts = 0;
  assert_int_equal(mica_tool_get_force(w, tool, NULL, NULL, &contacts), MICA_OK);
  assert_true(contacts > 0); /* 1 cm deep: it touches */

  /* |q| = 1.5 and 3e200: refused by poll; the tool keeps its last good pose. */
  const double bad_norms[] = {1.5, 0.5, 3e200, 0};
  for (size_t i = 0; i < sizeof bad_norms / sizeof bad_norms[0]; ++i) {
    h.orientation[0] = bad_norms[i];
    h.orientation[1] = h.orientation[2] = h.orientation[3] = 0;
    h.position[1] = -0.02;
    assert_int_equal(mica_device_poll(w, device, &ds, f), MICA_ERR_DEVICE);
    assert_true(f[0] == 0 && f[1] == 0 && f[2] == 0);
    assert_int_equal(mica_step(w, 0.01), MICA_OK);
    assert_unit_pose(w, tool);
    double p[3];
    assert_int_equal(mica_tool_get_pose(w, tool, p, NULL), MICA_OK);
    assert_true(fabs(p[1] - 0.0) < 1e-12); /* not moved to the refused reading */
  }
  mica_device_stats st = {sizeof st};
  assert_int_equal(mica_device_get_stats(w, device, &st), MICA_OK);
  assert_int_equal(st.last_status, MICA_ERR_DEVICE);
  assert_int_equal(st.failures, 4);
  assert_int_equal(mica_device_destroy(w, device), MICA_OK);

  /* A scale of 1e200 times a reading of 1e200: not finite in the scene, refused. */
  hostile_init(&h);
  assert_int_equal(add_hostile(w, &h, tool, 1e200, &device), MICA_OK);
  h.position[0] = 1e200;
  assert_int_equal(mica_device_poll(w, device, &ds, f), MICA_ERR_DEVICE);
  assert_int_equal(mica_step(w, 0.01), MICA_OK);
  assert_unit_pose(w, tool);
  double tf[3];
  assert_int_equal(mica_tool_get_force(w, tool, tf, NULL, NULL), MICA_OK);
  assert_true(isfinite(tf[0]) && isfinite(tf[1]) && isfinite(tf[2]));
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* Defects 7 and 8: time steps below the floor                                                */

static void test_time_steps_below_the_floor(void** state) {
  (void)state;
  const int32_t solvers[3] = {MICA_SOLVER_DIRECT, MICA_SOLVER_PCG, MICA_SOLVER_MICA};
  for (int s = 0; s < 3; ++s) {
    mica_world* w = make_world(solvers[s]);
    add_block(w);
    const mica_tool_id tool = add_sphere(w, 0.002);
    assert_true(mica_step(w, 0.01) >= 0);
    double before[3], after[3];
    assert_int_equal(mica_tool_get_force(w, tool, before, NULL, NULL), MICA_OK);
    /* 0.4: MICA_OK and an infinite force below ~1e-160 s; DIRECT at 5e-324 an internal message. */
    const double tiny[] = {1e-200, 5e-324, 1e-160, 9.99e-10};
    for (size_t i = 0; i < sizeof tiny / sizeof tiny[0]; ++i) {
      assert_int_equal(mica_step(w, tiny[i]), MICA_ERR_INVALID_ARGUMENT);
      const char* message = mica_world_last_error(w);
      assert_true(contains(message, "time step must be in [1e-9, 1] s"));
      assert_false(contains(message, "lemke"));
      assert_int_equal(mica_tool_get_force(w, tool, after, NULL, NULL), MICA_OK);
      assert_memory_equal(before, after, sizeof before);
    }
    /* At the floor: finite figures. */
    const mica_status st = mica_step(w, 1e-9);
    assert_true(st == MICA_OK || st == MICA_WARN_NOT_CONVERGED || st == MICA_ERR_NUMERICAL);
    assert_int_equal(mica_tool_get_force(w, tool, after, NULL, NULL), MICA_OK);
    assert_true(isfinite(after[0]) && isfinite(after[1]) && isfinite(after[2]));
    mica_world_destroy(w);
  }
}

/* ------------------------------------------------------------------------------------------ */
/* Defect 6: a failed step is undone whole                                                    */

typedef struct twin {
  mica_world* w;
  mica_body_id body;
  mica_tool_id tool;
  mica_device_id device;
  hostile dev;
} twin;

static void make_twin(twin* t, int32_t solver, int32_t sweep, int32_t refactor_interval, int with_device,
                      double youngs_modulus) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = 0;
  wd.solver = solver;
  wd.mica_sweep = sweep;
  wd.refactor_interval = refactor_interval;
  wd.max_iterations = 500;
  wd.tolerance = 1e-9;
  assert_int_equal(mica_world_create(&wd, &t->w), MICA_OK);
  /* Light (and soft enough): a load of 1e308 N makes its velocities overflow. */
  t->body = add_block_of(t->w, 1, youngs_modulus);
  t->tool = add_sphere(t->w, 0.002);
  hostile_init(&t->dev);
  t->device = 0;
  if (with_device) assert_int_equal(add_hostile(t->w, &t->dev, t->tool, 1.0, &t->device), MICA_OK);
}

/* A step that fails (a huge load makes the velocities overflow), then the load is removed. */
static void fail_a_step(twin* t, int step) {
  const int32_t node = 5;
  const double huge[3] = {1e308, -1e308, 1e308}, zero[3] = {0, 0, 0};
  assert_int_equal(mica_body_set_node_forces(t->w, t->body, &node, huge, 1), MICA_OK);
  if (step) assert_int_equal(mica_step(t->w, 0.01), MICA_ERR_NUMERICAL);
  assert_int_equal(mica_body_set_node_forces(t->w, t->body, &node, zero, 1), MICA_OK);
}

static void assert_same(twin* a, twin* b) {
  static double pa[3 * 4096], pb[3 * 4096];
  int32_t na = 0, nb = 0;
  assert_int_equal(mica_body_get_positions(a->w, a->body, pa, 4096, &na), MICA_OK);
  assert_int_equal(mica_body_get_positions(b->w, b->body, pb, 4096, &nb), MICA_OK);
  assert_int_equal(na, nb);
  assert_memory_equal(pa, pb, sizeof(double) * 3 * (size_t)na);
  assert_int_equal(mica_body_get_velocities(a->w, a->body, pa, 4096, &na), MICA_OK);
  assert_int_equal(mica_body_get_velocities(b->w, b->body, pb, 4096, &nb), MICA_OK);
  assert_memory_equal(pa, pb, sizeof(double) * 3 * (size_t)na);
  double fa[3], fb[3], ta[3], tb[3], qa[7], qb[7];
  int32_t ca, cb;
  assert_int_equal(mica_tool_get_force(a->w, a->tool, fa, ta, &ca), MICA_OK);
  assert_int_equal(mica_tool_get_force(b->w, b->tool, fb, tb, &cb), MICA_OK);
  assert_memory_equal(fa, fb, sizeof fa);
  assert_memory_equal(ta, tb, sizeof ta);
  assert_int_equal(ca, cb);
  assert_int_equal(mica_tool_get_pose(a->w, a->tool, qa, qa + 3), MICA_OK);
  assert_int_equal(mica_tool_get_pose(b->w, b->tool, qb, qb + 3), MICA_OK);
  assert_memory_equal(qa, qb, sizeof qa);
}

/* The device moves the tool; a step fails: the tool stays where the step found it. */
static void test_failed_step_leaves_the_device_tool(void** state) {
  (void)state;
  twin a, b;
  make_twin(&a, MICA_SOLVER_MICA, MICA_SWEEP_GAUSS_SEIDEL, 0, 1, 10);
  make_twin(&b, MICA_SOLVER_MICA, MICA_SWEEP_GAUSS_SEIDEL, 0, 1, 10);
  mica_device_state ds = {sizeof ds};
  double f[3];
  for (int k = 0; k < 12; ++k) {
    const double y = 0.01 - 0.002 - 0.0005 * k;
    a.dev.position[1] = b.dev.position[1] = y;
    assert_true(mica_device_poll(a.w, a.device, &ds, f) >= 0);
    assert_true(mica_device_poll(b.w, b.device, &ds, f) >= 0);
    if (k == 5) {
      fail_a_step(&a, 1);
      fail_a_step(&b, 0);
      assert_same(&a, &b); /* 0.4: a's tool had moved to the device's new pose */
    }
    assert_true(mica_step(a.w, 0.01) >= 0);
    assert_true(mica_step(b.w, 0.01) >= 0);
    assert_same(&a, &b);
  }
  mica_world_destroy(a.w);
  mica_world_destroy(b.w);
}

/* The factored sweep with a background refresh: the failed step shifts no schedule, and the
 * state saved after it restores into a fresh world that then steps as the original does. */
static void test_failed_step_keeps_the_factor_schedule(void** state) {
  (void)state;
  for (int interval = 1; interval <= 3; ++interval) {
    twin a, b, c;
    make_twin(&a, MICA_SOLVER_MICA, MICA_SWEEP_FACTORED, interval, 0, 1e4);
    make_twin(&b, MICA_SOLVER_MICA, MICA_SWEEP_FACTORED, interval, 0, 1e4);
    c.w = NULL;
    for (int k = 0; k < 14; ++k) {
      const double p[3] = {0.003, 0.01 - 0.002 - 0.001 * k, 0.002}, q[4] = {1, 0, 0, 0};
      assert_int_equal(mica_tool_set_pose(a.w, a.tool, p, q), MICA_OK);
      assert_int_equal(mica_tool_set_pose(b.w, b.tool, p, q), MICA_OK);
      if (k == 4 || k == 7 || k == 8) {
        fail_a_step(&a, 1);
        fail_a_step(&b, 0);
        /* c: a fresh world given a's state saved after the failed step. */
        size_t bytes = 0;
        assert_int_equal(mica_world_state_size(a.w, &bytes), MICA_OK);
        void* saved = malloc(bytes);
        assert_int_equal(mica_world_save_state(a.w, saved, bytes), MICA_OK);
        if (c.w) mica_world_destroy(c.w);
        make_twin(&c, MICA_SOLVER_MICA, MICA_SWEEP_FACTORED, interval, 0, 1e4);
        assert_int_equal(mica_world_restore_state(c.w, saved, bytes), MICA_OK);
        free(saved);
      }
      if (c.w) assert_int_equal(mica_tool_set_pose(c.w, c.tool, p, q), MICA_OK);
      assert_true(mica_step(a.w, 0.01) >= 0);
      assert_true(mica_step(b.w, 0.01) >= 0);
      assert_same(&a, &b); /* 0.4: 1.9e-13 m apart after the refresh that the failed step shifted */
      if (c.w) {
        assert_true(mica_step(c.w, 0.01) >= 0);
        assert_same(&a, &c); /* the next refresh adopts over the restored factor: see test_lagged_factor */
      }
    }
    mica_world_destroy(a.w);
    mica_world_destroy(b.w);
    mica_world_destroy(c.w);
  }
}

/* ------------------------------------------------------------------------------------------ */
/* Defect 9: the loaders read regular files of bounded size only                              */

static void test_loaders_refuse_special_and_huge_files(void** state) {
  (void)state;
  mica_world* w = make_world(MICA_SOLVER_DIRECT);
  const mica_body_def bd = mica_body_def_default();
  mica_body_id body = 0;
  char path[512];
  /* A FIFO named .msh: 0.4 waited for a writer forever. */
  tmp_path("fifo.msh", path, sizeof path);
  assert_int_equal(mkfifo(path, 0600), 0);
  assert_int_equal(mica_body_create_from_file(w, &bd, path, &body), MICA_ERR_IO);
  assert_true(contains(mica_world_last_error(w), "not a regular file"));
  /* A symlink to /dev/zero: 0.4 read until the address space was gone. */
  tmp_path("zero.msh", path, sizeof path);
  assert_int_equal(symlink("/dev/zero", path), 0);
  assert_int_equal(mica_body_create_from_file(w, &bd, path, &body), MICA_ERR_IO);
  assert_true(contains(mica_world_last_error(w), "not a regular file"));
  tmp_path("zero.node", path, sizeof path);
  assert_int_equal(symlink("/dev/zero", path), 0);
  assert_int_equal(mica_body_create_from_file(w, &bd, path, &body), MICA_ERR_IO);
  /* Above the cap (a sparse file: nothing is written). */
  tmp_path("huge.msh", path, sizeof path);
  FILE* f = fopen(path, "wb");
  assert_non_null(f);
  fclose(f);
  assert_int_equal(truncate(path, (off_t)(256u << 20) + 1), 0);
  assert_int_equal(mica_body_create_from_file(w, &bd, path, &body), MICA_ERR_IO);
  assert_true(contains(mica_world_last_error(w), "larger than"));
  unlink(path);
  /* A directory. */
  tmp_path("dir.msh", path, sizeof path);
  assert_int_equal(mkdir(path, 0700), 0);
  assert_int_equal(mica_body_create_from_file(w, &bd, path, &body), MICA_ERR_IO);
  assert_int_equal(body, 0);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* Hostile device modes                                                                       */

/* Runs `polls` servo cycles with `mutate` changing the device between them, a step every 10;
 * every force sent must be finite and within the clamp, every status in the documented set. */
typedef void (*mutate_fn)(hostile* h, int k);

static void run_hostile(const char* name, mutate_fn mutate, int polls, int expect_failures) {
  hostile h;
  mica_tool_id tool = 0;
  mica_world* w = hostile_scene(MICA_SOLVER_MICA, &tool, &h);
  mica_device_id device = 0;
  assert_int_equal(add_hostile(w, &h, tool, 1.0, &device), MICA_OK);
  mica_device_info info = {sizeof info};
  assert_int_equal(mica_device_get_info(w, device, &info), MICA_OK);
  mica_device_state ds = {sizeof ds};
  int failures = 0;
  double largest = 0;
  for (int k = 0; k < polls; ++k) {
    mutate(&h, k);
    double f[3] = {NAN, NAN, NAN};
    const mica_status st = mica_device_poll(w, device, &ds, f);
    assert_true(st == MICA_OK || st == MICA_WARN_DEVICE || st == MICA_ERR_DEVICE);
    if (st < 0) {
      failures++;
      assert_true(f[0] == 0 && f[1] == 0 && f[2] == 0);
    }
    assert_true(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2]));
    assert_true(norm3(f) <= info.max_force * (1 + 1e-12));
    assert_true(isfinite(h.sent[0]) && isfinite(h.sent[1]) && isfinite(h.sent[2]));
    assert_true(norm3(h.sent) <= info.max_force * (1 + 1e-12));
    if (norm3(f) > largest) largest = norm3(f);
    if (k % 10 == 9) {
      const mica_status s = mica_step(w, 0.01);
      assert_true(s == MICA_OK || s == MICA_WARN_NOT_CONVERGED);
      assert_unit_pose(w, tool);
    }
  }
  print_message("%-22s %d polls, %d refused, largest force %.3g N\n", name, polls, failures, largest);
  if (expect_failures) assert_true(failures > 0);
  else assert_int_equal(failures, 0);
  mica_device_stats st = {sizeof st};
  assert_int_equal(mica_device_get_stats(w, device, &st), MICA_OK);
  assert_int_equal(st.failures, failures);
  mica_world_destroy(w);
}

/* Pressing down 1 mm per 10 polls; every third poll something is wrong. */
static void press(hostile* h, int k) {
  h->position[0] = 0;
  h->position[1] = -0.0001 * k;
  h->position[2] = 0;
  h->orientation[0] = 1;
  h->orientation[1] = h->orientation[2] = h->orientation[3] = 0;
}
static void nan_pose(hostile* h, int k) {
  press(h, k);
  if (k % 3 == 2) h->position[k % 2] = NAN;
}
static void inf_pose(hostile* h, int k) {
  press(h, k);
  if (k % 3 == 2) h->position[1] = k % 2 ? INFINITY : -INFINITY;
}
static void huge_pose(hostile* h, int k) {
  press(h, k);
  if (k % 3 == 2) h->position[1] = k % 2 ? 1e300 : -1e300;
}
static void nan_orientation(hostile* h, int k) {
  press(h, k);
  if (k % 3 == 2) h->orientation[2] = NAN;
}
static void non_unit_orientation(hostile* h, int k) {
  press(h, k);
  if (k % 3 == 2) h->orientation[0] = k % 2 ? 1.5 : 1e-300;
}
static void flipped_orientation(hostile* h, int k) {
  press(h, k);
  if (k % 2) h->orientation[0] = -1; /* the same rotation: accepted */
}
static void fails_after_30(hostile* h, int k) {
  press(h, k);
  h->fail_after = 30;
}
static void clock_back(hostile* h, int k) {
  press(h, k);
  if (k % 7 == 6) h->timestamp -= 0.5;
}
static void stalls(hostile* h, int k) {
  press(h, k);
  if (k % 25 == 24) {
    const struct timespec pause = {0, 50 * 1000 * 1000};
    nanosleep(&pause, NULL);
  }
}

static void test_hostile_device_modes(void** state) {
  (void)state;
  run_hostile("NaN positions", nan_pose, 120, 1);
  run_hostile("infinite positions", inf_pose, 120, 1);
  run_hostile("huge positions", huge_pose, 120, 1);
  run_hostile("NaN orientations", nan_orientation, 120, 1);
  run_hostile("non-unit orientations", non_unit_orientation, 120, 1);
  run_hostile("flipped orientations", flipped_orientation, 120, 0);
  run_hostile("fails after 30 reads", fails_after_30, 120, 1);
  run_hostile("clock going back", clock_back, 120, 1);
  run_hostile("50 ms stalls", stalls, 100, 0);
}

/* After a 50 ms stall the rate limit allows the growth of two servo periods, not of 50 ms. */
static void test_rate_limit_after_a_stall(void** state) {
  (void)state;
  hostile h;
  mica_tool_id tool = 0;
  mica_world* w = hostile_scene(MICA_SOLVER_MICA, &tool, &h);
  mica_device_def dd = hostile_def(&h, tool);
  dd.force_mode = MICA_FORCE_HOLD;
  dd.filter_window = 1;
  dd.max_force_rate = 1000;  /* N/s: 1 N per ms */
  dd.stall_timeout = 1;      /* no fade in this test */
  mica_device_id device = 0;
  assert_int_equal(mica_device_create(w, &dd, &device), MICA_OK);
  /* Press 8 mm deep and let the simulation settle: a held force above the clamp (3.3 N). */
  h.position[1] = -0.008;
  mica_device_state ds = {sizeof ds};
  double f[3];
  assert_true(mica_device_poll(w, device, &ds, f) >= 0); /* zero: nothing published yet */
  for (int k = 0; k < 20; ++k) assert_true(mica_step(w, 0.01) >= 0);
  double tf[3];
  assert_int_equal(mica_tool_get_force(w, tool, tf, NULL, NULL), MICA_OK);
  /* The next read comes 50 ms late: at most 1000 N/s * 2 ms = 2 N of growth in that cycle
   * (0.4 allowed 1000 N/s * the whole gap, and jumped to the clamp). */
  const struct timespec pause = {0, 50 * 1000 * 1000};
  nanosleep(&pause, NULL);
  assert_true(mica_device_poll(w, device, &ds, f) >= 0);
  const double first = norm3(f);
  nanosleep(&pause, NULL);
  assert_true(mica_device_poll(w, device, &ds, f) >= 0);
  const double after = norm3(f);
  print_message("held force %.3f N; rendered %.4f N, then %.4f N, each after a 50 ms stall\n", norm3(tf), first,
                after);
  assert_true(norm3(tf) > 3.3);
  assert_true(first <= 2.0 + 1e-9);
  assert_true(after - first <= 2.0 + 1e-9);
  mica_world_destroy(w);
}

/* A device claiming absurd figures is refused at creation; one with sane figures is not. */
static void test_absurd_nominal_figures(void** state) {
  (void)state;
  hostile h;
  mica_tool_id tool = 0;
  mica_world* w = hostile_scene(MICA_SOLVER_MICA, &tool, &h);
  h.has_info = 1;
  h.info.struct_size = sizeof h.info;
  strcpy(h.info.name, "hostile");
  h.info.max_force = 1e300; /* 0.4: the clamp was 1e300 N */
  h.info.continuous_force = 1;
  h.info.nominal_stiffness = 500;
  h.info.nominal_damping = 1;
  h.info.workspace_radius = 0.1;
  mica_device_id device = 0;
  assert_int_equal(add_hostile(w, &h, tool, 1.0, &device), MICA_ERR_DEVICE);
  assert_true(contains(mica_world_last_error(w), "max_force"));
  h.info.max_force = 5;
  h.info.nominal_stiffness = 1e300;
  assert_int_equal(add_hostile(w, &h, tool, 1.0, &device), MICA_ERR_DEVICE);
  assert_true(contains(mica_world_last_error(w), "nominal_stiffness"));
  h.info.nominal_stiffness = 500;
  /* Found by fuzz_api: a filter window of INT32_MAX samples allocated 51 GB (ASan: out of memory). */
  mica_device_def dd = hostile_def(&h, tool);
  dd.filter_window = INT32_MAX;
  assert_int_equal(mica_device_create(w, &dd, &device), MICA_ERR_INVALID_ARGUMENT);
  assert_true(contains(mica_world_last_error(w), "filter window must be 1..10000"));
  assert_int_equal(add_hostile(w, &h, tool, 1.0, &device), MICA_OK);
  mica_device_info info = {sizeof info};
  assert_int_equal(mica_device_get_info(w, device, &info), MICA_OK);
  assert_true(info.max_force == 5);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* Defect 5: the exact frictional solve on one tet under a sphere                             */

static double now_s(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* 0.4 failed 3 of 5 steps with friction 1 and every step with friction 10, each after 1e6
 * box-PGS sweeps (0.2-0.7 s), and the time budget did not bound it. */
static void test_one_tet_under_a_frictional_sphere(void** state) {
  (void)state;
  const int32_t solvers[2] = {MICA_SOLVER_DIRECT, MICA_SOLVER_PCG};
  const double frictions[2] = {1, 10};
  for (int s = 0; s < 2; ++s)
    for (int f = 0; f < 2; ++f) {
      mica_world_def wd = mica_world_def_default();
      wd.solver = solvers[s];
      wd.time_budget_ms = 50;
      mica_world* w = NULL;
      assert_int_equal(mica_world_create(&wd, &w), MICA_OK);
      mica_body_def bd = mica_body_def_default();
      bd.youngs_modulus = 1e5;
      const int32_t tet[4] = {0, 1, 2, 3};
      mica_body_id body;
      assert_int_equal(mica_body_create(w, &bd, kTetNodes, 4, tet, 1, &body), MICA_OK);
      const int32_t base[3] = {0, 1, 3}; /* the nodes at y = 0 */
      const mica_lpc_def fixed = mica_lpc_def_default();
      mica_lpc_id lpc;
      assert_int_equal(mica_add_lpc(w, body, base, 3, &fixed, &lpc), MICA_OK);
      mica_tool_def td = mica_tool_def_default();
      td.radius = 0.02;
      td.friction = frictions[f];
      td.position[1] = 0.1 + 0.02 - 0.002; /* 2 mm onto the top node */
      mica_tool_id tool;
      assert_int_equal(mica_tool_create(w, &td, &tool), MICA_OK);
      double worst = 0;
      int ok = 0;
      for (int k = 0; k < 5; ++k) {
        const double p[3] = {0.001 * k, td.position[1] - 0.0005 * k, 0.0005 * k}, q[4] = {1, 0, 0, 0};
        assert_int_equal(mica_tool_set_pose(w, tool, p, q), MICA_OK);
        const double t0 = now_s();
        const mica_status st = mica_step(w, 0.01);
        const double t = now_s() - t0;
        if (t > worst) worst = t;
        assert_true(st == MICA_OK || st == MICA_WARN_NOT_CONVERGED);
        ok += st == MICA_OK;
        double force[3];
        int32_t contacts = 0;
        assert_int_equal(mica_tool_get_force(w, tool, force, NULL, &contacts), MICA_OK);
        assert_true(isfinite(force[0]) && isfinite(force[1]) && isfinite(force[2]));
        assert_true(contacts > 0);
      }
      print_message("%s, friction %g: %d of 5 steps MICA_OK, slowest %.1f ms\n",
                    solvers[s] == MICA_SOLVER_DIRECT ? "DIRECT" : "PCG", frictions[f], ok, 1e3 * worst);
      assert_int_equal(ok, 5);
      assert_true(worst < 1.0); /* a generous bound: sanitizer builds are several times slower */
      mica_world_destroy(w);
    }
}

/* A box tool teleported around a small box and onto a larger one (found by the API fuzzer,
 * found_teleported_box_507_contacts): hundreds of contact rows that no impulses satisfy, since
 * the tool presses the small box from every side. The factored sweep must give up in bounded
 * work and say so, not run its rounds to the iteration cap: MICA_WARN_NOT_CONVERGED, finite
 * results, fewer iterations than the cap (the impulses of such a problem grow by the same step
 * every round, so only the stall rule stops it). */
static void test_tool_closed_around_a_body(void** state) {
  (void)state;
  mica_world_def wd = mica_world_def_default(); /* the factored sweep, 200 iterations */
  wd.relinearise_max = 1;                        /* one solve a step: the cap is the step's */
  mica_world* w = NULL;
  assert_int_equal(mica_world_create(&wd, &w), MICA_OK);
  const mica_body_def bd = mica_body_def_default();
  const int32_t cells_big[3] = {2, 2, 2}, cells_small[3] = {1, 1, 1};
  const double big_lo[3] = {-0.05, -0.1, -0.05}, big_hi[3] = {0.05, 0, 0.05};
  const double small_lo[3] = {0, 0, 0}, small_hi[3] = {0.005, 0.005, 0.005};
  mica_body_id big, small;
  assert_int_equal(mica_body_create_box(w, &bd, big_lo, big_hi, cells_big, 5, &big), MICA_OK);
  assert_int_equal(mica_body_create_box(w, &bd, small_lo, small_hi, cells_small, 5, &small), MICA_OK);
  mica_tool_def td = mica_tool_def_default();
  td.shape = MICA_TOOL_BOX;
  td.half_extents[0] = td.half_extents[1] = td.half_extents[2] = 0.01;
  td.position[0] = -0.126;
  td.position[1] = -0.128;
  td.position[2] = 0.001;
  mica_tool_id tool;
  assert_int_equal(mica_tool_create(w, &td, &tool), MICA_OK);
  assert_int_equal(mica_step(w, 0.01) >= 0, 1);
  const double p[3] = {0.003, 0.005, 0.002}, q[4] = {1, 0, 0, 0};
  assert_int_equal(mica_tool_set_pose(w, tool, p, q), MICA_OK);
  const double t0 = now_s();
  assert_int_equal(mica_step(w, 0.01), MICA_WARN_NOT_CONVERGED);
  const double ms = 1e3 * (now_s() - t0);
  mica_world_stats st;
  memset(&st, 0, sizeof st);
  st.struct_size = sizeof st;
  assert_int_equal(mica_world_get_stats(w, &st), MICA_OK);
  print_message("enclosed body: %d contacts, %d iterations and %d solves, residual %.3g, %.1f ms\n", st.contacts,
                st.solver_iterations, st.solves, st.solver_residual, ms);
  assert_true(st.contacts > 100);
  assert_int_equal(st.converged, 0);
  assert_true(st.solver_iterations < wd.max_iterations);
  double force[3];
  assert_int_equal(mica_tool_get_force(w, tool, force, NULL, NULL), MICA_OK);
  assert_true(isfinite(force[0]) && isfinite(force[1]) && isfinite(force[2]));
  const mica_body_id bodies[2] = {big, small};
  for (int b = 0; b < 2; ++b) {
    double x[3 * 27];
    int32_t n = 0;
    assert_int_equal(mica_body_get_positions(w, bodies[b], x, 27, &n), MICA_OK);
    for (int32_t i = 0; i < 3 * n; ++i) assert_true(isfinite(x[i]));
  }
  mica_world_destroy(w);
}

/* A host's "no real limit" for the time budget (1e300, DBL_MAX) is no budget: the step converges
 * as without one (0.6 overflowed the clock's duration and stopped every step at once). */
static void test_a_huge_time_budget_is_no_budget(void** state) {
  (void)state;
  const double budgets[] = {0, 1e300, DBL_MAX, 86400e3 * 2};
  int32_t iterations[4];
  for (int k = 0; k < 4; ++k) {
    mica_world_def wd = mica_world_def_default();
    wd.time_budget_ms = budgets[k];
    mica_world* w = NULL;
    assert_int_equal(mica_world_create(&wd, &w), MICA_OK);
    add_block(w);
    add_sphere(w, 0.002);
    for (int s = 0; s < 3; ++s) assert_int_equal(mica_step(w, 0.01), MICA_OK);
    mica_world_stats stats = {sizeof stats};
    assert_int_equal(mica_world_get_stats(w, &stats), MICA_OK);
    assert_int_equal(stats.out_of_time, 0);
    assert_int_equal(stats.converged, 1);
    iterations[k] = stats.solver_iterations;
    assert_int_equal(iterations[k], iterations[0]);
    mica_world_destroy(w);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_duplicate_tets_are_refused),
      cmocka_unit_test(test_device_poses_are_validated),
      cmocka_unit_test(test_time_steps_below_the_floor),
      cmocka_unit_test(test_a_huge_time_budget_is_no_budget),
      cmocka_unit_test(test_failed_step_leaves_the_device_tool),
      cmocka_unit_test(test_failed_step_keeps_the_factor_schedule),
      cmocka_unit_test(test_loaders_refuse_special_and_huge_files),
      cmocka_unit_test(test_hostile_device_modes),
      cmocka_unit_test(test_rate_limit_after_a_stall),
      cmocka_unit_test(test_absurd_nominal_figures),
      cmocka_unit_test(test_one_tet_under_a_frictional_sphere),
      cmocka_unit_test(test_tool_closed_around_a_body),
  };
  return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
