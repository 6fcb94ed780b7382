/* SPDX-License-Identifier: Apache-2.0 */
/* Bad input through the C ABI: every entry point of mica.h, given bad input, returns a clear
 * status and a message that names what was wrong, leaves the world exactly as it was, and never
 * crashes.
 *
 * "Exactly as it was" is checked by one helper (EXPECT_FAIL) that snapshots the fixture world
 * before the call (positions, velocities, rest positions, surface, counts, energies, step count,
 * and the number of points the whole world writes to VTK, which counts its bodies' nodes) and
 * compares it bit for bit afterwards. It also checks that the world's log callback received the
 * same message at MICA_LOG_ERROR with the user pointer. Loads and constraints, which no getter
 * shows, are checked by stepping twin worlds (test_failed_calls_leave_no_trace).
 *
 * Files are written only to a fresh directory under /tmp, removed at the end. */
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
#include <sys/stat.h>
#include <unistd.h>

#include <mica/mica.h>

/* ------------------------------------------------------------------------------------------ */
/* Temporary files                                                                             */

static char g_dir[256];
static char g_files[64][512];
static int g_file_count;

/* g_dir/name, remembered for removal at the end. */
static const char* tmp_path(const char* name) {
  for (int i = 0; i < g_file_count; ++i) {
    const char* slash = strrchr(g_files[i], '/');
    if (slash && strcmp(slash + 1, name) == 0) return g_files[i];
  }
  if (g_file_count >= 64) return NULL;
  snprintf(g_files[g_file_count], sizeof g_files[0], "%s/%s", g_dir, name);
  return g_files[g_file_count++];
}

static const char* write_tmp(const char* name, const char* text) {
  const char* path = tmp_path(name);
  FILE* f = fopen(path, "wb");
  if (!f) return NULL;
  fputs(text, f);
  fclose(f);
  return path;
}

static int group_setup(void** state) {
  (void)state;
  strcpy(g_dir, "/tmp/mica-capi-bad-input-XXXXXX");
  return mkdtemp(g_dir) ? 0 : -1;
}

static int group_teardown(void** state) {
  (void)state;
  for (int i = 0; i < g_file_count; ++i) {
    struct stat st;
    if (stat(g_files[i], &st) == 0) {
      if (S_ISDIR(st.st_mode)) rmdir(g_files[i]);
      else unlink(g_files[i]);
    }
  }
  rmdir(g_dir);
  return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* Fixture: a world with a live body, a destroyed body, a live and a removed constraint       */

typedef struct fixture {
  mica_world* world;
  mica_body_id body;      /* live 3x1x1 box, stepped once so velocities are not zero */
  mica_body_id dead_body; /* destroyed */
  mica_lpc_id lpc;        /* live: x = 0 face fixed */
  mica_lpc_id dead_lpc;   /* removed */
  int32_t node_count;
  int log_calls;
  int32_t log_level;
  void* log_user;
  char log_message[2048];
} fixture;

static void record_log(int32_t level, const char* message, void* user) {
  fixture* fx = (fixture*)user;
  fx->log_calls += 1;
  fx->log_level = level;
  fx->log_user = user;
  snprintf(fx->log_message, sizeof fx->log_message, "%s", message ? message : "(null)");
}

static const double kLo[3] = {0, 0, 0};
static const double kHi[3] = {0.3, 0.1, 0.1};
static const int32_t kCells[3] = {3, 1, 1};

#define REQUIRE_OK(call)                                                                             \
  do {                                                                                               \
    const mica_status s_ = (call);                                                                   \
    if (s_ != MICA_OK) {                                                                             \
      print_error("%s:%d: %s returned %s\n  last error: %s\n", __FILE__, __LINE__, #call,            \
                  mica_status_string(s_), mica_world_last_error(NULL));                              \
      _fail(__FILE__, __LINE__);                                                                     \
    }                                                                                                \
  } while (0)

#define REQUIRE_OK_W(world, call)                                                                    \
  do {                                                                                               \
    const mica_status s_ = (call);                                                                   \
    if (s_ != MICA_OK) {                                                                             \
      print_error("%s:%d: %s returned %s\n  last error: %s\n", __FILE__, __LINE__, #call,            \
                  mica_status_string(s_), mica_world_last_error(world));                             \
      _fail(__FILE__, __LINE__);                                                                     \
    }                                                                                                \
  } while (0)

/* The fixture world with the given solver (and, for MICA, sweep); NULL on failure. */
static fixture* new_fixture(int32_t solver, int32_t sweep) {
  fixture* fx = calloc(1, sizeof *fx);
  if (!fx) return NULL;
  mica_world_def wd = mica_world_def_default();
  wd.solver = solver;
  wd.mica_sweep = sweep;
  wd.log = record_log;
  wd.log_user = fx;
  if (mica_world_create(&wd, &fx->world) != MICA_OK) return NULL;
  const mica_body_def bd = mica_body_def_default();
  if (mica_body_create_box(fx->world, &bd, kLo, kHi, kCells, 6, &fx->body) != MICA_OK) return NULL;
  mica_body_def moved = bd;
  moved.translation[0] = 1.0;
  if (mica_body_create_box(fx->world, &moved, kLo, kHi, kCells, 5, &fx->dead_body) != MICA_OK) return NULL;
  if (mica_body_destroy(fx->world, fx->dead_body) != MICA_OK) return NULL;
  if (mica_body_get_counts(fx->world, fx->body, &fx->node_count, NULL, NULL) != MICA_OK) return NULL;

  const double normal[3] = {1, 0, 0};
  int32_t face[64];
  int32_t count = 0;
  if (mica_body_select_nodes_by_plane(fx->world, fx->body, kLo, normal, 1e-9, 1, face, 64, &count) != MICA_OK)
    return NULL;
  mica_lpc_def fixed = mica_lpc_def_default();
  if (mica_add_lpc(fx->world, fx->body, face, count, &fixed, &fx->lpc) != MICA_OK) return NULL;
  mica_lpc_def plane = mica_lpc_def_default();
  plane.kind = MICA_LPC_PLANE;
  plane.direction[0][0] = 0;
  plane.direction[0][2] = 1;
  const int32_t tip[1] = {fx->node_count - 1};
  if (mica_add_lpc(fx->world, fx->body, tip, 1, &plane, &fx->dead_lpc) != MICA_OK) return NULL;
  if (mica_lpc_remove(fx->world, fx->dead_lpc) != MICA_OK) return NULL;
  if (mica_step(fx->world, 0.01) != MICA_OK) return NULL;
  fx->log_calls = 0;
  return fx;
}

static int setup(void** state) {
  fixture* fx = new_fixture(MICA_SOLVER_DIRECT, MICA_SWEEP_FACTORED);
  *state = fx;
  return fx ? 0 : -1;
}

static int teardown(void** state) {
  fixture* fx = *state;
  /* The world is still usable after all the failures. */
  const mica_status s = mica_step(fx->world, 0.01);
  int32_t n = 0;
  const mica_status c = mica_body_get_counts(fx->world, fx->body, &n, NULL, NULL);
  mica_world_destroy(fx->world);
  const int bad = s != MICA_OK || c != MICA_OK || n != fx->node_count;
  free(fx);
  if (bad) print_error("teardown: the world is no longer usable after the failed calls\n");
  return bad ? -1 : 0;
}

/* ------------------------------------------------------------------------------------------ */
/* Messages                                                                                    */

static int is_ident(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

/* `phrase` occurs in `text` as whole words: not inside a longer identifier or number
 * ("world" does not match inside "mica_world_create", "1" does not match inside "17"). */
static int has_phrase(const char* text, const char* phrase) {
  const size_t n = strlen(phrase);
  if (n == 0) return 1;
  for (const char* p = strstr(text, phrase); p; p = strstr(p + 1, phrase)) {
    const int left_ok = p == text || !is_ident(p[-1]) || !is_ident(phrase[0]);
    const int right_ok = p[n] == '\0' || !is_ident(p[n]) || !is_ident(phrase[n - 1]);
    if (left_ok && right_ok) return 1;
  }
  return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* Snapshot of everything observable about the fixture world                                  */

typedef struct snapshot {
  mica_status counts_status;
  int32_t nodes, tets, tris;
  double* x;
  double* v;
  double* rest;
  int32_t* surface;
  int64_t step_count;
  mica_world_stats stats; /* all of it: counters, residual, timings */
  double kinetic, elastic, potential;
  long world_points;
} snapshot;

static long vtk_points(const char* path) {
  FILE* f = fopen(path, "rb");
  if (!f) return -1;
  char line[512];
  long n = -2;
  while (fgets(line, sizeof line, f))
    if (sscanf(line, "POINTS %ld", &n) == 1) break;
  fclose(f);
  return n;
}

static void take_snapshot(const fixture* fx, snapshot* s) {
  memset(s, 0, sizeof *s);
  s->counts_status = mica_body_get_counts(fx->world, fx->body, &s->nodes, &s->tets, &s->tris);
  const size_t n = (size_t)(s->nodes > 0 ? s->nodes : 0), t = (size_t)(s->tris > 0 ? s->tris : 0);
  s->x = calloc(3 * n + 1, sizeof(double));
  s->v = calloc(3 * n + 1, sizeof(double));
  s->rest = calloc(3 * n + 1, sizeof(double));
  s->surface = calloc(3 * t + 1, sizeof(int32_t));
  mica_body_get_positions(fx->world, fx->body, s->x, s->nodes, NULL);
  mica_body_get_velocities(fx->world, fx->body, s->v, s->nodes, NULL);
  mica_body_get_rest_positions(fx->world, fx->body, s->rest, s->nodes, NULL);
  mica_body_get_surface(fx->world, fx->body, s->surface, s->tris, NULL);
  memset(&s->stats, 0, sizeof s->stats);
  s->stats.struct_size = sizeof s->stats;
  mica_world_get_stats(fx->world, &s->stats);
  s->step_count = s->stats.step_count;
  mica_body_get_energy(fx->world, fx->body, &s->kinetic, &s->elastic, &s->potential);
  const char* path = tmp_path("snapshot.vtk");
  s->world_points = mica_world_write_vtk(fx->world, path) == MICA_OK ? vtk_points(path) : -3;
}

static void free_snapshot(snapshot* s) {
  free(s->x);
  free(s->v);
  free(s->rest);
  free(s->surface);
}

/* Nonzero when a and b differ; says where. */
static int snapshot_differs(const snapshot* a, const snapshot* b, char* why, size_t why_size) {
  const size_t n = (size_t)(a->nodes > 0 ? a->nodes : 0), t = (size_t)(a->tris > 0 ? a->tris : 0);
  if (a->counts_status != MICA_OK || b->counts_status != MICA_OK)
    return snprintf(why, why_size, "the fixture body cannot be read back"), 1;
  if (a->nodes != b->nodes || a->tets != b->tets || a->tris != b->tris)
    return snprintf(why, why_size, "counts changed: %d/%d/%d -> %d/%d/%d", a->nodes, a->tets, a->tris, b->nodes,
                    b->tets, b->tris),
           1;
  if (memcmp(a->x, b->x, 3 * n * sizeof(double)) != 0) return snprintf(why, why_size, "positions changed"), 1;
  if (memcmp(a->v, b->v, 3 * n * sizeof(double)) != 0) return snprintf(why, why_size, "velocities changed"), 1;
  if (memcmp(a->rest, b->rest, 3 * n * sizeof(double)) != 0)
    return snprintf(why, why_size, "rest positions changed"), 1;
  if (memcmp(a->surface, b->surface, 3 * t * sizeof(int32_t)) != 0)
    return snprintf(why, why_size, "surface changed"), 1;
  if (a->step_count != b->step_count)
    return snprintf(why, why_size, "step_count changed: %lld -> %lld", (long long)a->step_count,
                    (long long)b->step_count),
           1;
  if (memcmp(&a->stats, &b->stats, sizeof a->stats) != 0) {
    int stage = -1;
    for (int k = 0; k < MICA_STAGE_COUNT && stage < 0; ++k)
      if (memcmp(&a->stats.stages[k], &b->stats.stages[k], sizeof a->stats.stages[k]) != 0) stage = k;
    return snprintf(why, why_size,
                    "the stats changed: converged %d -> %d, solver_iterations %d -> %d, residual %g -> %g, "
                    "first changed stage: %s",
                    a->stats.converged, b->stats.converged, a->stats.solver_iterations, b->stats.solver_iterations,
                    a->stats.solver_residual, b->stats.solver_residual, stage < 0 ? "none" : mica_stage_name(stage)),
           1;
  }
  if (memcmp(&a->kinetic, &b->kinetic, sizeof(double)) != 0 ||
      memcmp(&a->elastic, &b->elastic, sizeof(double)) != 0 ||
      memcmp(&a->potential, &b->potential, sizeof(double)) != 0)
    return snprintf(why, why_size, "energies changed (gravity or state): potential %.17g -> %.17g",
                    a->potential, b->potential),
           1;
  if (a->world_points != b->world_points)
    return snprintf(why, why_size, "the world's VTK point count changed: %ld -> %ld (a body was added or removed)",
                    a->world_points, b->world_points),
           1;
  return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* The failure check                                                                           */

/* Checks the status, the message (from the world, or from the thread when `on_thread`), that
 * each needle appears in it as whole words, that the log received it (world calls), and that
 * the fixture world did not change. */
static void check_failure(fixture* fx, snapshot* before, mica_status got, mica_status expected, int on_thread,
                          const char* call, const char* const* needles, const char* file, int line) {
  char message[2048];
  snprintf(message, sizeof message, "%s", mica_world_last_error(on_thread ? NULL : fx->world));
  const int log_calls = fx->log_calls;
  const int32_t log_level = fx->log_level;
  const void* log_user = fx->log_user;
  char log_message[2048];
  snprintf(log_message, sizeof log_message, "%s", fx->log_message);

  snapshot after;
  take_snapshot(fx, &after);
  char why[512] = "";
  const int changed = snapshot_differs(before, &after, why, sizeof why);
  free_snapshot(before);
  free_snapshot(&after);

  int bad = 0;
  if (got != expected) {
    print_error("%s:%d: %s\n  returned %d (%s)\n  expected %d (%s)\n  message: %s\n", file, line, call, got,
                mica_status_string(got), expected, mica_status_string(expected), message);
    bad = 1;
  }
  if (message[0] == '\0') {
    print_error("%s:%d: %s: mica_world_last_error(%s) is empty after the failure\n", file, line, call,
                on_thread ? "NULL" : "world");
    bad = 1;
  }
  for (const char* const* n = needles; *n; ++n) {
    if (!has_phrase(message, *n)) {
      print_error("%s:%d: %s: the message does not name '%s':\n  %s\n", file, line, call, *n, message);
      bad = 1;
    }
  }
  if (!on_thread) {
    if (log_calls != 1 || log_level != MICA_LOG_ERROR || log_user != fx || strcmp(log_message, message) != 0) {
      print_error("%s:%d: %s: the log callback got %d call(s), level %d, user %p (want 1, %d, %p):\n  %s\n", file,
                  line, call, log_calls, log_level, log_user, MICA_LOG_ERROR, (void*)fx, log_message);
      bad = 1;
    }
  }
  if (changed) {
    print_error("%s:%d: %s failed but changed the world: %s\n", file, line, call, why);
    bad = 1;
  }
  fx->log_calls = 0;
  fx->log_message[0] = '\0';
  if (bad) _fail(file, line);
}

/* EXPECT_FAIL(fx, status, call, needles...): the call on fx->world fails with `status`, its
 * message (on the world) names every needle, and nothing changed. Pass NULL for no needle. */
#define EXPECT_FAIL(fx, expected, call, ...)                                                         \
  do {                                                                                               \
    snapshot before_;                                                                                \
    take_snapshot((fx), &before_);                                                                   \
    (fx)->log_calls = 0;                                                                             \
    const mica_status got_ = (call);                                                                 \
    check_failure((fx), &before_, got_, (expected), 0, #call, (const char* const[]){__VA_ARGS__, NULL}, \
                  __FILE__, __LINE__);                                                               \
  } while (0)

/* The same for a call made without a world (world == NULL, creation): the message is on the
 * thread. The fixture world must still be unchanged. */
#define EXPECT_FAIL_NO_WORLD(fx, expected, call, ...)                                                \
  do {                                                                                               \
    snapshot before_;                                                                                \
    take_snapshot((fx), &before_);                                                                   \
    (fx)->log_calls = 0;                                                                             \
    const mica_status got_ = (call);                                                                 \
    check_failure((fx), &before_, got_, (expected), 1, #call, (const char* const[]){__VA_ARGS__, NULL}, \
                  __FILE__, __LINE__);                                                               \
  } while (0)

#define EXPECT_STATUS(expected, call)                                                                \
  do {                                                                                               \
    const mica_status got_ = (call);                                                                 \
    if (got_ != (expected)) {                                                                        \
      print_error("%s:%d: %s\n  returned %d (%s)\n  expected %d (%s)\n", __FILE__, __LINE__, #call, got_, \
                  mica_status_string(got_), (expected), mica_status_string(expected));               \
      _fail(__FILE__, __LINE__);                                                                     \
    }                                                                                                \
  } while (0)

static const char* hex_id(uint64_t id, char* text, size_t size) {
  snprintf(text, size, "0x%llx", (unsigned long long)id);
  return text;
}

/* A valid two-tet mesh: tet 0 = (0,1,2,3) and tet 1 = (1,2,3,4) share the face (1,2,3). */
static const double kTwoTetNodes[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
static const int32_t kTwoTets[8] = {0, 1, 2, 3, 1, 2, 3, 4};

/* ------------------------------------------------------------------------------------------ */
/* NULL pointers                                                                               */

static void test_null_world(void** state) {
  fixture* fx = *state;
  const mica_body_id b = fx->body;
  const double v3[3] = {0, 0, 0}, n3[3] = {1, 0, 0};
  const int32_t nodes[1] = {0};
  const double forces[3] = {0, 0, 1};
  const mica_body_def bd = mica_body_def_default();
  const mica_lpc_def ld = mica_lpc_def_default();
  double buf[3 * 64];
  int32_t ibuf[3 * 256];
  int32_t count = 0;
  const double* view = NULL;
  mica_body_id out_body = 0;
  mica_lpc_id out_lpc = 0;
  double e = 0;
  mica_world_stats st;
  memset(&st, 0, sizeof st);
  st.struct_size = sizeof st;

  mica_world_destroy(NULL); /* allowed */
  assert_non_null(mica_world_last_error(NULL));

  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_world_set_gravity(NULL, v3), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT,
                       mica_body_create(NULL, &bd, kTwoTetNodes, 5, kTwoTets, 2, &out_body), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT,
                       mica_body_create_from_file(NULL, &bd, "/tmp/x.msh", &out_body), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT,
                       mica_body_create_box(NULL, &bd, kLo, kHi, kCells, 6, &out_body), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_body_destroy(NULL, b), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_body_get_counts(NULL, b, &count, NULL, NULL), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_body_get_positions(NULL, b, buf, 64, &count), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_body_get_velocities(NULL, b, buf, 64, &count), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_body_get_rest_positions(NULL, b, buf, 64, &count),
                       "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_body_get_surface(NULL, b, ibuf, 256, &count), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_body_positions_view(NULL, b, &view, &count), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_body_set_node_forces(NULL, b, nodes, forces, 1), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT,
                       mica_body_select_nodes_in_box(NULL, b, kLo, kHi, 1, ibuf, 256, &count), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT,
                       mica_body_select_nodes_by_plane(NULL, b, v3, n3, 0.0, 1, ibuf, 256, &count), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_body_get_energy(NULL, b, &e, &e, &e), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_add_lpc(NULL, b, nodes, 1, &ld, &out_lpc), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_lpc_remove(NULL, fx->lpc), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_step(NULL, 0.01), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_world_get_stats(NULL, &st), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_body_write_vtk(NULL, b, tmp_path("null.vtk")), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_world_write_vtk(NULL, tmp_path("null.vtk")), "world");
  assert_int_equal(out_body, 0);
  assert_int_equal(out_lpc, 0);
}

static void test_null_world_create(void** state) {
  fixture* fx = *state;
  const mica_world_def wd = mica_world_def_default();
  mica_world* w = (mica_world*)&w; /* not NULL: creation must clear it */
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_world_create(NULL, &w), "def");
  assert_null(w);
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_world_create(&wd, NULL), "out_world");
}

/* The *_init functions have no world: their message goes to mica_world_last_error(NULL), which
 * the header defines as the last failed call on this thread that had no world. */
static void test_null_def_init(void** state) {
  fixture* fx = *state;
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT,
                       mica_world_def_init(NULL, (uint32_t)sizeof(mica_world_def), MICA_VERSION_NUMBER), "def");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_body_def_init(NULL, (uint32_t)sizeof(mica_body_def)), "def");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_lpc_def_init(NULL, (uint32_t)sizeof(mica_lpc_def)), "def");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_tool_def_init(NULL, (uint32_t)sizeof(mica_tool_def)), "def");
}

