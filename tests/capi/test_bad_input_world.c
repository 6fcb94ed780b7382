/* SPDX-License-Identifier: Apache-2.0 */
/* Bad input to capi/world.cpp through the C ABI: world creation and its def, gravity, the step,
 * the stats, VTK output; failed steps are undone whole, and failed calls leave no trace that only
 * stepping would show. The checks are in bad_input_util.h. */
#include "bad_input_util.h"

/* ------------------------------------------------------------------------------------------ */
/* NULL pointers                                                                               */

static const double kZero3[3] = {0, 0, 0};

static mica_status gravity_without_world(bad_call* c) {
  (void)c;
  return mica_world_set_gravity(NULL, kZero3);
}
static mica_status step_without_world(bad_call* c) {
  (void)c;
  return mica_step(NULL, 0.01);
}
static mica_status stats_without_world(bad_call* c) {
  (void)c;
  mica_world_stats st;
  memset(&st, 0, sizeof st);
  st.struct_size = sizeof st;
  return mica_world_get_stats(NULL, &st);
}
static mica_status body_vtk_without_world(bad_call* c) {
  return mica_body_write_vtk(NULL, c->fx->body, tmp_path("null.vtk"));
}
static mica_status world_vtk_without_world(bad_call* c) {
  (void)c;
  return mica_world_write_vtk(NULL, tmp_path("null.vtk"));
}
static mica_status create_without_def(bad_call* c) {
  mica_world* w = (mica_world*)&w; /* not NULL: creation must clear it */
  const mica_status s = mica_world_create(NULL, &w);
  if (w) bad_wrong(c, "*out_world is %p, not NULL", (void*)w);
  return s;
}
static mica_status create_without_out(bad_call* c) {
  (void)c;
  const mica_world_def wd = mica_world_def_default();
  return mica_world_create(&wd, NULL);
}
static mica_status gravity_null(bad_call* c) { return mica_world_set_gravity(c->fx->world, NULL); }
static mica_status stats_null(bad_call* c) { return mica_world_get_stats(c->fx->world, NULL); }
static mica_status body_vtk_null(bad_call* c) { return mica_body_write_vtk(c->fx->world, c->fx->body, NULL); }
static mica_status world_vtk_null(bad_call* c) { return mica_world_write_vtk(c->fx->world, NULL); }

static const bad_case kNullCases[] = {
    {"mica_world_set_gravity: NULL world", gravity_without_world, MICA_ERR_NULL_ARGUMENT, "world",
     .no_world = NO_WORLD},
    {"mica_step: NULL world", step_without_world, MICA_ERR_NULL_ARGUMENT, "world", .no_world = NO_WORLD},
    {"mica_world_get_stats: NULL world", stats_without_world, MICA_ERR_NULL_ARGUMENT, "world", .no_world = NO_WORLD},
    {"mica_body_write_vtk: NULL world", body_vtk_without_world, MICA_ERR_NULL_ARGUMENT, "world", .no_world = NO_WORLD},
    {"mica_world_write_vtk: NULL world", world_vtk_without_world, MICA_ERR_NULL_ARGUMENT, "world",
     .no_world = NO_WORLD},
    {"mica_world_create: NULL def", create_without_def, MICA_ERR_NULL_ARGUMENT, "def", .no_world = NO_WORLD},
    {"mica_world_create: NULL out_world", create_without_out, MICA_ERR_NULL_ARGUMENT, "out_world",
     .no_world = NO_WORLD},
    /* The *_init functions have no world: their message goes to mica_world_last_error(NULL), which
     * the header defines as the last failed call on this thread that had no world. */
    {"mica_world_def_init: NULL def", def_init_without_def, MICA_ERR_NULL_ARGUMENT, "def", .with.arg = WORLD_DEF,
     .no_world = NO_WORLD},
    {"mica_world_set_gravity: NULL gravity", gravity_null, MICA_ERR_NULL_ARGUMENT, "gravity"},
    {"mica_world_get_stats: NULL out", stats_null, MICA_ERR_NULL_ARGUMENT, "out"},
    {"mica_body_write_vtk: NULL path", body_vtk_null, MICA_ERR_NULL_ARGUMENT, "path"},
    {"mica_world_write_vtk: NULL path", world_vtk_null, MICA_ERR_NULL_ARGUMENT, "path"},
};

