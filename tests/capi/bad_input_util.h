/* SPDX-License-Identifier: Apache-2.0 */
/* Shared by tests/capi/test_bad_input_*.c (one file per capi/<concern>.cpp): every entry point of mica.h,
 * given bad input, returns a clear status and a message that names what was wrong, leaves the
 * world exactly as it was, and never crashes.
 *
 * "Exactly as it was" is checked by one helper (check_failure) that snapshots the fixture world
 * before the call (positions, velocities, rest positions, surface, counts, energies, the stats,
 * and the number of points the whole world writes to VTK, which counts its bodies' nodes) and
 * compares it bit for bit afterwards. It also checks that the world's log callback received the
 * same message at MICA_LOG_ERROR with the user pointer.
 *
 * A file's cases are tables of bad_case rows ({name, the call that builds the bad input, the
 * expected status, a phrase the message must name}) run by run_bad_cases, which applies
 * check_failure to every row and every variant of a row.
 *
 * Files are written only to a fresh directory under /tmp, removed at the end. Everything here is
 * static or static inline: each test file includes it once. */
#ifndef MICA_TESTS_CAPI_BAD_INPUT_UTIL_H
#define MICA_TESTS_CAPI_BAD_INPUT_UTIL_H

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

#define COUNT_OF(a) (sizeof(a) / sizeof((a)[0]))

/* ------------------------------------------------------------------------------------------ */
/* Temporary files                                                                             */

static char g_dir[256];
static char g_files[64][512];
static int g_file_count;

/* g_dir/name, remembered for removal at the end. */
static inline const char* tmp_path(const char* name) {
  for (int i = 0; i < g_file_count; ++i) {
    const char* slash = strrchr(g_files[i], '/');
    if (slash && strcmp(slash + 1, name) == 0) return g_files[i];
  }
  if (g_file_count >= 64) return NULL;
  snprintf(g_files[g_file_count], sizeof g_files[0], "%s/%s", g_dir, name);
  return g_files[g_file_count++];
}

static inline const char* write_tmp(const char* name, const char* text) {
  const char* path = tmp_path(name);
  FILE* f = fopen(path, "wb");
  if (!f) return NULL;
  fputs(text, f);
  fclose(f);
  return path;
}

static inline int group_setup(void** state) {
  (void)state;
  strcpy(g_dir, "/tmp/mica-capi-bad-input-XXXXXX");
  return mkdtemp(g_dir) ? 0 : -1;
}