static void test_null_pointers(void** state) {
  fixture* fx = *state;
  mica_world* w = fx->world;
  const mica_body_id b = fx->body;
  const double v3[3] = {0, 0, 0}, n3[3] = {1, 0, 0};
  const int32_t nodes[1] = {0};
  const double forces[3] = {0, 0, 1};
  const mica_body_def bd = mica_body_def_default();
  const mica_lpc_def ld = mica_lpc_def_default();
  const char* msh = tmp_path("valid_for_null.msh");
  double buf[3 * 64];
  int32_t ibuf[3 * 256];
  int32_t count = 0;
  const double* view = NULL;
  mica_body_id out_body = 0;
  mica_lpc_id out_lpc = 0;

  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_world_set_gravity(w, NULL), "gravity");

  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_create(w, NULL, kTwoTetNodes, 5, kTwoTets, 2, &out_body), "def");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_create(w, &bd, NULL, 5, kTwoTets, 2, &out_body), "nodes");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_create(w, &bd, kTwoTetNodes, 5, NULL, 2, &out_body), "tets");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_create(w, &bd, kTwoTetNodes, 5, kTwoTets, 2, NULL), "out_body");

  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_create_from_file(w, &bd, NULL, &out_body), "path");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_create_from_file(w, &bd, msh, NULL), "out_body");

  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_create_box(w, NULL, kLo, kHi, kCells, 6, &out_body), "def");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_create_box(w, &bd, NULL, kHi, kCells, 6, &out_body), "lo");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_create_box(w, &bd, kLo, NULL, kCells, 6, &out_body), "hi");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_create_box(w, &bd, kLo, kHi, NULL, 6, &out_body), "cells");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_create_box(w, &bd, kLo, kHi, kCells, 6, NULL), "out_body");

  /* Size query with neither a buffer nor a count has nowhere to answer. */
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_get_positions(w, b, NULL, 0, NULL), "out_count");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_get_velocities(w, b, NULL, 0, NULL), "out_count");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_get_rest_positions(w, b, NULL, 0, NULL), "out_count");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_get_surface(w, b, NULL, 0, NULL), "out_count");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_positions_view(w, b, NULL, &count), "out");

  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_set_node_forces(w, b, NULL, forces, 1), "nodes");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_set_node_forces(w, b, nodes, NULL, 1), "forces");

  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_select_nodes_in_box(w, b, NULL, kHi, 1, ibuf, 256, &count), "lo");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_select_nodes_in_box(w, b, kLo, NULL, 1, ibuf, 256, &count), "hi");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_select_nodes_in_box(w, b, kLo, kHi, 1, NULL, 0, NULL),
              "out_count");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT,
              mica_body_select_nodes_by_plane(w, b, NULL, n3, 0.0, 1, ibuf, 256, &count), "point");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT,
              mica_body_select_nodes_by_plane(w, b, v3, NULL, 0.0, 1, ibuf, 256, &count), "normal");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_select_nodes_by_plane(w, b, v3, n3, 0.0, 1, NULL, 0, NULL),
              "out_count");

  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_add_lpc(w, b, NULL, 1, &ld, &out_lpc), "nodes");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_add_lpc(w, b, nodes, 1, NULL, &out_lpc), "def");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_add_lpc(w, b, nodes, 1, &ld, NULL), "out_lpc");

  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_world_get_stats(w, NULL), "out");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_body_write_vtk(w, b, NULL), "path");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_world_write_vtk(w, NULL), "path");

  assert_int_equal(out_body, 0);
  assert_int_equal(out_lpc, 0);
  (void)buf;
  (void)view;
}