static void test_null_pointers(void** state) {
  fixture* fx = *state;
  mica_world_destroy(NULL); /* allowed */
  assert_non_null(mica_world_last_error(NULL));
  RUN_BAD_CASES(fx, kNullCases);
}

/* ------------------------------------------------------------------------------------------ */
/* The world def: values outside their domain, enums, struct sizes, versions                   */

/* Each spoils one field of a default def, with the variant's bad value. */
static void gravity(mica_world_def* d, int i) { d->gravity[i / 3] = kNonfinite[i % 3]; }
static const double kBadTolerance[] = {NAN, INFINITY, -INFINITY, 0.0, -1e-8};
static void tolerance(mica_world_def* d, int i) {
  d->solver = MICA_SOLVER_PCG;
  d->tolerance = kBadTolerance[i];
}
static const int32_t kBadIterations[] = {0, -1, INT32_MIN};
static void max_iterations(mica_world_def* d, int i) {
  d->solver = MICA_SOLVER_PCG;
  d->max_iterations = kBadIterations[i];
}
static const double kBadSpeed[] = {NAN, INFINITY, -INFINITY, 0.0, -1.0};
static void max_recovery_speed(mica_world_def* d, int i) { d->max_recovery_speed = kBadSpeed[i]; }
static const int32_t kBadSweeps[] = {0, -1, INT32_MIN};
static void pgs_sweeps(mica_world_def* d, int i) {
  d->solver = MICA_SOLVER_MICA;
  d->pgs_sweeps = kBadSweeps[i];
}
static const int32_t kBadNorm[] = {2, -1, INT32_MAX};
static void paper_norm(mica_world_def* d, int i) { d->paper_norm = kBadNorm[i]; }
static const double kBadRelaxation[] = {0, 2, -1, NAN};
static void relaxation(mica_world_def* d, int i) { d->relaxation = kBadRelaxation[i]; }
static const double kBadBudget[] = {-1, NAN, INFINITY};
static void time_budget_ms(mica_world_def* d, int i) { d->time_budget_ms = kBadBudget[i]; }
static const int32_t kBadThreads[] = {-1, 1025, INT32_MIN};
static void threads(mica_world_def* d, int i) { d->threads = kBadThreads[i]; }
static const double kBadRelin[] = {-1e-3, NAN, INFINITY};
static void relinearise_tolerance(mica_world_def* d, int i) { d->relinearise_tolerance = kBadRelin[i]; }
static const int32_t kBadRefactor[] = {-1, INT32_MIN};
static void refactor_interval(mica_world_def* d, int i) { d->refactor_interval = kBadRefactor[i]; }
static const int32_t kBadSweepKind[] = {2, -1, INT32_MAX};
static void mica_sweep(mica_world_def* d, int i) { d->mica_sweep = kBadSweepKind[i]; }
static const int32_t kBadSolver[] = {99, -1, MICA_SOLVER_MICA + 1, INT32_MIN};
static void solver(mica_world_def* d, int i) { d->solver = kBadSolver[i]; }
/* A host's job system (never called: every def below is refused). */
static void* enqueue_nothing(mica_task_fn task, int32_t items, int32_t min_range, void* context, void* user) {
  (void)task, (void)items, (void)min_range, (void)context, (void)user;
  return NULL;
}
static void finish_nothing(void* handle, void* user) { (void)handle, (void)user; }
static void job_system(mica_world_def* d, int32_t worker_count) {
  d->enqueue_task = enqueue_nothing;
  d->finish_task = finish_nothing;
  d->task_worker_count = worker_count;
}
static void enqueue_only(mica_world_def* d, int i) {
  (void)i;
  job_system(d, 2);
  d->finish_task = NULL;
}
static void finish_only(mica_world_def* d, int i) {
  (void)i;
  job_system(d, 2);
  d->enqueue_task = NULL;
}
static const int32_t kBadWorkerCount[] = {0, -1, 1025, INT32_MIN};
static void task_worker_count(mica_world_def* d, int i) {
  if (i < (int)COUNT_OF(kBadWorkerCount))
    job_system(d, kBadWorkerCount[i]);
  else
    d->task_worker_count = 2; /* without a job system */
}
static const int32_t kThreadsBesideJobs[] = {0, 2, 4};
static void threads_beside_jobs(mica_world_def* d, int i) {
  job_system(d, 2);
  d->threads = kThreadsBesideJobs[i];
}
static const uint32_t kOtherVersion[] = {(MICA_VERSION_MAJOR + 1) * 10000u + MICA_VERSION_MINOR * 100u,
                                         (MICA_VERSION_MAJOR + 1) * 10000u, 990000u, UINT32_MAX};
