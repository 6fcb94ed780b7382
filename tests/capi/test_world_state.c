/* SPDX-License-Identifier: Apache-2.0 */
/* The world's state, read out whole (positions, velocities, contacts, statistics, tool forces,
 * constraint reactions, the saved state), for every solver:
 * - a step that fails is undone whole: after it, every readout is bit for bit that of the last good
 *   step, and the world then steps as a twin that never failed;
 * - a saved state restored into a fresh world reads out as the original and steps as it does (a
 *   value a step hands the next that the state's list leaves out fails here).
 * A sphere rests pressed into a box fixed at its base (a second box on top in the two-body case);
 * after ten good steps, node forces of 1e308 N on every node make the velocities overflow. */
#include <stdarg.h>
#include <stddef.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include <mica/mica.h>

#include "box_scene.h"
#include "capi_ok.h"

typedef struct solver_case {
  const char* name;
  int32_t solver, sweep, model, two_bodies;
} solver_case;

static const solver_case kCases[] = {
    {"MICA Gauss-Seidel", MICA_SOLVER_MICA, MICA_SWEEP_GAUSS_SEIDEL, MICA_MODEL_COROTATIONAL, 0},
    {"MICA factored", MICA_SOLVER_MICA, MICA_SWEEP_FACTORED, MICA_MODEL_COROTATIONAL, 0},
    {"exact (CHOLMOD)", MICA_SOLVER_DIRECT, MICA_SWEEP_FACTORED, MICA_MODEL_COROTATIONAL, 0},
    {"exact (PCG)", MICA_SOLVER_PCG, MICA_SWEEP_FACTORED, MICA_MODEL_COROTATIONAL, 0},
    {"MICA factored, linear", MICA_SOLVER_MICA, MICA_SWEEP_FACTORED, MICA_MODEL_LINEAR, 0},
    {"exact, linear", MICA_SOLVER_DIRECT, MICA_SWEEP_FACTORED, MICA_MODEL_LINEAR, 0},
    {"MICA factored, two bodies", MICA_SOLVER_MICA, MICA_SWEEP_FACTORED, MICA_MODEL_COROTATIONAL, 1},
    {"MICA factored, neo-Hookean", MICA_SOLVER_MICA, MICA_SWEEP_FACTORED, MICA_MODEL_NEO_HOOKEAN, 0},
    {"MICA Gauss-Seidel, neo-Hookean", MICA_SOLVER_MICA, MICA_SWEEP_GAUSS_SEIDEL, MICA_MODEL_NEO_HOOKEAN, 0},
    {"exact, neo-Hookean", MICA_SOLVER_DIRECT, MICA_SWEEP_FACTORED, MICA_MODEL_NEO_HOOKEAN, 0},
};

typedef struct scene {
  mica_world* w;
  box_scene box;
  mica_body_id top;  /* the second body, or MICA_NULL_ID */
} scene;

static void make_scene(scene* s, const solver_case* c) {
  mica_world_def wd = mica_world_def_default();
  wd.solver = c->solver;
  wd.mica_sweep = c->sweep;
  wd.refactor_interval = 3; /* a background refresh in flight when the step fails */
  OK(NULL, mica_world_create(&wd, &s->w));
  box_scene_def def = box_scene_def_default();
  def.body.model = c->model;
  def.body.youngs_modulus = 2e4;
  def.cells[0] = def.cells[1] = def.cells[2] = 4;
  def.tool_radius = 0.02;
  def.tool_position[0] = 0.03; /* off the top box, pressed 2 mm into the top face */
  def.tool_position[1] = 0.1 + 0.02 - 0.002;
  def.tool_position[2] = 0.05;
  OK(s->w, box_scene_create(s->w, &def, &s->box));
  s->top = MICA_NULL_ID;
  if (c->two_bodies) {
    const double lo[3] = {0.06, 0.1005, 0.03}, hi[3] = {0.08, 0.1205, 0.05};
    const int32_t cells[3] = {2, 2, 2};
    OK(s->w, mica_body_create_box(s->w, &def.body, lo, hi, cells, 6, &s->top));
  }
}