/* Optional outputs really are optional. */
static void test_optional_outputs_may_be_null(void** state) {
  fixture* fx = *state;
  EXPECT_STATUS(MICA_OK, mica_body_get_counts(fx->world, fx->body, NULL, NULL, NULL));
  EXPECT_STATUS(MICA_OK, mica_body_get_energy(fx->world, fx->body, NULL, NULL, NULL));
  const double* view = NULL;
  EXPECT_STATUS(MICA_OK, mica_body_positions_view(fx->world, fx->body, &view, NULL));
  assert_non_null(view);
  EXPECT_STATUS(MICA_OK, mica_body_set_node_forces(fx->world, fx->body, NULL, NULL, 0));
  double* x = calloc(3 * (size_t)fx->node_count, sizeof(double));
  EXPECT_STATUS(MICA_OK, mica_body_get_positions(fx->world, fx->body, x, fx->node_count, NULL));
  assert_memory_equal(x, view, 3 * (size_t)fx->node_count * sizeof(double));
  free(x);
}

/* ------------------------------------------------------------------------------------------ */
/* Non-finite doubles                                                                          */

static void test_nonfinite_world_def(void** state) {
  fixture* fx = *state;
  const double bad[3] = {NAN, INFINITY, -INFINITY};
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i < 3; ++i) {
      mica_world_def wd = mica_world_def_default();
      wd.gravity[k] = bad[i];
      mica_world* w = (mica_world*)&wd;
      EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &w), "gravity");
      assert_null(w);
      mica_world_destroy(w);
    }
  }
  const double bad_tolerance[5] = {NAN, INFINITY, -INFINITY, 0.0, -1e-8};
  for (int i = 0; i < 5; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.solver = MICA_SOLVER_PCG;
    wd.tolerance = bad_tolerance[i];
    mica_world* w = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &w), "tolerance");
    assert_null(w);
  }
  const int32_t bad_iterations[3] = {0, -1, INT32_MIN};
  for (int i = 0; i < 3; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.solver = MICA_SOLVER_PCG;
    wd.max_iterations = bad_iterations[i];
    mica_world* w = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &w), "max_iterations");
    assert_null(w);
  }
  const double bad_speed[5] = {NAN, INFINITY, -INFINITY, 0.0, -1.0};
  for (int i = 0; i < 5; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.max_recovery_speed = bad_speed[i];
    mica_world* w = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &w), "max_recovery_speed");
    assert_null(w);
  }
  const int32_t bad_sweeps[3] = {0, -1, INT32_MIN};
  for (int i = 0; i < 3; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.solver = MICA_SOLVER_MICA;
    wd.pgs_sweeps = bad_sweeps[i];
    mica_world* w = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &w), "pgs_sweeps");
    assert_null(w);
  }
  const int32_t bad_norm[3] = {2, -1, INT32_MAX};
  for (int i = 0; i < 3; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.paper_norm = bad_norm[i];
    mica_world* w = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &w), "paper_norm");
    assert_null(w);
  }
  const double bad_relaxation[4] = {0, 2, -1, NAN};
  for (int i = 0; i < 4; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.relaxation = bad_relaxation[i];
    mica_world* w = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &w), "relaxation");
    assert_null(w);
  }
  const double bad_budget[3] = {-1, NAN, INFINITY};
  for (int i = 0; i < 3; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.time_budget_ms = bad_budget[i];
    mica_world* w = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &w), "time_budget_ms");
    assert_null(w);
  }
  const int32_t bad_threads[3] = {-1, 1025, INT32_MIN};
  for (int i = 0; i < 3; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.threads = bad_threads[i];
    mica_world* w = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &w), "threads");
    assert_null(w);
  }
  const double bad_relin[3] = {-1e-3, NAN, INFINITY};
  for (int i = 0; i < 3; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.relinearise_tolerance = bad_relin[i];
    mica_world* w = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &w), "relinearise_tolerance");
    assert_null(w);
  }
  const int32_t bad_refactor[2] = {-1, INT32_MIN};
  for (int i = 0; i < 2; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.refactor_interval = bad_refactor[i];
    mica_world* w = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &w), "refactor_interval");
    assert_null(w);
  }
  const int32_t bad_sweep_kind[3] = {2, -1, INT32_MAX};
  for (int i = 0; i < 3; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.mica_sweep = bad_sweep_kind[i];
    mica_world* w = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &w), "mica_sweep");
    assert_null(w);
  }
}

static void test_nonfinite_gravity(void** state) {
  fixture* fx = *state;
  const double bad[3] = {NAN, INFINITY, -INFINITY};
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) {
      double g[3] = {0, -9.81, 0};
      g[k] = bad[i];
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_set_gravity(fx->world, g), "gravity");
    }
}

/* One field of a body def made bad; the same def must fail through all three creators. */
typedef struct {
  const char* what;
  void (*spoil)(mica_body_def*, double);
} body_field;

static void spoil_youngs(mica_body_def* d, double x) { d->youngs_modulus = x; }
static void spoil_poisson(mica_body_def* d, double x) { d->poisson_ratio = x; }
static void spoil_density(mica_body_def* d, double x) { d->density = x; }
static void spoil_alpha(mica_body_def* d, double x) { d->rayleigh_alpha = x; }
static void spoil_beta(mica_body_def* d, double x) { d->rayleigh_beta = x; }
static void spoil_translation0(mica_body_def* d, double x) { d->translation[0] = x; }
static void spoil_translation2(mica_body_def* d, double x) { d->translation[2] = x; }
static void spoil_velocity1(mica_body_def* d, double x) { d->velocity[1] = x; }
static void spoil_velocity2(mica_body_def* d, double x) { d->velocity[2] = x; }

static void test_bad_body_def_values(void** state) {
  fixture* fx = *state;
  mica_world* w = fx->world;
  const char* msh = write_tmp("two_tets_for_def.msh",
                              "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
                              "5 1 1 1\n$EndNodes\n$Elements\n2\n1 4 0 1 2 3 4\n2 4 0 2 3 4 5\n$EndElements\n");
  assert_non_null(msh);
  const body_field fields[] = {
      {"youngs_modulus", spoil_youngs}, {"poisson_ratio", spoil_poisson}, {"density", spoil_density},
      {"rayleigh_alpha", spoil_alpha},  {"rayleigh_beta", spoil_beta},    {"translation", spoil_translation0},
      {"translation", spoil_translation2}, {"velocity", spoil_velocity1}, {"velocity", spoil_velocity2},
  };
  const double nonfinite[3] = {NAN, INFINITY, -INFINITY};
  for (size_t f = 0; f < sizeof fields / sizeof fields[0]; ++f)
    for (int i = 0; i < 3; ++i) {
      mica_body_def bd = mica_body_def_default();
      fields[f].spoil(&bd, nonfinite[i]);
      mica_body_id out = 0;
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(w, &bd, kLo, kHi, kCells, 6, &out), NULL);
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create(w, &bd, kTwoTetNodes, 5, kTwoTets, 2, &out), NULL);
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_from_file(w, &bd, msh, &out), NULL);
      assert_int_equal(out, 0);
    }
  /* Finite values outside the domain. */
  struct {
    void (*spoil)(mica_body_def*, double);
    double value;
  } domain[] = {{spoil_youngs, 0.0},   {spoil_youngs, -1e4}, {spoil_poisson, 0.5}, {spoil_poisson, 0.7},
                {spoil_poisson, -0.1}, {spoil_density, 0.0}, {spoil_density, -1}, {spoil_alpha, -1e-3},
                {spoil_beta, -1e-3}};
  for (size_t k = 0; k < sizeof domain / sizeof domain[0]; ++k) {
    mica_body_def bd = mica_body_def_default();
    domain[k].spoil(&bd, domain[k].value);
    mica_body_id out = 0;
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(w, &bd, kLo, kHi, kCells, 6, &out), NULL);
    assert_int_equal(out, 0);
  }
}

static void test_nonfinite_node_coordinates(void** state) {
  fixture* fx = *state;
  const mica_body_def bd = mica_body_def_default();
  const double nonfinite[3] = {NAN, INFINITY, -INFINITY};
  for (int c = 0; c < 15; c += 4)
    for (int i = 0; i < 3; ++i) {
      double nodes[15];
      memcpy(nodes, kTwoTetNodes, sizeof nodes);
      nodes[c] = nonfinite[i];
      char node_name[32];
      snprintf(node_name, sizeof node_name, "node %d", c / 3);
      mica_body_id out = 0;
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create(fx->world, &bd, nodes, 5, kTwoTets, 2, &out),
                  node_name);
      assert_int_equal(out, 0);
    }
}

static void test_bad_box_corners(void** state) {
  fixture* fx = *state;
  const mica_body_def bd = mica_body_def_default();
  const double nonfinite[3] = {NAN, INFINITY, -INFINITY};
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 3; ++i) {
      double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
      mica_body_id out = 0;
      lo[k] = nonfinite[i];
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(fx->world, &bd, lo, hi, kCells, 6, &out), NULL);
      lo[k] = 0;
      hi[k] = nonfinite[i];
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(fx->world, &bd, lo, hi, kCells, 5, &out), NULL);
      /* An empty or inverted box. */
      hi[k] = 0;
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(fx->world, &bd, lo, hi, kCells, 6, &out), NULL);
      hi[k] = -1;
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(fx->world, &bd, lo, hi, kCells, 6, &out), NULL);
      assert_int_equal(out, 0);
    }
}