static void header_version(mica_world_def* d, int i) { d->header_version = kOtherVersion[i]; }

static mica_status create_spoiled(bad_call* c) {
  mica_world_def wd = mica_world_def_default();
  c->with.world_def(&wd, c->i);
  return create_world(c, &wd);
}

/* Another major version through the FFI entry point (mica_world_def_init names it). */
static mica_status create_from_other_version(bad_call* c) {
  mica_world_def fd;
  const mica_status init = mica_world_def_init(&fd, (uint32_t)sizeof fd, kOtherVersion[c->i]);
  if (init != MICA_OK) return bad_wrong(c, "mica_world_def_init(%u) returned %d", kOtherVersion[c->i], init), init;
  if (fd.header_version != kOtherVersion[c->i])
    bad_wrong(c, "mica_world_def_init set header_version %u, not %u", fd.header_version, kOtherVersion[c->i]);
  return create_world(c, &fd);
}

static mica_status create_with_bad_size(bad_call* c) {
  any_def d;
  memset(&d, 0, sizeof d);
  d.world = mica_world_def_default();
  d.world.struct_size = bad_struct_size(c->i, sizeof d.world);
  return create_world(c, &d.world);
}

static const bad_case kDefCases[] = {
    {"mica_world_create: non-finite gravity", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "gravity", 9,
     {.world_def = gravity}, NO_WORLD},
    {"mica_world_create: tolerance", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "tolerance", COUNT_OF(kBadTolerance),
     {.world_def = tolerance}, NO_WORLD},
    {"mica_world_create: max_iterations", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "max_iterations",
     COUNT_OF(kBadIterations), {.world_def = max_iterations}, NO_WORLD},
    {"mica_world_create: max_recovery_speed", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "max_recovery_speed",
     COUNT_OF(kBadSpeed), {.world_def = max_recovery_speed}, NO_WORLD},
    {"mica_world_create: pgs_sweeps", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "pgs_sweeps", COUNT_OF(kBadSweeps),
     {.world_def = pgs_sweeps}, NO_WORLD},
    {"mica_world_create: paper_norm", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "paper_norm", COUNT_OF(kBadNorm),
     {.world_def = paper_norm}, NO_WORLD},
    {"mica_world_create: relaxation", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "relaxation", COUNT_OF(kBadRelaxation),
     {.world_def = relaxation}, NO_WORLD},
    {"mica_world_create: time_budget_ms", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "time_budget_ms",
     COUNT_OF(kBadBudget), {.world_def = time_budget_ms}, NO_WORLD},
    {"mica_world_create: threads", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "threads", COUNT_OF(kBadThreads),
     {.world_def = threads}, NO_WORLD},
    {"mica_world_create: relinearise_tolerance", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "relinearise_tolerance",
     COUNT_OF(kBadRelin), {.world_def = relinearise_tolerance}, NO_WORLD},
    {"mica_world_create: refactor_interval", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "refactor_interval",
     COUNT_OF(kBadRefactor), {.world_def = refactor_interval}, NO_WORLD},
    {"mica_world_create: mica_sweep", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "mica_sweep", COUNT_OF(kBadSweepKind),
     {.world_def = mica_sweep}, NO_WORLD},
    {"mica_world_create: solver", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "solver", COUNT_OF(kBadSolver),
     {.world_def = solver}, NO_WORLD},
    {"mica_world_create: enqueue_task without finish_task", create_spoiled, MICA_ERR_INVALID_ARGUMENT,
     "def->finish_task is NULL", 1, {.world_def = enqueue_only}, NO_WORLD},
    {"mica_world_create: finish_task without enqueue_task", create_spoiled, MICA_ERR_INVALID_ARGUMENT,
     "def->enqueue_task is NULL", 1, {.world_def = finish_only}, NO_WORLD},
    {"mica_world_create: task_worker_count", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "def->task_worker_count",
     COUNT_OF(kBadWorkerCount) + 1, {.world_def = task_worker_count}, NO_WORLD},
    {"mica_world_create: threads beside a job system", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "def->threads",
     COUNT_OF(kThreadsBesideJobs), {.world_def = threads_beside_jobs}, NO_WORLD},
    {"mica_world_create: struct_size", create_with_bad_size, MICA_ERR_STRUCT_SIZE, "struct_size", 3,
     .no_world = NO_WORLD},
    {"mica_world_def_init: struct_size", def_init_with_bad_size, MICA_ERR_STRUCT_SIZE, NULL, 3, .with.arg = WORLD_DEF,
     .no_world = NO_WORLD},
    {"mica_world_create: header_version of another major", create_spoiled, MICA_ERR_VERSION_MISMATCH, NULL,
     COUNT_OF(kOtherVersion), {.world_def = header_version}, NO_WORLD},
    {"mica_world_create: def from mica_world_def_init of another major", create_from_other_version,
     MICA_ERR_VERSION_MISMATCH, NULL, COUNT_OF(kOtherVersion), .no_world = NO_WORLD},
};