static void set_all_forces(scene* s, mica_body_id body, double value) {
  int32_t nodes = 0, tets = 0;
  OK(s->w, mica_body_get_counts(s->w, body, &nodes, &tets, NULL));
  int32_t* index = malloc(sizeof(int32_t) * (size_t)nodes);
  double* f = malloc(sizeof(double) * 3 * (size_t)nodes);
  for (int32_t i = 0; i < nodes; ++i) {
    index[i] = i;
    f[3 * i] = f[3 * i + 1] = f[3 * i + 2] = value;
  }
  OK(s->w, mica_body_set_node_forces(s->w, body, index, f, nodes));
  free(index);
  free(f);
}

/* Everything a host can read of the world, in one buffer, and the saved state. */
typedef struct readout {
  unsigned char* bytes;
  size_t size;
  void* state;
  size_t state_size;
} readout;

static void put(readout* r, const void* data, size_t n) {
  r->bytes = realloc(r->bytes, r->size + n);
  memcpy(r->bytes + r->size, data, n);
  r->size += n;
}

static void put_body(readout* r, scene* s, mica_body_id body) {
  int32_t nodes = 0, tets = 0, n = 0;
  OK(s->w, mica_body_get_counts(s->w, body, &nodes, &tets, NULL));
  double* x = malloc(sizeof(double) * 3 * (size_t)nodes);
  OK(s->w, mica_body_get_positions(s->w, body, x, nodes, &n));
  put(r, x, sizeof(double) * 3 * (size_t)n);
  OK(s->w, mica_body_get_velocities(s->w, body, x, nodes, &n));
  put(r, x, sizeof(double) * 3 * (size_t)n);
  free(x);
}

/* with_timings 0, for two worlds that stepped the same way at different times: the statistics'
 * wall-clock figures are zeroed and the saved state (which holds them) is left out; so is the
 * factorization count, a cache's (a linear body's plain matrix, factored in the failed step, is
 * the matrix the next step would factor: it need not). */
static readout read_world(scene* s, int with_timings) {
  readout r = {NULL, 0, NULL, 0};
  put_body(&r, s, s->box.body);
  if (s->top) put_body(&r, s, s->top);
  int32_t count = 0;
  OK(s->w, mica_world_get_contacts(s->w, NULL, 0, &count));
  assert_true(count > 0); /* the failed step must have contacts to leak */
  mica_contact* contacts = calloc((size_t)count, sizeof(mica_contact));
  contacts[0].struct_size = sizeof(mica_contact);
  OK(s->w, mica_world_get_contacts(s->w, contacts, count, &count));
  put(&r, contacts, sizeof(mica_contact) * (size_t)count);
  free(contacts);
  mica_world_stats stats;
  memset(&stats, 0, sizeof stats);
  stats.struct_size = sizeof stats;
  OK(s->w, mica_world_get_stats(s->w, &stats));
  if (!with_timings) {
    stats.ms_last_step = 0;
    for (int k = 0; k < MICA_STAGE_COUNT; ++k) stats.stages[k].ms_last_step = stats.stages[k].ms_total = 0;
    stats.factorizations = 0;
    stats.factor_waits = 0;
  }
  put(&r, &stats, sizeof stats);
  double f[3], t[3];
  int32_t active = 0;
  OK(s->w, mica_tool_get_force(s->w, s->box.tool, f, t, &active));
  put(&r, f, sizeof f);
  put(&r, t, sizeof t);
  put(&r, &active, sizeof active);
  OK(s->w, mica_lpc_get_reaction(s->w, s->box.base, f));
  put(&r, f, sizeof f);
  if (!with_timings) return r;
  OK(s->w, mica_world_state_size(s->w, &r.state_size));
  r.state = malloc(r.state_size);
  OK(s->w, mica_world_save_state(s->w, r.state, r.state_size));
  return r;
}

static void assert_same_readout(const readout* a, const readout* b) {
  assert_int_equal(a->size, b->size);
  assert_memory_equal(a->bytes, b->bytes, a->size);
  assert_int_equal(a->state_size, b->state_size);
  if (a->state) assert_memory_equal(a->state, b->state, a->state_size);
}