static void test_nonfinite_lpc(void** state) {
  fixture* fx = *state;
  const int32_t nodes[2] = {1, 2};
  const double nonfinite[3] = {NAN, INFINITY, -INFINITY};
  const int32_t kinds[3] = {MICA_LPC_PLANE, MICA_LPC_LINE, MICA_LPC_TWO_DIRS};
  for (int i = 0; i < 3; ++i)
    for (int c = 0; c < 3; ++c) {
      for (int k = 0; k < 3; ++k) {
        /* direction[0] is used by every kind here */
        mica_lpc_def d = mica_lpc_def_default();
        d.kind = kinds[k];
        d.direction[0][0] = 0;
        d.direction[0][2] = 1;
        d.direction[1][0] = 1;
        d.direction[1][1] = 0;
        d.direction[0][c] = nonfinite[i];
        mica_lpc_id out = 0;
        EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_add_lpc(fx->world, fx->body, nodes, 2, &d, &out), NULL);
        assert_int_equal(out, 0);
      }
      /* direction[1] of the two-direction kind */
      mica_lpc_def d = mica_lpc_def_default();
      d.kind = MICA_LPC_TWO_DIRS;
      d.direction[0][0] = 0;
      d.direction[0][2] = 1;
      d.direction[1][0] = 1;
      d.direction[1][1] = 0;
      d.direction[1][c] = nonfinite[i];
      mica_lpc_id out = 0;
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_add_lpc(fx->world, fx->body, nodes, 2, &d, &out), NULL);
      /* the prescribed velocity, for every kind */
      for (int32_t kind = MICA_LPC_FIXED; kind <= MICA_LPC_TWO_DIRS; ++kind) {
        mica_lpc_def dv = mica_lpc_def_default();
        dv.kind = kind;
        dv.velocity[c] = nonfinite[i];
        EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_add_lpc(fx->world, fx->body, nodes, 2, &dv, &out), NULL);
      }
      assert_int_equal(out, 0);
    }
  /* Zero and parallel directions are outside the domain too. */
  mica_lpc_def d = mica_lpc_def_default();
  mica_lpc_id out = 0;
  d.kind = MICA_LPC_PLANE;
  d.direction[0][0] = d.direction[0][1] = d.direction[0][2] = 0;
  EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_add_lpc(fx->world, fx->body, nodes, 2, &d, &out), NULL);
  d.kind = MICA_LPC_LINE;
  EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_add_lpc(fx->world, fx->body, nodes, 2, &d, &out), NULL);
  d = mica_lpc_def_default();
  d.kind = MICA_LPC_TWO_DIRS;
  d.direction[0][0] = 1;
  d.direction[0][1] = 0;
  d.direction[1][0] = -2;
  d.direction[1][1] = 0;
  EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_add_lpc(fx->world, fx->body, nodes, 2, &d, &out), "parallel");
  assert_int_equal(out, 0);
}

static void test_nonfinite_node_forces(void** state) {
  fixture* fx = *state;
  const int32_t nodes[2] = {3, 4};
  const double nonfinite[3] = {NAN, INFINITY, -INFINITY};
  for (int i = 0; i < 3; ++i)
    for (int c = 0; c < 6; ++c) {
      double f[6] = {0.1, 0.2, 0.3, -0.1, -0.2, -0.3};
      f[c] = nonfinite[i];
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_set_node_forces(fx->world, fx->body, nodes, f, 2), NULL);
    }
}

static void test_bad_dt(void** state) {
  fixture* fx = *state;
  /* Below the floor of 1e-9 s too (0.4 took 1e-200 and reported infinite forces). */
  const double bad[] = {0.0, -0.0, -0.01, -1.0, 1.0000001, 2.0, 1e300, NAN, INFINITY, -INFINITY, -NAN,
                        5e-324, 1e-300, 1e-160, 1e-10, 9.999e-10};
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i)
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_step(fx->world, bad[i]), "[1e-9, 1] s");
  /* The edges of [1e-9, 1] are accepted. */
  EXPECT_STATUS(MICA_OK, mica_step(fx->world, 1.0));
  EXPECT_STATUS(MICA_OK, mica_step(fx->world, 1e-6));
  EXPECT_STATUS(MICA_OK, mica_step(fx->world, 1e-9));
}

static void test_bad_selection_inputs(void** state) {
  fixture* fx = *state;
  mica_world* w = fx->world;
  const mica_body_id b = fx->body;
  int32_t ibuf[256];
  int32_t count = -7;
  const double nonfinite[3] = {NAN, INFINITY, -INFINITY};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) {
      double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
      lo[k] = nonfinite[i];
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_select_nodes_in_box(w, b, lo, hi, 1, ibuf, 256, &count),
                  NULL);
      lo[k] = -1;
      hi[k] = nonfinite[i];
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_select_nodes_in_box(w, b, lo, hi, 0, ibuf, 256, &count),
                  NULL);
      double point[3] = {0, 0, 0}, normal[3] = {1, 0, 0};
      point[k] = nonfinite[i];
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT,
                  mica_body_select_nodes_by_plane(w, b, point, normal, 0.0, 1, ibuf, 256, &count), NULL);
      point[k] = 0;
      normal[k] = nonfinite[i];
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT,
                  mica_body_select_nodes_by_plane(w, b, point, normal, 0.0, 1, ibuf, 256, &count), NULL);
      normal[k] = k == 0 ? 1 : 0;
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT,
                  mica_body_select_nodes_by_plane(w, b, point, normal, nonfinite[i], 1, ibuf, 256, &count), NULL);
    }
  const double zero[3] = {0, 0, 0};
  EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT,
              mica_body_select_nodes_by_plane(w, b, zero, zero, 0.0, 1, ibuf, 256, &count), NULL);
  const double n3[3] = {1, 0, 0};
  const int32_t bad_rest[3] = {2, -1, INT32_MAX};
  for (int i = 0; i < 3; ++i) {
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT,
                mica_body_select_nodes_in_box(w, b, kLo, kHi, bad_rest[i], ibuf, 256, &count), "use_rest");
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT,
                mica_body_select_nodes_by_plane(w, b, zero, n3, 0.0, bad_rest[i], ibuf, 256, &count), "use_rest");
  }
  assert_int_equal(count, -7); /* nothing was answered */
}

/* ------------------------------------------------------------------------------------------ */
/* Indices                                                                                     */

static void test_out_of_range_lpc_nodes(void** state) {
  fixture* fx = *state;
  const mica_lpc_def d = mica_lpc_def_default();
  const int32_t bad[3] = {-1, fx->node_count, INT32_MAX};
  for (int i = 0; i < 3; ++i) {
    char index[32];
    snprintf(index, sizeof index, "%d", bad[i]);
    mica_lpc_id out = 0;
    const int32_t at0[3] = {bad[i], 1, 2};
    EXPECT_FAIL(fx, MICA_ERR_OUT_OF_RANGE, mica_add_lpc(fx->world, fx->body, at0, 3, &d, &out), index,
                "position 0");
    const int32_t at2[3] = {0, 1, bad[i]};
    EXPECT_FAIL(fx, MICA_ERR_OUT_OF_RANGE, mica_add_lpc(fx->world, fx->body, at2, 3, &d, &out), index,
                "position 2");
    assert_int_equal(out, 0);
  }
}

static void test_out_of_range_node_forces(void** state) {
  fixture* fx = *state;
  const double f[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  const int32_t bad[3] = {-1, fx->node_count, INT32_MAX};
  for (int i = 0; i < 3; ++i) {
    char index[32];
    snprintf(index, sizeof index, "%d", bad[i]);
    const int32_t at0[3] = {bad[i], 1, 2};
    EXPECT_FAIL(fx, MICA_ERR_OUT_OF_RANGE, mica_body_set_node_forces(fx->world, fx->body, at0, f, 3), index,
                "position 0");
    const int32_t at2[3] = {0, 1, bad[i]};
    EXPECT_FAIL(fx, MICA_ERR_OUT_OF_RANGE, mica_body_set_node_forces(fx->world, fx->body, at2, f, 3), index,
                "position 2");
  }
}

static void test_out_of_range_tets(void** state) {
  fixture* fx = *state;
  const mica_body_def bd = mica_body_def_default();
  const int32_t bad[3] = {-1, 5, INT32_MAX};
  for (int i = 0; i < 3; ++i)
    for (int corner = 0; corner < 4; ++corner) {
      char index[32];
      snprintf(index, sizeof index, "%d", bad[i]);
      int32_t tets[8];
      memcpy(tets, kTwoTets, sizeof tets);
      tets[4 + corner] = bad[i];
      mica_body_id out = 0;
      EXPECT_FAIL(fx, MICA_ERR_OUT_OF_RANGE, mica_body_create(fx->world, &bd, kTwoTetNodes, 5, tets, 2, &out), index,
                  "tet 1");
      memcpy(tets, kTwoTets, sizeof tets);
      tets[corner] = bad[i];
      EXPECT_FAIL(fx, MICA_ERR_OUT_OF_RANGE, mica_body_create(fx->world, &bd, kTwoTetNodes, 5, tets, 2, &out), index,
                  "tet 0");
      assert_int_equal(out, 0);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* Counts and capacities                                                                       */

static void test_bad_counts(void** state) {
  fixture* fx = *state;
  mica_world* w = fx->world;
  const mica_body_def bd = mica_body_def_default();
  const mica_lpc_def ld = mica_lpc_def_default();
  const int32_t nodes[1] = {0};
  const double forces[3] = {0, 0, 1};
  mica_body_id out_body = 0;
  mica_lpc_id out_lpc = 0;
  const int32_t bad_nodes[5] = {-1, INT32_MIN, 0, 3, INT32_MAX};
  for (int i = 0; i < 5; ++i)
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT,
                mica_body_create(w, &bd, kTwoTetNodes, bad_nodes[i], kTwoTets, 2, &out_body), "node_count");
  const int32_t bad_tets[3] = {-1, INT32_MIN, 0};
  for (int i = 0; i < 3; ++i)
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT,
                mica_body_create(w, &bd, kTwoTetNodes, 5, kTwoTets, bad_tets[i], &out_body), "tet_count");
  const int32_t bad_counts[2] = {-1, INT32_MIN};
  for (int i = 0; i < 2; ++i) {
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_set_node_forces(w, fx->body, nodes, forces, bad_counts[i]),
                "count");
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_add_lpc(w, fx->body, nodes, bad_counts[i], &ld, &out_lpc),
                "count");
  }
  EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_add_lpc(w, fx->body, nodes, 0, &ld, &out_lpc), "count");
  const int32_t bad_cells[4][3] = {{0, 1, 1}, {1, -1, 1}, {1, 1, INT32_MIN}, {-5, -5, -5}};
  for (int i = 0; i < 4; ++i)
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(w, &bd, kLo, kHi, bad_cells[i], 6, &out_body),
                "cells");
  assert_int_equal(out_body, 0);
  assert_int_equal(out_lpc, 0);
}

/* Cell counts whose node or tet count overflows 64-bit products must be refused as invalid,
 * not turned into a failed allocation. */
static void test_huge_box(void** state) {
  fixture* fx = *state;
  const mica_body_def bd = mica_body_def_default();
  const int32_t huge[4][3] = {
      {100000, 100000, 100000}, {2097152, 2097152, 2097152}, {INT32_MAX, INT32_MAX, 1}, {INT32_MAX, INT32_MAX, INT32_MAX}};
  for (int i = 0; i < 4; ++i) {
    mica_body_id out = 0;
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(fx->world, &bd, kLo, kHi, huge[i], 6, &out), NULL);
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(fx->world, &bd, kLo, kHi, huge[i], 5, &out), NULL);
    assert_int_equal(out, 0);
  }
}

#define SENTINEL_D (-12345.678)
#define SENTINEL_I (-777)

typedef mica_status (*node_getter)(const mica_world*, mica_body_id, double*, int32_t, int32_t*);

static void check_node_getter_small(fixture* fx, node_getter get, const char* name, int32_t capacity,
                                    mica_status expected) {
  const int32_t n = fx->node_count;
  double* buf = malloc(sizeof(double) * 3 * (size_t)n);
  for (int32_t i = 0; i < 3 * n; ++i) buf[i] = SENTINEL_D;
  int32_t out_count = SENTINEL_I;
  char needed[32];
  snprintf(needed, sizeof needed, "%d", n);
  snapshot before;
  take_snapshot(fx, &before);
  fx->log_calls = 0;
  const mica_status got = get(fx->world, fx->body, buf, capacity, &out_count);
  char call[128];
  snprintf(call, sizeof call, "%s(capacity %d of %d)", name, capacity, n);
  check_failure(fx, &before, got, expected, 0, call,
                (const char* const[]){expected == MICA_ERR_BUFFER_TOO_SMALL ? needed : NULL, NULL}, __FILE__,
                __LINE__);
  for (int32_t i = 0; i < 3 * n; ++i)
    if (buf[i] != SENTINEL_D) {
      print_error("%s: the buffer was written (item %d) although the call failed\n", call, i / 3);
      fail();
    }
  if (expected == MICA_ERR_BUFFER_TOO_SMALL && out_count != n) {
    print_error("%s: *out_count is %d, want the needed count %d\n", call, out_count, n);
    fail();
  }
  free(buf);
}