static void test_bad_world_def(void** state) {
  fixture* fx = *state;
  RUN_BAD_CASES(fx, kDefCases);
  /* The exact size works and writes exactly that much. */
  union {
    mica_world_def d;
    unsigned char bytes[sizeof(mica_world_def) + 16];
  } w;
  memset(&w, 0xcd, sizeof w);
  EXPECT_STATUS(MICA_OK, mica_world_def_init(&w.d, (uint32_t)sizeof(mica_world_def), MICA_VERSION_NUMBER));
  for (size_t i = sizeof(mica_world_def); i < sizeof w.bytes; ++i) assert_int_equal(w.bytes[i], 0xcd);
  assert_int_equal(w.d.struct_size, sizeof(mica_world_def));
  /* Another minor or patch of the same major is fine. */
  mica_world_def wd = mica_world_def_default();
  wd.header_version = MICA_VERSION_MAJOR * 10000u + 99u * 100u + 99u;
  mica_world* nw = NULL;
  EXPECT_STATUS(MICA_OK, mica_world_create(&wd, &nw));
  assert_non_null(nw);
  mica_world_destroy(nw);
}

/* ------------------------------------------------------------------------------------------ */
/* Gravity, the time step, the stats, VTK output                                              */

static mica_status set_nonfinite_gravity(bad_call* c) {
  double g[3] = {0, -9.81, 0};
  g[c->i / 3] = kNonfinite[c->i % 3];
  return mica_world_set_gravity(c->fx->world, g);
}

/* Below the floor of 1e-9 s too (0.4 took 1e-200 and reported infinite forces). */
static const double kBadDt[] = {0.0,   -0.0,   -0.01,  -1.0,    1.0000001, 2.0,   1e300, NAN,
                                INFINITY, -INFINITY, -NAN, 5e-324, 1e-300,    1e-160, 1e-10, 9.999e-10};
static mica_status step_bad_dt(bad_call* c) { return mica_step(c->fx->world, kBadDt[c->i]); }

/* The stats of another size are left alone but for struct_size, which is read. */
static mica_status stats_with_bad_size(bad_call* c) {
  union {
    mica_world_stats s;
    unsigned char bytes[sizeof(mica_world_stats) + 16];
  } st;
  memset(&st, 0xab, sizeof st);
  const uint32_t size = bad_struct_size(c->i, sizeof st.s);
  st.s.struct_size = size;
  const mica_status s = mica_world_get_stats(c->fx->world, &st.s);
  if (st.s.struct_size != size) bad_wrong(c, "struct_size became %u", st.s.struct_size);
  return bytes_unwritten(c, st.bytes + sizeof(uint32_t), sizeof st.bytes - sizeof(uint32_t), 0xab, s);
}