static void free_readout(readout* r) {
  free(r->bytes);
  free(r->state);
}

/* Both worlds step `steps` times with the tool at (x0 + dx k, y, z) and read out alike after each
 * step (but for timings). */
static void step_alike(scene* a, scene* b, int steps, double x0, double dx) {
  for (int k = 0; k < steps; ++k) {
    const double p[3] = {x0 + dx * k, 0.1 + 0.02 - 0.003, 0.05}, q[4] = {1, 0, 0, 0};
    OK(a->w, mica_tool_set_pose(a->w, a->box.tool, p, q));
    OK(b->w, mica_tool_set_pose(b->w, b->box.tool, p, q));
    OK(a->w, mica_step(a->w, 0.01));
    OK(b->w, mica_step(b->w, 0.01));
    readout ra = read_world(a, 0), rb = read_world(b, 0);
    assert_same_readout(&ra, &rb);
    free_readout(&ra);
    free_readout(&rb);
  }
}

static void test_a_failed_step_changes_no_readout(void** state) {
  (void)state;
  for (size_t k = 0; k < sizeof kCases / sizeof kCases[0]; ++k) {
    const solver_case* c = &kCases[k];
    print_message("%s\n", c->name);
    scene failing, twin;
    make_scene(&failing, c);
    make_scene(&twin, c);
    for (int i = 0; i < 10; ++i) {
      OK(failing.w, mica_step(failing.w, 0.01));
      OK(twin.w, mica_step(twin.w, 0.01));
    }
    /* The tool moves 1 mm before the failed step: new gaps, new contacts. */
    const double p[3] = {0.03, 0.1 + 0.02 - 0.003, 0.05}, q[4] = {1, 0, 0, 0};
    OK(failing.w, mica_tool_set_pose(failing.w, failing.box.tool, p, q));
    OK(twin.w, mica_tool_set_pose(twin.w, twin.box.tool, p, q));
    readout before = read_world(&failing, 1);
    set_all_forces(&failing, failing.box.body, 1e308);
    assert_int_equal(mica_step(failing.w, 0.01), MICA_ERR_NUMERICAL);
    /* The message names the body by the id the host holds. */
    char id[32];
    snprintf(id, sizeof id, "body 0x%llx", (unsigned long long)failing.box.body);
    assert_non_null(strstr(mica_world_last_error(failing.w), id));
    set_all_forces(&failing, failing.box.body, 0);
    readout after = read_world(&failing, 1);
    assert_same_readout(&before, &after);
    free_readout(&before);
    free_readout(&after);
    /* And the world goes on as if the step had never been tried. */
    step_alike(&failing, &twin, 3, 0.03, 0);
    mica_world_destroy(failing.w);
    mica_world_destroy(twin.w);
  }
}

static void test_a_restored_state_reads_and_steps_as_the_original(void** state) {
  (void)state;
  for (size_t k = 0; k < sizeof kCases / sizeof kCases[0]; ++k) {
    const solver_case* c = &kCases[k];
    print_message("%s\n", c->name);
    scene original, restored;
    make_scene(&original, c);
    make_scene(&restored, c);
    for (int i = 0; i < 10; ++i) {
      const double p[3] = {0.03, 0.1 + 0.02 - 0.002 - 0.0002 * i, 0.05}, q[4] = {1, 0, 0, 0};
      OK(original.w, mica_tool_set_pose(original.w, original.box.tool, p, q));
      OK(original.w, mica_step(original.w, 0.01));
    }
    readout saved = read_world(&original, 1);
    OK(restored.w, mica_world_restore_state(restored.w, saved.state, saved.state_size));
    readout back = read_world(&restored, 1);
    assert_same_readout(&saved, &back);
    free_readout(&saved);
    free_readout(&back);
    step_alike(&original, &restored, 4, 0.03, 0.001);
    mica_world_destroy(original.w);
    mica_world_destroy(restored.w);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_a_failed_step_changes_no_readout),
      cmocka_unit_test(test_a_restored_state_reads_and_steps_as_the_original),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