typedef mica_status (*index_getter)(fixture*, int32_t*, int32_t, int32_t*);

static mica_status get_surface(fixture* fx, int32_t* out, int32_t capacity, int32_t* out_count) {
  return mica_body_get_surface(fx->world, fx->body, out, capacity, out_count);
}
static mica_status get_in_box(fixture* fx, int32_t* out, int32_t capacity, int32_t* out_count) {
  const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  return mica_body_select_nodes_in_box(fx->world, fx->body, lo, hi, 1, out, capacity, out_count);
}
static mica_status get_by_plane(fixture* fx, int32_t* out, int32_t capacity, int32_t* out_count) {
  const double p[3] = {0.15, 0, 0}, n[3] = {1, 0, 0};
  return mica_body_select_nodes_by_plane(fx->world, fx->body, p, n, 1e-9, 0, out, capacity, out_count);
}

static void check_index_getter_small(fixture* fx, index_getter get, int32_t width, const char* name, int32_t capacity,
                                     mica_status expected) {
  int32_t needed = -1;
  EXPECT_STATUS(MICA_OK, get(fx, NULL, 0, &needed));
  assert_true(needed > 0);
  int32_t* buf = malloc(sizeof(int32_t) * (size_t)(width * needed));
  for (int32_t i = 0; i < width * needed; ++i) buf[i] = SENTINEL_I;
  int32_t out_count = SENTINEL_I;
  char needed_text[32];
  snprintf(needed_text, sizeof needed_text, "%d", needed);
  snapshot before;
  take_snapshot(fx, &before);
  fx->log_calls = 0;
  const mica_status got = get(fx, buf, capacity, &out_count);
  char call[128];
  snprintf(call, sizeof call, "%s(capacity %d of %d)", name, capacity, needed);
  check_failure(fx, &before, got, expected, 0, call,
                (const char* const[]){expected == MICA_ERR_BUFFER_TOO_SMALL ? needed_text : NULL, NULL}, __FILE__,
                __LINE__);
  for (int32_t i = 0; i < width * needed; ++i)
    if (buf[i] != SENTINEL_I) {
      print_error("%s: the buffer was written (item %d) although the call failed\n", call, i / width);
      fail();
    }
  if (expected == MICA_ERR_BUFFER_TOO_SMALL && out_count != needed) {
    print_error("%s: *out_count is %d, want the needed count %d\n", call, out_count, needed);
    fail();
  }
  free(buf);
}

static void test_buffer_too_small(void** state) {
  fixture* fx = *state;
  const int32_t n = fx->node_count;
  const int32_t caps[2] = {0, n - 1};
  for (int i = 0; i < 2; ++i) {
    check_node_getter_small(fx, mica_body_get_positions, "mica_body_get_positions", caps[i],
                            MICA_ERR_BUFFER_TOO_SMALL);
    check_node_getter_small(fx, mica_body_get_velocities, "mica_body_get_velocities", caps[i],
                            MICA_ERR_BUFFER_TOO_SMALL);
    check_node_getter_small(fx, mica_body_get_rest_positions, "mica_body_get_rest_positions", caps[i],
                            MICA_ERR_BUFFER_TOO_SMALL);
  }
  int32_t tris = 0, in_box = 0, on_plane = 0;
  EXPECT_STATUS(MICA_OK, get_surface(fx, NULL, 0, &tris));
  EXPECT_STATUS(MICA_OK, get_in_box(fx, NULL, 0, &in_box));
  EXPECT_STATUS(MICA_OK, get_by_plane(fx, NULL, 0, &on_plane));
  assert_int_equal(in_box, n);
  assert_int_equal(on_plane, 8); /* x <= 0.15: the faces x = 0 and x = 0.1 */
  check_index_getter_small(fx, get_surface, 3, "mica_body_get_surface", 0, MICA_ERR_BUFFER_TOO_SMALL);
  check_index_getter_small(fx, get_surface, 3, "mica_body_get_surface", tris - 1, MICA_ERR_BUFFER_TOO_SMALL);
  check_index_getter_small(fx, get_in_box, 1, "mica_body_select_nodes_in_box", 0, MICA_ERR_BUFFER_TOO_SMALL);
  check_index_getter_small(fx, get_in_box, 1, "mica_body_select_nodes_in_box", in_box - 1, MICA_ERR_BUFFER_TOO_SMALL);
  check_index_getter_small(fx, get_by_plane, 1, "mica_body_select_nodes_by_plane", 0, MICA_ERR_BUFFER_TOO_SMALL);
  check_index_getter_small(fx, get_by_plane, 1, "mica_body_select_nodes_by_plane", on_plane - 1,
                           MICA_ERR_BUFFER_TOO_SMALL);

  /* Without out_count the call still refuses and leaves the buffer alone. */
  double* buf = malloc(sizeof(double) * 3 * (size_t)n);
  for (int32_t i = 0; i < 3 * n; ++i) buf[i] = SENTINEL_D;
  EXPECT_FAIL(fx, MICA_ERR_BUFFER_TOO_SMALL, mica_body_get_positions(fx->world, fx->body, buf, n - 1, NULL), NULL);
  for (int32_t i = 0; i < 3 * n; ++i) assert_true(buf[i] == SENTINEL_D);
  free(buf);
}

/* A negative capacity is a value outside its domain: MICA_ERR_INVALID_ARGUMENT (the header:
 * "a value is outside its domain (NaN, negative, bad enum)"), and the buffer stays untouched. */
static void test_negative_capacity(void** state) {
  fixture* fx = *state;
  const int32_t caps[2] = {-1, INT32_MIN};
  for (int i = 0; i < 2; ++i) {
    check_node_getter_small(fx, mica_body_get_positions, "mica_body_get_positions", caps[i],
                            MICA_ERR_INVALID_ARGUMENT);
    check_node_getter_small(fx, mica_body_get_velocities, "mica_body_get_velocities", caps[i],
                            MICA_ERR_INVALID_ARGUMENT);
    check_node_getter_small(fx, mica_body_get_rest_positions, "mica_body_get_rest_positions", caps[i],
                            MICA_ERR_INVALID_ARGUMENT);
    check_index_getter_small(fx, get_surface, 3, "mica_body_get_surface", caps[i], MICA_ERR_INVALID_ARGUMENT);
    check_index_getter_small(fx, get_in_box, 1, "mica_body_select_nodes_in_box", caps[i], MICA_ERR_INVALID_ARGUMENT);
    check_index_getter_small(fx, get_by_plane, 1, "mica_body_select_nodes_by_plane", caps[i],
                             MICA_ERR_INVALID_ARGUMENT);
  }
}

/* ------------------------------------------------------------------------------------------ */
/* Stale ids                                                                                   */

static void check_stale_body_id(fixture* fx, mica_body_id id) {
  mica_world* w = fx->world;
  char hex[32];
  hex_id(id, hex, sizeof hex);
  const double v3[3] = {0, 0, 0}, n3[3] = {1, 0, 0};
  const int32_t nodes[1] = {0};
  const double forces[3] = {0, 0, 1};
  const mica_lpc_def ld = mica_lpc_def_default();
  double buf[3 * 64];
  int32_t ibuf[3 * 256];
  int32_t count = SENTINEL_I, nn = SENTINEL_I, nt = SENTINEL_I, ntri = SENTINEL_I;
  const double* view = NULL;
  mica_lpc_id out_lpc = 0;
  double e1 = SENTINEL_D, e2 = SENTINEL_D, e3 = SENTINEL_D;
  const char* vtk = tmp_path("stale.vtk");
  unlink(vtk);

  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_destroy(w, id), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_get_counts(w, id, &nn, &nt, &ntri), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_get_positions(w, id, buf, 64, &count), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_get_positions(w, id, NULL, 0, &count), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_get_velocities(w, id, buf, 64, &count), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_get_rest_positions(w, id, buf, 64, &count), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_get_surface(w, id, ibuf, 256, &count), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_positions_view(w, id, &view, &count), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_set_node_forces(w, id, nodes, forces, 1), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_set_node_forces(w, id, NULL, NULL, 0), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_select_nodes_in_box(w, id, kLo, kHi, 1, ibuf, 256, &count), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_select_nodes_by_plane(w, id, v3, n3, 0.0, 1, ibuf, 256, &count), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_get_energy(w, id, &e1, &e2, &e3), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_add_lpc(w, id, nodes, 1, &ld, &out_lpc), hex);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_write_vtk(w, id, vtk), hex);

  assert_int_equal(count, SENTINEL_I);
  assert_int_equal(nn, SENTINEL_I);
  assert_int_equal(nt, SENTINEL_I);
  assert_int_equal(ntri, SENTINEL_I);
  assert_null(view);
  assert_int_equal(out_lpc, 0);
  assert_true(e1 == SENTINEL_D && e2 == SENTINEL_D && e3 == SENTINEL_D);
  assert_int_equal(access(vtk, F_OK), -1); /* no file for a stale body */
}

static void test_stale_body_ids(void** state) {
  fixture* fx = *state;
  check_stale_body_id(fx, fx->dead_body);       /* destroyed */
  check_stale_body_id(fx, fx->lpc);             /* an lpc id where a body id is expected */
  check_stale_body_id(fx, MICA_NULL_ID);        /* null */
  check_stale_body_id(fx, 0x0100000100000063u); /* made up: body kind, generation 1, slot 99 */
  check_stale_body_id(fx, (fx->body & ~(0xffffffull << 32)) | (0x000abcull << 32)); /* live slot, wrong generation */
  check_stale_body_id(fx, fx->body ^ (0xffull << 56)); /* live slot, unknown kind */
  check_stale_body_id(fx, UINT64_MAX);
}

static void test_stale_lpc_ids(void** state) {
  fixture* fx = *state;
  const mica_lpc_id bad[6] = {fx->dead_lpc, fx->body, fx->dead_body, MICA_NULL_ID, 0x0200000100000063u, UINT64_MAX};
  for (int i = 0; i < 6; ++i) {
    char hex[32];
    EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_lpc_remove(fx->world, bad[i]), hex_id(bad[i], hex, sizeof hex));
  }
  /* The live constraint is still there: removing it works once, then it is stale. */
  EXPECT_STATUS(MICA_OK, mica_lpc_remove(fx->world, fx->lpc));
  char hex[32];
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_lpc_remove(fx->world, fx->lpc), hex_id(fx->lpc, hex, sizeof hex));
}

/* ------------------------------------------------------------------------------------------ */
/* Struct sizes and versions                                                                   */