static const char* missing_dir_vtk(bad_call* c) {
  bad_needle(c, 0, "%s/no-such-dir/out.vtk", g_dir);
  return c->needle[0];
}
static mica_status body_vtk_missing_dir(bad_call* c) {
  return mica_body_write_vtk(c->fx->world, c->fx->body, missing_dir_vtk(c));
}
static mica_status world_vtk_missing_dir(bad_call* c) { return mica_world_write_vtk(c->fx->world, missing_dir_vtk(c)); }
static mica_status body_vtk_directory(bad_call* c) { return mica_body_write_vtk(c->fx->world, c->fx->body, g_dir); }
static mica_status world_vtk_directory(bad_call* c) { return mica_world_write_vtk(c->fx->world, g_dir); }
static mica_status world_vtk_empty_path(bad_call* c) { return mica_world_write_vtk(c->fx->world, ""); }

static const bad_case kWorldCases[] = {
    {"mica_world_set_gravity: non-finite", set_nonfinite_gravity, MICA_ERR_INVALID_ARGUMENT, "gravity", 9},
    {"mica_step: dt outside [1e-9, 1] s", step_bad_dt, MICA_ERR_INVALID_ARGUMENT, "[1e-9, 1] s", COUNT_OF(kBadDt)},
    {"mica_world_get_stats: struct_size", stats_with_bad_size, MICA_ERR_STRUCT_SIZE, "struct_size", 3},
    {"mica_body_write_vtk: missing directory", body_vtk_missing_dir, MICA_ERR_IO, NULL},
    {"mica_world_write_vtk: missing directory", world_vtk_missing_dir, MICA_ERR_IO, NULL},
    {"mica_body_write_vtk: a directory", body_vtk_directory, MICA_ERR_IO, NULL},
    {"mica_world_write_vtk: a directory", world_vtk_directory, MICA_ERR_IO, NULL},
    {"mica_world_write_vtk: empty path", world_vtk_empty_path, MICA_ERR_IO, NULL},
};

static void test_bad_world_calls(void** state) {
  fixture* fx = *state;
  RUN_BAD_CASES(fx, kWorldCases);
  /* The edges of [1e-9, 1] are accepted. */
  EXPECT_STATUS(MICA_OK, mica_step(fx->world, 1.0));
  EXPECT_STATUS(MICA_OK, mica_step(fx->world, 1e-6));
  EXPECT_STATUS(MICA_OK, mica_step(fx->world, 1e-9));
}

/* ------------------------------------------------------------------------------------------ */
/* Failed calls leave no trace that only stepping would show (loads, constraints, gravity)     */

static mica_world* twin_world(mica_body_id* body) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[0] = 0.5;
  mica_world* w = NULL;
  if (mica_world_create(&wd, &w) != MICA_OK) return NULL;
  const mica_body_def bd = mica_body_def_default();
  if (mica_body_create_box(w, &bd, kLo, kHi, kCells, 6, body) != MICA_OK) return NULL;
  const int32_t fixed[1] = {0};
  mica_lpc_def d = mica_lpc_def_default();
  mica_lpc_id lpc;
  if (mica_add_lpc(w, *body, fixed, 1, &d, &lpc) != MICA_OK) return NULL;
  return w;
}