static inline int group_teardown(void** state) {
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

static inline void record_log(int32_t level, const char* message, void* user) {
  fixture* fx = (fixture*)user;
  fx->log_calls += 1;
  fx->log_level = level;
  fx->log_user = user;
  snprintf(fx->log_message, sizeof fx->log_message, "%s", message ? message : "(null)");
}

static const double kLo[3] = {0, 0, 0};
static const double kHi[3] = {0.3, 0.1, 0.1};
static const int32_t kCells[3] = {3, 1, 1};
static const double kNonfinite[3] = {NAN, INFINITY, -INFINITY};

/* A valid two-tet mesh: tet 0 = (0,1,2,3) and tet 1 = (1,2,3,4) share the face (1,2,3). */
static const double kTwoTetNodes[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
static const int32_t kTwoTets[8] = {0, 1, 2, 3, 1, 2, 3, 4};
/* The same mesh as a Gmsh 2.2 file. */
static const char kTwoTetMsh[] =
    "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"
    "5 1 1 1\n$EndNodes\n$Elements\n2\n1 4 0 1 2 3 4\n2 4 0 2 3 4 5\n$EndElements\n";

#define SENTINEL_D (-12345.678)
#define SENTINEL_I (-777)

#define REQUIRE_OK_W(world, call)                                                                    \
  do {                                                                                               \
    const mica_status s_ = (call);                                                                   \
    if (s_ != MICA_OK) {                                                                             \
      print_error("%s:%d: %s returned %s\n  last error: %s\n", __FILE__, __LINE__, #call,            \
                  mica_status_string(s_), mica_world_last_error(world));                             \
      _fail(__FILE__, __LINE__);                                                                     \
    }                                                                                                \
  } while (0)

/* For calls without a world: the message is on the thread. */
#define REQUIRE_OK(call) REQUIRE_OK_W(NULL, call)

#define EXPECT_STATUS(expected, call)                                                                \
  do {                                                                                               \
    const mica_status got_ = (call);                                                                 \
    if (got_ != (expected)) {                                                                        \
      print_error("%s:%d: %s\n  returned %d (%s)\n  expected %d (%s)\n", __FILE__, __LINE__, #call, got_, \
                  mica_status_string(got_), (expected), mica_status_string(expected));               \
      _fail(__FILE__, __LINE__);                                                                     \
    }                                                                                                \
  } while (0)

/* The fixture world with the given solver; NULL on failure. */
static inline fixture* new_fixture(int32_t solver, int32_t sweep) {
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

static inline int setup(void** state) {
  fixture* fx = new_fixture(MICA_SOLVER_DIRECT, MICA_SWEEP_FACTORED);
  *state = fx;
  return fx ? 0 : -1;
}

static inline int teardown(void** state) {
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

static inline int is_ident(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

/* `phrase` occurs in `text` as whole words: not inside a longer identifier or number
 * ("world" does not match inside "mica_world_create", "1" does not match inside "17"). */
static inline int has_phrase(const char* text, const char* phrase) {
  const size_t n = strlen(phrase);
  if (n == 0) return 1;
  for (const char* p = strstr(text, phrase); p; p = strstr(p + 1, phrase)) {
    const int left_ok = p == text || !is_ident(p[-1]) || !is_ident(phrase[0]);
    const int right_ok = p[n] == '\0' || !is_ident(p[n]) || !is_ident(phrase[n - 1]);
    if (left_ok && right_ok) return 1;
  }
  return 0;
}

static inline const char* hex_id(uint64_t id, char* text, size_t size) {
  snprintf(text, size, "0x%llx", (unsigned long long)id);
  return text;
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

static inline long vtk_points(const char* path) {
  FILE* f = fopen(path, "rb");
  if (!f) return -1;
  char line[512];
  long n = -2;
  while (fgets(line, sizeof line, f))
    if (sscanf(line, "POINTS %ld", &n) == 1) break;
  fclose(f);
  return n;
}

static inline void take_snapshot(const fixture* fx, snapshot* s) {
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

static inline void free_snapshot(snapshot* s) {
  free(s->x);
  free(s->v);
  free(s->rest);
  free(s->surface);
}

/* Nonzero when a and b differ; says where. */
static inline int snapshot_differs(const snapshot* a, const snapshot* b, char* why, size_t why_size) {
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
 * the fixture world did not change. Frees `before`. */
static inline void check_failure(fixture* fx, snapshot* before, mica_status got, mica_status expected, int on_thread,
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
#define EXPECT_FAIL(fx, expected, call, ...) EXPECT_FAIL_ON_(0, fx, expected, call, #call, __VA_ARGS__)

/* The same for a call made without a world (world == NULL, creation): the message is on the
 * thread. The fixture world must still be unchanged. */
#define EXPECT_FAIL_NO_WORLD(fx, expected, call, ...) EXPECT_FAIL_ON_(1, fx, expected, call, #call, __VA_ARGS__)

#define EXPECT_FAIL_ON_(on_thread, fx, expected, call, text, ...)                                     \
  do {                                                                                               \
    snapshot before_;                                                                                \
    take_snapshot((fx), &before_);                                                                   \
    (fx)->log_calls = 0;                                                                             \
    const mica_status got_ = (call);                                                                 \
    check_failure((fx), &before_, got_, (expected), (on_thread), (text),                             \
                  (const char* const[]){__VA_ARGS__, NULL}, __FILE__, __LINE__);                     \
  } while (0)

/* ------------------------------------------------------------------------------------------ */
/* Tables of bad calls                                                                         */

typedef mica_status (*node_getter)(const mica_world*, mica_body_id, double*, int32_t, int32_t*);
typedef mica_status (*index_getter)(fixture*, int32_t*, int32_t, int32_t*);

typedef struct index_list {
  const char* name;
  index_getter get;
  int32_t width; /* int32_t per item */
} index_list;

typedef struct mesh_arrays {
  const double* nodes;
  int32_t node_count;
  const int32_t* tets;
  int32_t tet_count;
} mesh_arrays;

/* What a row hands to its call besides the variant: which argument, field, getter, id or mesh. */
typedef union bad_with {
  int arg; /* which argument is bad, or which of several calls is made */
  void (*world_def)(mica_world_def*, int);
  void (*body_def)(mica_body_def*, int);
  void (*lpc_def)(mica_lpc_def*, int);
  void (*tool_def)(mica_tool_def*, int);
  node_getter nodes;
  const index_list* indices;
  uint64_t (*id)(const fixture*);
  const mesh_arrays* mesh;
} bad_with;

/* What a call sees, and what it reports beyond its status. */
typedef struct bad_call {
  fixture* fx;
  int i;         /* the variant: 0 .. the row's variants - 1 */
  bad_with with; /* the row's */
  const char* called;  /* the function called, where the row's name does not say (several creators) */
  char needle[2][600]; /* phrases known only once the call is built (an id, an index, a path) */
  char wrong[512];     /* what else went wrong: an output written although the call failed */
} bad_call;

typedef struct bad_case {
  const char* name;                /* "mica_function: what is bad" */
  mica_status (*call)(bad_call*);  /* builds the bad input, makes the call, returns its status */
  mica_status expected;
  const char* needle; /* the message names it as whole words; NULL for nothing in particular */
  int variants;       /* the call is made for c->i = 0 .. variants - 1; 0 means once */
  bad_with with;
  int no_world; /* NO_WORLD: the call has no world, its message is on the thread */
} bad_case;

#define NO_WORLD 1

/* In a call: `p`, or NULL where the row names argument k (.with.arg = k) as the NULL one. */
#define NULL_IF(k, p) (c->with.arg == (k) ? NULL : (p))

/* Sets a needle the call knows only once it is built. */
static inline void bad_needle(bad_call* c, int k, const char* format, ...) {
  va_list args;
  va_start(args, format);
  vsnprintf(c->needle[k], sizeof c->needle[k], format, args);
  va_end(args);
}

/* Says what else went wrong (the first thing only). */
static inline void bad_wrong(bad_call* c, const char* format, ...) {
  if (c->wrong[0]) return;
  va_list args;
  va_start(args, format);
  vsnprintf(c->wrong, sizeof c->wrong, format, args);
  va_end(args);
}

/* Every row, every variant: the status, the message, the log and the unchanged world
 * (check_failure), then whatever the call itself found wrong. */
static inline void run_bad_cases(fixture* fx, const bad_case* rows, size_t count, const char* file, int line) {
  for (size_t r = 0; r < count; ++r) {
    const int variants = rows[r].variants > 0 ? rows[r].variants : 1;
    for (int i = 0; i < variants; ++i) {
      bad_call c;
      memset(&c, 0, sizeof c);
      c.fx = fx;
      c.i = i;
      c.with = rows[r].with;
      snapshot before;
      take_snapshot(fx, &before);
      fx->log_calls = 0;
      const mica_status got = rows[r].call(&c);
      char call[512];
      snprintf(call, sizeof call, "%s%s%s [variant %d of %d]", c.called ? c.called : "", c.called ? ", " : "",
               rows[r].name, i, variants);
      const char* needles[4];
      int n = 0;
      if (rows[r].needle) needles[n++] = rows[r].needle;
      for (int k = 0; k < 2; ++k)
        if (c.needle[k][0]) needles[n++] = c.needle[k];
      needles[n] = NULL;
      check_failure(fx, &before, got, rows[r].expected, rows[r].no_world, call, needles, file, line);
      if (c.wrong[0]) {
        print_error("%s:%d: %s: %s\n", file, line, call, c.wrong);
        _fail(file, line);
      }
    }
  }
}

#define RUN_BAD_CASES(fx, rows) run_bad_cases((fx), (rows), COUNT_OF(rows), __FILE__, __LINE__)

/* The status `s` of a failed call that had `*id` (named `name`, set to 0 before the call) to
 * answer: it must still be 0. */
static inline mica_status id_unwritten(bad_call* c, const char* name, const uint64_t* id, mica_status s) {
  if (*id != 0) bad_wrong(c, "*%s is 0x%llx, not 0", name, (unsigned long long)*id);
  return s;
}

/* The status `s` of a failed call that had `doubles` (filled with SENTINEL_D) to answer into:
 * none may be written. */
static inline mica_status doubles_unwritten(bad_call* c, const double* doubles, size_t count, mica_status s) {
  for (size_t k = 0; k < count; ++k)
    if (doubles[k] != SENTINEL_D) return bad_wrong(c, "item %zu of the buffer was written", k), s;
  return s;
}

/* The same for `count` bytes that were `fill`. */
static inline mica_status bytes_unwritten(bad_call* c, const unsigned char* bytes, size_t count, unsigned char fill,
                                          mica_status s) {
  for (size_t k = 0; k < count; ++k)
    if (bytes[k] != fill) return bad_wrong(c, "byte %zu was written", k), s;
  return s;
}

/* The struct sizes that are not `size` (variant i): 0, 1, and larger than this header's. Where
 * the larger is tried, the struct sits in a buffer 16 bytes larger, so that it is safe. */
static inline uint32_t bad_struct_size(int i, size_t size) {
  const uint32_t sizes[3] = {0, 1, (uint32_t)size + 8};
  return sizes[i];
}

/* Any def, in a buffer larger than each: an oversized struct_size is safe to try. */
typedef union any_def {
  mica_world_def world;
  mica_body_def body;
  mica_lpc_def lpc;
  mica_tool_def tool;
  unsigned char bytes[sizeof(mica_world_def) + sizeof(mica_body_def) + sizeof(mica_lpc_def) + sizeof(mica_tool_def)];
} any_def;

enum def_kind { WORLD_DEF, BODY_DEF, LPC_DEF, TOOL_DEF };

/* mica_<kind>_def_init (.with.arg = the kind) with a NULL def. */
static inline mica_status def_init_without_def(bad_call* c) {
  switch (c->with.arg) {
    case WORLD_DEF: return mica_world_def_init(NULL, (uint32_t)sizeof(mica_world_def), MICA_VERSION_NUMBER);
    case BODY_DEF: return mica_body_def_init(NULL, (uint32_t)sizeof(mica_body_def));
    case LPC_DEF: return mica_lpc_def_init(NULL, (uint32_t)sizeof(mica_lpc_def));
    default: return mica_tool_def_init(NULL, (uint32_t)sizeof(mica_tool_def));
  }
}

/* mica_<kind>_def_init (.with.arg = the kind) with a struct_size that is not the def's (variant
 * i) leaves the def alone, every byte of it. */
static inline mica_status def_init_with_bad_size(bad_call* c) {
  any_def d;
  memset(&d, 0xcd, sizeof d);
  mica_status s = MICA_OK;
  switch (c->with.arg) {
    case WORLD_DEF:
      s = mica_world_def_init(&d.world, bad_struct_size(c->i, sizeof d.world), MICA_VERSION_NUMBER);
      break;
    case BODY_DEF: s = mica_body_def_init(&d.body, bad_struct_size(c->i, sizeof d.body)); break;
    case LPC_DEF: s = mica_lpc_def_init(&d.lpc, bad_struct_size(c->i, sizeof d.lpc)); break;
    default: s = mica_tool_def_init(&d.tool, bad_struct_size(c->i, sizeof d.tool)); break;
  }
  return bytes_unwritten(c, d.bytes, sizeof d.bytes, 0xcd, s);
}

/* Creation of a world from a def that must fail: the world pointer, set beforehand, is cleared. */
static inline mica_status create_world(bad_call* c, const mica_world_def* def) {
  mica_world* w = (mica_world*)c; /* not NULL: creation must clear it */
  const mica_status s = mica_world_create(def, &w);
  if (w) bad_wrong(c, "*out_world is %p, not NULL", (void*)w);
  if (s == MICA_OK) mica_world_destroy(w);
  return s;
}

#endif /* MICA_TESTS_CAPI_BAD_INPUT_UTIL_H */