static void test_struct_size(void** state) {
  fixture* fx = *state;
  mica_world* w = fx->world;
  const char* msh = write_tmp("two_tets_for_size.msh",
                              "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
                              "5 1 1 1\n$EndNodes\n$Elements\n2\n1 4 0 1 2 3 4\n2 4 0 2 3 4 5\n$EndElements\n");
  assert_non_null(msh);
  const int32_t nodes[2] = {1, 2};
  for (int k = 0; k < 3; ++k) {
    /* Defs are embedded in larger buffers so that an oversized struct_size is safe to try. */
    struct {
      mica_world_def d;
      char pad[16];
    } wd;
    memset(&wd, 0, sizeof wd);
    wd.d = mica_world_def_default();
    const uint32_t wsizes[3] = {0, 1, (uint32_t)sizeof(mica_world_def) + 8};
    wd.d.struct_size = wsizes[k];
    mica_world* nw = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_STRUCT_SIZE, mica_world_create(&wd.d, &nw), "struct_size");
    assert_null(nw);

    struct {
      mica_body_def d;
      char pad[16];
    } bd;
    memset(&bd, 0, sizeof bd);
    bd.d = mica_body_def_default();
    const uint32_t bsizes[3] = {0, 1, (uint32_t)sizeof(mica_body_def) + 8};
    bd.d.struct_size = bsizes[k];
    mica_body_id out = 0;
    EXPECT_FAIL(fx, MICA_ERR_STRUCT_SIZE, mica_body_create(w, &bd.d, kTwoTetNodes, 5, kTwoTets, 2, &out),
                "struct_size");
    EXPECT_FAIL(fx, MICA_ERR_STRUCT_SIZE, mica_body_create_from_file(w, &bd.d, msh, &out), "struct_size");
    EXPECT_FAIL(fx, MICA_ERR_STRUCT_SIZE, mica_body_create_box(w, &bd.d, kLo, kHi, kCells, 6, &out), "struct_size");
    assert_int_equal(out, 0);

    struct {
      mica_lpc_def d;
      char pad[16];
    } ld;
    memset(&ld, 0, sizeof ld);
    ld.d = mica_lpc_def_default();
    const uint32_t lsizes[3] = {0, 1, (uint32_t)sizeof(mica_lpc_def) + 8};
    ld.d.struct_size = lsizes[k];
    mica_lpc_id lpc = 0;
    EXPECT_FAIL(fx, MICA_ERR_STRUCT_SIZE, mica_add_lpc(w, fx->body, nodes, 2, &ld.d, &lpc), "struct_size");
    assert_int_equal(lpc, 0);

    union {
      mica_world_stats s;
      unsigned char bytes[sizeof(mica_world_stats) + 16];
    } st;
    memset(&st, 0xab, sizeof st);
    const uint32_t ssizes[3] = {0, 1, (uint32_t)sizeof(mica_world_stats) + 8};
    st.s.struct_size = ssizes[k];
    EXPECT_FAIL(fx, MICA_ERR_STRUCT_SIZE, mica_world_get_stats(w, &st.s), "struct_size");
    for (size_t i = sizeof(uint32_t); i < sizeof st.bytes; ++i) assert_int_equal(st.bytes[i], 0xab);
    assert_int_equal(st.s.struct_size, ssizes[k]);
  }
}

static void test_struct_size_init(void** state) {
  (void)state;
  const uint32_t extra = 8;
  union {
    mica_world_def d;
    unsigned char bytes[sizeof(mica_world_def) + 16];
  } w;
  union {
    mica_body_def d;
    unsigned char bytes[sizeof(mica_body_def) + 16];
  } b;
  union {
    mica_lpc_def d;
    unsigned char bytes[sizeof(mica_lpc_def) + 16];
  } l;
  const uint32_t wsizes[3] = {0, 1, (uint32_t)sizeof(mica_world_def) + extra};
  const uint32_t bsizes[3] = {0, 1, (uint32_t)sizeof(mica_body_def) + extra};
  const uint32_t lsizes[3] = {0, 1, (uint32_t)sizeof(mica_lpc_def) + extra};
  for (int k = 0; k < 3; ++k) {
    memset(&w, 0xcd, sizeof w);
    memset(&b, 0xcd, sizeof b);
    memset(&l, 0xcd, sizeof l);
    EXPECT_STATUS(MICA_ERR_STRUCT_SIZE, mica_world_def_init(&w.d, wsizes[k], MICA_VERSION_NUMBER));
    EXPECT_STATUS(MICA_ERR_STRUCT_SIZE, mica_body_def_init(&b.d, bsizes[k]));
    EXPECT_STATUS(MICA_ERR_STRUCT_SIZE, mica_lpc_def_init(&l.d, lsizes[k]));
    for (size_t i = 0; i < sizeof w.bytes; ++i) assert_int_equal(w.bytes[i], 0xcd);
    for (size_t i = 0; i < sizeof b.bytes; ++i) assert_int_equal(b.bytes[i], 0xcd);
    for (size_t i = 0; i < sizeof l.bytes; ++i) assert_int_equal(l.bytes[i], 0xcd);
  }
  /* The exact size works and writes exactly that much. */
  memset(&w, 0xcd, sizeof w);
  EXPECT_STATUS(MICA_OK, mica_world_def_init(&w.d, (uint32_t)sizeof(mica_world_def), MICA_VERSION_NUMBER));
  for (size_t i = sizeof(mica_world_def); i < sizeof w.bytes; ++i) assert_int_equal(w.bytes[i], 0xcd);
  assert_int_equal(w.d.struct_size, sizeof(mica_world_def));
}

static void test_version_mismatch(void** state) {
  fixture* fx = *state;
  const uint32_t other[4] = {(MICA_VERSION_MAJOR + 1) * 10000u + MICA_VERSION_MINOR * 100u,
                             (MICA_VERSION_MAJOR + 1) * 10000u, 990000u, UINT32_MAX};
  for (int i = 0; i < 4; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.header_version = other[i];
    mica_world* w = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_VERSION_MISMATCH, mica_world_create(&wd, &w), NULL);
    assert_null(w);
    /* The same through the FFI entry point. */
    mica_world_def fd;
    EXPECT_STATUS(MICA_OK, mica_world_def_init(&fd, (uint32_t)sizeof fd, other[i]));
    assert_int_equal(fd.header_version, other[i]);
    w = (mica_world*)&fd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_VERSION_MISMATCH, mica_world_create(&fd, &w), NULL);
    assert_null(w);
  }
  /* Another minor or patch of the same major is fine. */
  mica_world_def wd = mica_world_def_default();
  wd.header_version = MICA_VERSION_MAJOR * 10000u + 99u * 100u + 99u;
  mica_world* w = NULL;
  EXPECT_STATUS(MICA_OK, mica_world_create(&wd, &w));
  assert_non_null(w);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* Enums                                                                                       */

static void test_bad_enums(void** state) {
  fixture* fx = *state;
  mica_world* w = fx->world;
  mica_body_id out = 0;
  const int32_t bad_models[3] = {7, -1, 2};
  for (int i = 0; i < 3; ++i) {
    mica_body_def bd = mica_body_def_default();
    bd.model = bad_models[i];
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(w, &bd, kLo, kHi, kCells, 6, &out), "model");
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create(w, &bd, kTwoTetNodes, 5, kTwoTets, 2, &out), "model");
  }
  const int32_t bad_mass[3] = {-1, 2, 100};
  for (int i = 0; i < 3; ++i) {
    mica_body_def bd = mica_body_def_default();
    bd.mass = bad_mass[i];
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(w, &bd, kLo, kHi, kCells, 6, &out), "mass");
  }
  const int32_t bad_static[3] = {2, -1, INT32_MAX};
  for (int i = 0; i < 3; ++i) {
    mica_body_def bd = mica_body_def_default();
    bd.is_static = bad_static[i];
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(w, &bd, kLo, kHi, kCells, 6, &out), "is_static");
  }
  const int32_t bad_tpc[5] = {4, 0, -5, 7, 12};
  const mica_body_def bd = mica_body_def_default();
  for (int i = 0; i < 5; ++i)
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_body_create_box(w, &bd, kLo, kHi, kCells, bad_tpc[i], &out),
                "tets_per_cell");
  assert_int_equal(out, 0);

  const int32_t bad_solver[4] = {99, -1, MICA_SOLVER_MICA + 1, INT32_MIN};
  for (int i = 0; i < 4; ++i) {
    mica_world_def wd = mica_world_def_default();
    wd.solver = bad_solver[i];
    mica_world* nw = (mica_world*)&wd;
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_create(&wd, &nw), "solver");
    assert_null(nw);
  }

  const int32_t bad_kind[3] = {42, -1, 4};
  const int32_t nodes[2] = {1, 2};
  for (int i = 0; i < 3; ++i) {
    mica_lpc_def ld = mica_lpc_def_default();
    ld.kind = bad_kind[i];
    mica_lpc_id lpc = 0;
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_add_lpc(w, fx->body, nodes, 2, &ld, &lpc), "kind");
    assert_int_equal(lpc, 0);
  }
}

/* ------------------------------------------------------------------------------------------ */
/* Bad meshes                                                                                  */