static void test_failed_calls_leave_no_trace(void** state) {
  (void)state;
  mica_body_id ba = 0, bb = 0;
  mica_world* a = twin_world(&ba);
  mica_world* b = twin_world(&bb);
  assert_non_null(a);
  assert_non_null(b);
  int32_t n = 0;
  REQUIRE_OK_W(a, mica_body_get_counts(a, ba, &n, NULL, NULL));

  /* On world a only: calls that fail part-way through their input. */
  const int32_t forced[3] = {5, 6, n}; /* the last is out of range */
  const double forces[9] = {0, 0, 10, 0, 0, 10, 0, 0, 10};
  EXPECT_STATUS(MICA_ERR_OUT_OF_RANGE, mica_body_set_node_forces(a, ba, forced, forces, 3));
  double nan_forces[9] = {0, 0, 10, 0, 0, 10, 0, 0, NAN};
  const int32_t forced_ok[3] = {5, 6, 7};
  EXPECT_STATUS(MICA_ERR_INVALID_ARGUMENT, mica_body_set_node_forces(a, ba, forced_ok, nan_forces, 3));
  mica_lpc_def d = mica_lpc_def_default();
  mica_lpc_id lpc = 0;
  const int32_t pinned[3] = {7, 8, -1};
  EXPECT_STATUS(MICA_ERR_OUT_OF_RANGE, mica_add_lpc(a, ba, pinned, 3, &d, &lpc));
  d.velocity[2] = NAN;
  EXPECT_STATUS(MICA_ERR_INVALID_ARGUMENT, mica_add_lpc(a, ba, forced_ok, 3, &d, &lpc));
  d = mica_lpc_def_default();
  d.kind = 42;
  EXPECT_STATUS(MICA_ERR_INVALID_ARGUMENT, mica_add_lpc(a, ba, forced_ok, 3, &d, &lpc));
  assert_int_equal(lpc, 0);
  const double g_bad[3] = {0, NAN, 0};
  EXPECT_STATUS(MICA_ERR_INVALID_ARGUMENT, mica_world_set_gravity(a, g_bad));
  EXPECT_STATUS(MICA_ERR_INVALID_ARGUMENT, mica_step(a, NAN));
  EXPECT_STATUS(MICA_ERR_INVALID_ARGUMENT, mica_step(a, 0));
  const mica_body_def bd = mica_body_def_default();
  const int32_t inverted[8] = {0, 1, 2, 3, 2, 1, 3, 4};
  mica_body_id extra = 0;
  EXPECT_STATUS(MICA_ERR_BAD_MESH, mica_body_create(a, &bd, kTwoTetNodes, 5, inverted, 2, &extra));
  EXPECT_STATUS(MICA_ERR_STALE_ID, mica_lpc_remove(a, ba));
  EXPECT_STATUS(MICA_ERR_STALE_ID, mica_body_destroy(a, ba + 1));

  for (int s = 0; s < 5; ++s) {
    REQUIRE_OK_W(a, mica_step(a, 0.01));
    REQUIRE_OK_W(b, mica_step(b, 0.01));
  }
  double* xa = calloc(3 * (size_t)n, sizeof(double));
  double* xb = calloc(3 * (size_t)n, sizeof(double));
  double* va = calloc(3 * (size_t)n, sizeof(double));
  double* vb = calloc(3 * (size_t)n, sizeof(double));
  REQUIRE_OK_W(a, mica_body_get_positions(a, ba, xa, n, NULL));
  REQUIRE_OK_W(b, mica_body_get_positions(b, bb, xb, n, NULL));
  REQUIRE_OK_W(a, mica_body_get_velocities(a, ba, va, n, NULL));
  REQUIRE_OK_W(b, mica_body_get_velocities(b, bb, vb, n, NULL));
  assert_memory_equal(xa, xb, 3 * (size_t)n * sizeof(double));
  assert_memory_equal(va, vb, 3 * (size_t)n * sizeof(double));
  /* and something did happen: node 0 is pinned, the others moved */
  double rest[3 * 64];
  REQUIRE_OK_W(a, mica_body_get_rest_positions(a, ba, rest, 64, NULL));
  assert_memory_equal(xa, rest, 3 * sizeof(double));
  assert_true(xa[3 * 9 + 1] < rest[3 * 9 + 1]);
  mica_world_stats sa, sb;
  memset(&sa, 0, sizeof sa);
  memset(&sb, 0, sizeof sb);
  sa.struct_size = sb.struct_size = sizeof sa;
  REQUIRE_OK_W(a, mica_world_get_stats(a, &sa));
  REQUIRE_OK_W(b, mica_world_get_stats(b, &sb));
  assert_int_equal(sa.step_count, 5);
  assert_int_equal(sb.step_count, 5);
  free(xa);
  free(xb);
  free(va);
  free(vb);
  mica_world_destroy(a);
  mica_world_destroy(b);
}