static void test_bad_meshes(void** state) {
  fixture* fx = *state;
  mica_world* w = fx->world;
  const mica_body_def bd = mica_body_def_default();
  mica_body_id out = 0;

  /* The valid mesh is accepted (control), in a world of its own. */
  {
    mica_world_def wd = mica_world_def_default();
    mica_world* other = NULL;
    REQUIRE_OK(mica_world_create(&wd, &other));
    REQUIRE_OK_W(other, mica_body_create(other, &bd, kTwoTetNodes, 5, kTwoTets, 2, &out));
    mica_world_destroy(other);
    out = 0;
  }

  /* Inverted: two nodes of tet 1 swapped. */
  int32_t inverted[8] = {0, 1, 2, 3, 2, 1, 3, 4};
  EXPECT_FAIL(fx, MICA_ERR_BAD_MESH, mica_body_create(w, &bd, kTwoTetNodes, 5, inverted, 2, &out), "tet 1");
  int32_t inverted0[8] = {0, 1, 3, 2, 1, 2, 3, 4};
  EXPECT_FAIL(fx, MICA_ERR_BAD_MESH, mica_body_create(w, &bd, kTwoTetNodes, 5, inverted0, 2, &out), "tet 0");

  /* Zero volume: tet 1 has four coplanar nodes (z = 0). */
  const double flat_nodes[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 0};
  const int32_t flat_tets[8] = {0, 1, 2, 3, 0, 1, 4, 2};
  EXPECT_FAIL(fx, MICA_ERR_BAD_MESH, mica_body_create(w, &bd, flat_nodes, 5, flat_tets, 2, &out), "tet 1");
  /* A single flat tet, and a tet whose nodes all coincide. */
  const double flat4[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  const int32_t one[4] = {0, 1, 2, 3};
  EXPECT_FAIL(fx, MICA_ERR_BAD_MESH, mica_body_create(w, &bd, flat4, 4, one, 1, &out), "tet 0");
  const double same4[12] = {1, 2, 3, 1, 2, 3, 1, 2, 3, 1, 2, 3};
  EXPECT_FAIL(fx, MICA_ERR_BAD_MESH, mica_body_create(w, &bd, same4, 4, one, 1, &out), "tet 0");

  /* Node 5 is used by no tet. */
  const double six_nodes[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 5, 5, 5};
  EXPECT_FAIL(fx, MICA_ERR_BAD_MESH, mica_body_create(w, &bd, six_nodes, 6, kTwoTets, 2, &out), "node 5");
  /* Node 4 is used by no tet (only tet 0 given). */
  EXPECT_FAIL(fx, MICA_ERR_BAD_MESH, mica_body_create(w, &bd, kTwoTetNodes, 5, kTwoTets, 1, &out), "node 4");

  /* A node repeated within a tet. */
  const int32_t repeated[8] = {0, 1, 2, 3, 1, 2, 2, 4};
  EXPECT_FAIL(fx, MICA_ERR_BAD_MESH, mica_body_create(w, &bd, kTwoTetNodes, 5, repeated, 2, &out), "tet 1");
  const int32_t all_same[8] = {0, 1, 2, 3, 4, 4, 4, 4};
  EXPECT_FAIL(fx, MICA_ERR_BAD_MESH, mica_body_create(w, &bd, kTwoTetNodes, 5, all_same, 2, &out), "tet 1");
  assert_int_equal(out, 0);
}

/* ------------------------------------------------------------------------------------------ */
/* Mesh files                                                                                  */

static void test_mesh_files(void** state) {
  fixture* fx = *state;
  mica_world* w = fx->world;
  const mica_body_def bd = mica_body_def_default();
  mica_body_id out = 0;

  /* Missing files. */
  char missing[600];
  snprintf(missing, sizeof missing, "%s/no-such-dir/missing.msh", g_dir);
  EXPECT_FAIL(fx, MICA_ERR_IO, mica_body_create_from_file(w, &bd, missing, &out), missing);
  snprintf(missing, sizeof missing, "%s/missing.node", g_dir);
  EXPECT_FAIL(fx, MICA_ERR_IO, mica_body_create_from_file(w, &bd, missing, &out), missing);
  /* A directory named like a mesh. */
  const char* dir = tmp_path("directory.msh");
  assert_int_equal(mkdir(dir, 0700), 0);
  EXPECT_FAIL(fx, MICA_ERR_IO, mica_body_create_from_file(w, &bd, dir, &out), dir);

  /* Unknown extensions, whether or not the file exists. */
  const char* stl = write_tmp("mesh.stl", "solid x\nendsolid x\n");
  EXPECT_FAIL(fx, MICA_ERR_UNSUPPORTED, mica_body_create_from_file(w, &bd, stl, &out), stl);
  EXPECT_FAIL(fx, MICA_ERR_UNSUPPORTED, mica_body_create_from_file(w, &bd, "/nonexistent/mesh.obj", &out),
              "/nonexistent/mesh.obj");
  EXPECT_FAIL(fx, MICA_ERR_UNSUPPORTED, mica_body_create_from_file(w, &bd, "", &out), NULL);

  /* Malformed Gmsh files: a parse error with the line number. */
  static const char* const kHead = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n";
  struct {
    const char* name;
    const char* body;
    int with_head;
  } bad[] = {
      /* $Nodes promises 5 nodes and the file ends after 2 */
      {"truncated_nodes.msh", "$Nodes\n5\n1 0 0 0\n2 1 0 0\n", 1},
      /* the same, cut in the middle of a line */
      {"truncated_line.msh", "$Nodes\n5\n1 0 0 0\n2 1 0", 1},
      /* a coordinate that is not a number */
      {"bad_coordinate.msh", "$Nodes\n1\n1 0 abc 0\n$EndNodes\n", 1},
      /* a non-finite coordinate */
      {"nan_coordinate.msh", "$Nodes\n1\n1 0 nan 0\n$EndNodes\n", 1},
      /* a node count that the file cannot hold */
      {"lying_count.msh", "$Nodes\n999999999999\n1 0 0 0\n$EndNodes\n", 1},
      {"negative_count.msh", "$Nodes\n-3\n$EndNodes\n", 1},
      /* an element naming a node that $Nodes did not list */
      {"unknown_node.msh",
       "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 0 1 2 3 99\n$EndElements\n", 1},
      /* a tet with three nodes */
      {"short_tet.msh",
       "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 0 1 2 3\n$EndElements\n", 1},
      /* a missing $EndNodes */
      {"no_end.msh", "$Nodes\n1\n1 0 0 0\n$Elements\n", 1},
      /* not a Gmsh file at all, an empty file, binary garbage */
      {"not_gmsh.msh", "hello world\n", 0},
      {"empty.msh", "", 0},
      {"garbage.msh", "\x01\x02\x03\xff\xfe\n\n\x7f", 0},
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
    char text[1024];
    snprintf(text, sizeof text, "%s%s", bad[i].with_head ? kHead : "", bad[i].body);
    const char* path = write_tmp(bad[i].name, text);
    assert_non_null(path);
    EXPECT_FAIL(fx, MICA_ERR_PARSE, mica_body_create_from_file(w, &bd, path, &out), "line", path);
  }

  /* Malformed TetGen pair. */
  write_tmp("bad_pair.ele", "1 4 0\n0 0 1 2 3\n");
  const char* node = write_tmp("bad_pair.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 one 0\n3 0 0 1\n");
  EXPECT_FAIL(fx, MICA_ERR_PARSE, mica_body_create_from_file(w, &bd, node, &out), "line");
  assert_int_equal(out, 0);

  /* Control: a valid file (the two-tet mesh) loads, in another world. */
  const char* good = write_tmp("good.msh",
                               "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
                               "5 1 1 1\n$EndNodes\n$Elements\n2\n1 4 0 1 2 3 4\n2 4 0 2 3 4 5\n$EndElements\n");
  mica_world_def wd = mica_world_def_default();
  mica_world* other = NULL;
  REQUIRE_OK(mica_world_create(&wd, &other));
  REQUIRE_OK_W(other, mica_body_create_from_file(other, &bd, good, &out));
  int32_t n = 0, t = 0;
  REQUIRE_OK_W(other, mica_body_get_counts(other, out, &n, &t, NULL));
  assert_int_equal(n, 5);
  assert_int_equal(t, 2);
  mica_world_destroy(other);
}

/* ------------------------------------------------------------------------------------------ */
/* Output files                                                                                */

static void test_vtk_bad_paths(void** state) {
  fixture* fx = *state;
  char path[600];
  snprintf(path, sizeof path, "%s/no-such-dir/out.vtk", g_dir);
  EXPECT_FAIL(fx, MICA_ERR_IO, mica_body_write_vtk(fx->world, fx->body, path), path);
  EXPECT_FAIL(fx, MICA_ERR_IO, mica_world_write_vtk(fx->world, path), path);
  EXPECT_FAIL(fx, MICA_ERR_IO, mica_body_write_vtk(fx->world, fx->body, g_dir), NULL);
  EXPECT_FAIL(fx, MICA_ERR_IO, mica_world_write_vtk(fx->world, g_dir), NULL);
  EXPECT_FAIL(fx, MICA_ERR_IO, mica_world_write_vtk(fx->world, ""), NULL);
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
/* Status text, stage names, the log                                                           */

static void test_status_strings(void** state) {
  (void)state;
#define S(code) {code, #code}
  static const struct {
    mica_status code;
    const char* name;
  } kCodes[] = {
      S(MICA_OK),
      S(MICA_WARN_NOT_CONVERGED),
      S(MICA_ERR_NULL_ARGUMENT),
      S(MICA_ERR_INVALID_ARGUMENT),
      S(MICA_ERR_OUT_OF_RANGE),
      S(MICA_ERR_STALE_ID),
      S(MICA_ERR_VERSION_MISMATCH),
      S(MICA_ERR_STRUCT_SIZE),
      S(MICA_ERR_BAD_MESH),
      S(MICA_ERR_IO),
      S(MICA_ERR_PARSE),
      S(MICA_ERR_NUMERICAL),
      S(MICA_ERR_WRONG_STATE),
      S(MICA_ERR_UNSUPPORTED),
      S(MICA_ERR_BUFFER_TOO_SMALL),
      S(MICA_ERR_DEVICE),
      S(MICA_ERR_OUT_OF_MEMORY),
      S(MICA_ERR_INTERNAL),
  };
#undef S
  const size_t count = sizeof kCodes / sizeof kCodes[0];
  const mica_status unknown[6] = {2, -17, 100, -1000, INT32_MAX, INT32_MIN};
  for (size_t i = 0; i < count; ++i) {
    const char* text = mica_status_string(kCodes[i].code);
    assert_non_null(text);
    assert_true(strlen(text) > strlen(kCodes[i].name));
    /* names its code: "MICA_ERR_STALE_ID: ..." */
    if (!has_phrase(text, kCodes[i].name)) {
      print_error("mica_status_string(%s) = '%s' does not name the status\n", kCodes[i].name, text);
      fail();
    }
    for (size_t j = 0; j < i; ++j) assert_string_not_equal(text, mica_status_string(kCodes[j].code));
    for (int u = 0; u < 6; ++u) assert_string_not_equal(text, mica_status_string(unknown[u]));
  }
  for (int u = 0; u < 6; ++u) {
    const char* text = mica_status_string(unknown[u]);
    assert_non_null(text);
    assert_true(strlen(text) > 0);
  }
}

static void test_stage_names(void** state) {
  (void)state;
  const int32_t outside[4] = {-1, MICA_STAGE_COUNT, INT32_MIN, INT32_MAX};
  for (int i = 0; i < 4; ++i) {
    assert_non_null(mica_stage_name(outside[i]));
    assert_string_equal(mica_stage_name(outside[i]), "unknown");
  }
  for (int32_t s = 0; s < MICA_STAGE_COUNT; ++s) {
    const char* name = mica_stage_name(s);
    assert_non_null(name);
    assert_true(strlen(name) > 0);
    assert_string_not_equal(name, "unknown");
    for (int32_t t = 0; t < s; ++t) assert_string_not_equal(name, mica_stage_name(t));
  }
  assert_string_equal(mica_stage_name(MICA_STAGE_SOLVE), "solve");
  assert_string_equal(mica_stage_name(MICA_STAGE_ROTATIONS), "rotations");
}

typedef struct {
  int calls;
  int32_t level;
  void* user;
  char message[1024];
} log_record;

static void log_into(int32_t level, const char* message, void* user) {
  log_record* r = user;
  r->calls += 1;
  r->level = level;
  r->user = user;
  snprintf(r->message, sizeof r->message, "%s", message);
}

static void test_log_callback(void** state) {
  (void)state;
  log_record record;
  memset(&record, 0, sizeof record);
  mica_world_def wd = mica_world_def_default();
  wd.log = log_into;
  wd.log_user = &record;
  mica_world* w = NULL;
  REQUIRE_OK(mica_world_create(&wd, &w));
  assert_int_equal(record.calls, 0); /* success is silent at this level */

  EXPECT_STATUS(MICA_ERR_INVALID_ARGUMENT, mica_step(w, -1.0));
  assert_int_equal(record.calls, 1);
  assert_int_equal(record.level, MICA_LOG_ERROR);
  assert_ptr_equal(record.user, &record);
  assert_string_equal(record.message, mica_world_last_error(w));
  assert_true(has_phrase(record.message, "mica_step"));

  EXPECT_STATUS(MICA_ERR_STALE_ID, mica_body_destroy(w, 12345));
  assert_int_equal(record.calls, 2);
  assert_int_equal(record.level, MICA_LOG_ERROR);
  assert_string_equal(record.message, mica_world_last_error(w));
  assert_true(has_phrase(record.message, "0x3039"));

  const mica_body_def bd = mica_body_def_default();
  const int32_t inverted[8] = {0, 1, 2, 3, 2, 1, 3, 4};
  mica_body_id out = 0;
  EXPECT_STATUS(MICA_ERR_BAD_MESH, mica_body_create(w, &bd, kTwoTetNodes, 5, inverted, 2, &out));
  assert_int_equal(record.calls, 3);
  assert_true(has_phrase(record.message, "tet 1"));
  assert_string_equal(record.message, mica_world_last_error(w));

  /* Successful calls do not log errors. */
  REQUIRE_OK_W(w, mica_body_create(w, &bd, kTwoTetNodes, 5, kTwoTets, 2, &out));
  REQUIRE_OK_W(w, mica_step(w, 0.01));
  assert_int_equal(record.calls, 3);
  mica_world_destroy(w);

  /* A world without a log fails the same way, silently. */
  wd.log = NULL;
  wd.log_user = NULL;
  REQUIRE_OK(mica_world_create(&wd, &w));
  EXPECT_STATUS(MICA_ERR_INVALID_ARGUMENT, mica_step(w, NAN));
  assert_true(strlen(mica_world_last_error(w)) > 0);
  mica_world_destroy(w);
}

/* ------------------------------------------------------------------------------------------ */
/* Constraint reactions and tools                                                              */

static void test_lpc_reaction_bad_input(void** state) {
  fixture* fx = *state;
  double f[3] = {SENTINEL_D, SENTINEL_D, SENTINEL_D};
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_lpc_get_reaction(NULL, fx->lpc, f), "world");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_lpc_get_reaction(fx->world, fx->lpc, NULL), "out_force");
  const mica_lpc_id bad[5] = {fx->dead_lpc, fx->body, MICA_NULL_ID, 0x0200000100000063u, UINT64_MAX};
  for (int i = 0; i < 5; ++i) {
    char hex[32];
    EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_lpc_get_reaction(fx->world, bad[i], f), hex_id(bad[i], hex, sizeof hex));
  }
  assert_true(f[0] == SENTINEL_D && f[1] == SENTINEL_D && f[2] == SENTINEL_D);
  /* The live constraint answers with finite numbers. */
  EXPECT_STATUS(MICA_OK, mica_lpc_get_reaction(fx->world, fx->lpc, f));
  assert_true(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2]));
}