/* ------------------------------------------------------------------------------------------ */
/* Failed steps                                                                                */

/* A load whose exact answer overflows: 1e308 N on every node of the free 3 kg body. The
 * momentum balance of a backward-Euler step, sum(M v+) = sum(M v) + h sum(f), makes the mean
 * velocity after a 1 s step about 16e308 / 3 m/s, beyond DBL_MAX. Every solver must report
 * MICA_ERR_NUMERICAL and undo the step completely, the statistics included (the header: "on
 * an error the world is left exactly as it was"); none may return MICA_OK. */
static void check_numerical_failure(int32_t solver, int32_t sweep) {
  fixture* fx = new_fixture(solver, sweep);
  assert_non_null(fx);
  REQUIRE_OK_W(fx->world, mica_lpc_remove(fx->world, fx->lpc));
  int32_t nodes[64];
  double force[3 * 64], zero[3 * 64];
  assert_true(fx->node_count <= 64);
  for (int32_t k = 0; k < fx->node_count; ++k) {
    nodes[k] = k;
    force[3 * k] = force[3 * k + 1] = force[3 * k + 2] = 1e308;
    zero[3 * k] = zero[3 * k + 1] = zero[3 * k + 2] = 0;
  }
  REQUIRE_OK_W(fx->world, mica_body_set_node_forces(fx->world, fx->body, nodes, force, fx->node_count));
  /* Make the cleanup below run even when the check fails. */
  snapshot before;
  take_snapshot(fx, &before);
  fx->log_calls = 0;
  const mica_status got = mica_step(fx->world, 1.0);
  char failure[4096] = "";
  {
    snapshot after;
    take_snapshot(fx, &after);
    char why[512] = "";
    if (got != MICA_ERR_NUMERICAL)
      snprintf(failure, sizeof failure, "mica_step(1.0) with 1e308 N on every node returned %d (%s), want %s\n", got,
               mica_status_string(got), mica_status_string(MICA_ERR_NUMERICAL));
    if (snapshot_differs(&before, &after, why, sizeof why))
      snprintf(failure + strlen(failure), sizeof failure - strlen(failure),
               "mica_step(1.0) with 1e308 N on every node changed the world: %s\n", why);
    free_snapshot(&before);
    free_snapshot(&after);
  }
  /* Without the load the world steps again. */
  const mica_status unloaded = mica_body_set_node_forces(fx->world, fx->body, nodes, zero, fx->node_count);
  const mica_status again = mica_step(fx->world, 0.01);
  mica_world_destroy(fx->world);
  free(fx);
  if (failure[0]) {
    print_error("%s", failure);
    fail();
  }
  assert_int_equal(unloaded, MICA_OK);
  assert_int_equal(again, MICA_OK);
}

static void test_numerical_failure_direct(void** state) {
  (void)state;
  check_numerical_failure(MICA_SOLVER_DIRECT, MICA_SWEEP_FACTORED);
}
static void test_numerical_failure_pcg(void** state) {
  (void)state;
  check_numerical_failure(MICA_SOLVER_PCG, MICA_SWEEP_FACTORED);
}
static void test_numerical_failure_mica(void** state) {
  (void)state;
  check_numerical_failure(MICA_SOLVER_MICA, MICA_SWEEP_GAUSS_SEIDEL);
}
static void test_numerical_failure_mica_factored(void** state) {
  (void)state;
  check_numerical_failure(MICA_SOLVER_MICA, MICA_SWEEP_FACTORED);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_null_pointers, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_world_def, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_world_calls, setup, teardown),
      cmocka_unit_test(test_failed_calls_leave_no_trace),
      cmocka_unit_test(test_numerical_failure_direct),
      cmocka_unit_test(test_numerical_failure_pcg),
      cmocka_unit_test(test_numerical_failure_mica),
      cmocka_unit_test(test_numerical_failure_mica_factored),
  };
  return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