typedef struct {
  const char* what;
  void (*spoil)(mica_tool_def*, double);
  int32_t shape;
} tool_field;

static void spoil_radius(mica_tool_def* d, double x) { d->radius = x; }
static void spoil_normal(mica_tool_def* d, double x) { d->normal[1] = x; }
static void spoil_position(mica_tool_def* d, double x) { d->position[2] = x; }
static void spoil_orientation_w(mica_tool_def* d, double x) { d->orientation[0] = x; }
static void spoil_orientation_z(mica_tool_def* d, double x) { d->orientation[3] = x; }
static void spoil_margin(mica_tool_def* d, double x) { d->margin = x; }

static void test_tools_bad_input(void** state) {
  fixture* fx = *state;
  mica_world* w = fx->world;
  const mica_tool_def good = mica_tool_def_default();
  mica_tool_id tool = 0, dead_tool = 0;
  REQUIRE_OK_W(w, mica_tool_create(w, &good, &tool));
  REQUIRE_OK_W(w, mica_tool_create(w, &good, &dead_tool));
  REQUIRE_OK_W(w, mica_tool_destroy(w, dead_tool));
  const double p[3] = {0, 0, 0}, q[4] = {1, 0, 0, 0};
  double force[3] = {SENTINEL_D, SENTINEL_D, SENTINEL_D}, torque[3] = {SENTINEL_D, SENTINEL_D, SENTINEL_D};
  int32_t contacts = SENTINEL_I;
  mica_tool_id out = 0;

  /* NULL pointers */
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_tool_create(NULL, &good, &out), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_tool_destroy(NULL, tool), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_tool_set_pose(NULL, tool, p, q), "world");
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_tool_get_force(NULL, tool, force, torque, &contacts),
                       "world");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_tool_create(w, NULL, &out), "def");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_tool_create(w, &good, NULL), "out_tool");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_tool_set_pose(w, tool, NULL, q), "position");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_tool_set_pose(w, tool, p, NULL), "orientation");

  /* Non-finite and out-of-domain def values */
  const tool_field fields[] = {
      {"radius", spoil_radius, MICA_TOOL_SPHERE},
      {"normal", spoil_normal, MICA_TOOL_PLANE},
      {"position", spoil_position, MICA_TOOL_SPHERE},
      {"position", spoil_position, MICA_TOOL_PLANE},
      {"orientation", spoil_orientation_w, MICA_TOOL_SPHERE},
      {"orientation", spoil_orientation_z, MICA_TOOL_PLANE},
      {"margin", spoil_margin, MICA_TOOL_SPHERE},
  };
  const double nonfinite[3] = {NAN, INFINITY, -INFINITY};
  for (size_t k = 0; k < sizeof fields / sizeof fields[0]; ++k)
    for (int i = 0; i < 3; ++i) {
      mica_tool_def d = mica_tool_def_default();
      d.shape = fields[k].shape;
      fields[k].spoil(&d, nonfinite[i]);
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_tool_create(w, &d, &out), NULL);
    }
  {
    mica_tool_def d = mica_tool_def_default();
    const double bad_radius[2] = {0.0, -0.01};
    for (int i = 0; i < 2; ++i) {
      d.radius = bad_radius[i];
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_tool_create(w, &d, &out), NULL);
    }
    d = mica_tool_def_default();
    d.margin = -1e-3;
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_tool_create(w, &d, &out), NULL);
    d = mica_tool_def_default();
    d.shape = MICA_TOOL_PLANE;
    d.normal[0] = d.normal[1] = d.normal[2] = 0;
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_tool_create(w, &d, &out), NULL);
  }
  const int32_t bad_shape[3] = {5, -1, 42};
  for (int i = 0; i < 3; ++i) {
    mica_tool_def d = mica_tool_def_default();
    d.shape = bad_shape[i];
    EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_tool_create(w, &d, &out), "shape");
  }
  for (int k = 0; k < 3; ++k) {
    struct {
      mica_tool_def d;
      char pad[16];
    } d;
    memset(&d, 0, sizeof d);
    d.d = mica_tool_def_default();
    const uint32_t sizes[3] = {0, 1, (uint32_t)sizeof(mica_tool_def) + 8};
    d.d.struct_size = sizes[k];
    EXPECT_FAIL(fx, MICA_ERR_STRUCT_SIZE, mica_tool_create(w, &d.d, &out), "struct_size");
    union {
      mica_tool_def d;
      unsigned char bytes[sizeof(mica_tool_def) + 16];
    } u;
    memset(&u, 0xcd, sizeof u);
    EXPECT_STATUS(MICA_ERR_STRUCT_SIZE, mica_tool_def_init(&u.d, sizes[k]));
    for (size_t i = 0; i < sizeof u.bytes; ++i) assert_int_equal(u.bytes[i], 0xcd);
  }
  assert_int_equal(out, 0);

  /* Poses */
  for (int i = 0; i < 3; ++i)
    for (int c = 0; c < 4; ++c) {
      double pp[3] = {0, 0, 0}, qq[4] = {1, 0, 0, 0};
      if (c < 3) {
        pp[c] = nonfinite[i];
        EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_tool_set_pose(w, tool, pp, qq), NULL);
        pp[c] = 0;
      }
      qq[c] = nonfinite[i];
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_tool_set_pose(w, tool, pp, qq), NULL);
    }
  const double zero_q[4] = {0, 0, 0, 0};
  EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_tool_set_pose(w, tool, p, zero_q), NULL);

  /* Stale tool ids */
  const mica_tool_id bad[6] = {dead_tool, fx->body, fx->lpc, MICA_NULL_ID, 0x0300000100000063u, UINT64_MAX};
  for (int i = 0; i < 6; ++i) {
    char hex[32];
    hex_id(bad[i], hex, sizeof hex);
    EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_tool_destroy(w, bad[i]), hex);
    EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_tool_set_pose(w, bad[i], p, q), hex);
    EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_tool_get_force(w, bad[i], force, torque, &contacts), hex);
  }
  assert_true(force[0] == SENTINEL_D && torque[2] == SENTINEL_D && contacts == SENTINEL_I);
  /* A tool id where a body or a constraint id is expected */
  int32_t n = SENTINEL_I;
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_body_get_counts(w, tool, &n, NULL, NULL), NULL);
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_lpc_remove(w, tool), NULL);
  assert_int_equal(n, SENTINEL_I);

  /* The live tool still works, all outputs optional. */
  EXPECT_STATUS(MICA_OK, mica_tool_get_force(w, tool, NULL, NULL, NULL));
  EXPECT_STATUS(MICA_OK, mica_tool_destroy(w, tool));

  /* A zero quaternion is no rotation: refused at creation as mica_tool_set_pose refuses it.
   * (Checked last, and a wrongly created tool removed, so that the teardown's step, which a
   * tool in a DIRECT world would turn into MICA_ERR_UNSUPPORTED, still tests the world.) */
  mica_tool_def d = mica_tool_def_default();
  d.orientation[0] = d.orientation[1] = d.orientation[2] = d.orientation[3] = 0;
  out = 0;
  const mica_status zero_status = mica_tool_create(w, &d, &out);
  if (zero_status == MICA_OK) mica_tool_destroy(w, out);
  fx->log_calls = 0;
  EXPECT_STATUS(MICA_ERR_INVALID_ARGUMENT, zero_status);
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

static void test_error_message_scopes(void** state) {
  fixture* fx = *state;
  EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_step(fx->world, -2.0), NULL);
  char world_message[1024];
  snprintf(world_message, sizeof world_message, "%s", mica_world_last_error(fx->world));
  mica_world* w = (mica_world*)fx;
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_world_create(NULL, &w), "def");
  assert_string_equal(mica_world_last_error(fx->world), world_message);
  assert_string_not_equal(mica_world_last_error(NULL), world_message);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_null_world, setup, teardown),
      cmocka_unit_test_setup_teardown(test_null_world_create, setup, teardown),
      cmocka_unit_test_setup_teardown(test_null_def_init, setup, teardown),
      cmocka_unit_test_setup_teardown(test_null_pointers, setup, teardown),
      cmocka_unit_test_setup_teardown(test_optional_outputs_may_be_null, setup, teardown),
      cmocka_unit_test_setup_teardown(test_nonfinite_world_def, setup, teardown),
      cmocka_unit_test_setup_teardown(test_nonfinite_gravity, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_body_def_values, setup, teardown),
      cmocka_unit_test_setup_teardown(test_nonfinite_node_coordinates, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_box_corners, setup, teardown),
      cmocka_unit_test_setup_teardown(test_nonfinite_lpc, setup, teardown),
      cmocka_unit_test_setup_teardown(test_nonfinite_node_forces, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_dt, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_selection_inputs, setup, teardown),
      cmocka_unit_test_setup_teardown(test_out_of_range_lpc_nodes, setup, teardown),
      cmocka_unit_test_setup_teardown(test_out_of_range_node_forces, setup, teardown),
      cmocka_unit_test_setup_teardown(test_out_of_range_tets, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_counts, setup, teardown),
      cmocka_unit_test_setup_teardown(test_huge_box, setup, teardown),
      cmocka_unit_test_setup_teardown(test_buffer_too_small, setup, teardown),
      cmocka_unit_test_setup_teardown(test_negative_capacity, setup, teardown),
      cmocka_unit_test_setup_teardown(test_stale_body_ids, setup, teardown),
      cmocka_unit_test_setup_teardown(test_stale_lpc_ids, setup, teardown),
      cmocka_unit_test_setup_teardown(test_struct_size, setup, teardown),
      cmocka_unit_test(test_struct_size_init),
      cmocka_unit_test_setup_teardown(test_version_mismatch, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_enums, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_meshes, setup, teardown),
      cmocka_unit_test_setup_teardown(test_mesh_files, setup, teardown),
      cmocka_unit_test_setup_teardown(test_vtk_bad_paths, setup, teardown),
      cmocka_unit_test(test_failed_calls_leave_no_trace),
      cmocka_unit_test(test_status_strings),
      cmocka_unit_test(test_stage_names),
      cmocka_unit_test(test_log_callback),
      cmocka_unit_test_setup_teardown(test_lpc_reaction_bad_input, setup, teardown),
      cmocka_unit_test_setup_teardown(test_tools_bad_input, setup, teardown),
      cmocka_unit_test(test_numerical_failure_direct),
      cmocka_unit_test(test_numerical_failure_pcg),
      cmocka_unit_test(test_numerical_failure_mica),
      cmocka_unit_test(test_numerical_failure_mica_factored),
      cmocka_unit_test_setup_teardown(test_error_message_scopes, setup, teardown),
  };
  return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
