/* SPDX-License-Identifier: Apache-2.0 */
/* mica_world_def.enqueue_task / finish_task: a world stepping on a host's job system (a small
 * pthread one here, as an engine's would be) moves its bodies and tool bit for bit as the same
 * world on its own workers, whatever the host's worker count, whether the host helps inside
 * finish_task or runs every range inside enqueue_task; the callbacks are called as mica.h says;
 * a def from a header without the fields steps on the world's own workers. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <pthread.h>
#include <cmocka.h>

#include <mica/mica.h>

#include "box_scene.h"
#include "capi_ok.h"

/* ---- A job system: worker threads taking one-item ranges of the enqueued tasks in turn. ---- */

#define MAX_WORKERS 8
#define MAX_TASKS 4

typedef struct task_slot {
  mica_task_fn fn;
  void* context;
  int32_t items, next, done; /* items handed out: [0, next); ranges returned: done */
  int used;
} task_slot;

typedef struct job_system {
  pthread_t workers[MAX_WORKERS];
  int worker_count;
  int help;   /* 1: finish_task runs ranges on the calling thread while it waits */
  int inline_; /* 1: enqueue_task runs every range itself and returns NULL */
  pthread_mutex_t mutex;
  pthread_cond_t changed;
  task_slot slots[MAX_TASKS];
  int stop;
  /* What the library asked for. */
  long enqueued, finished, ranges, ranges_on_workers, largest_item_count, bad_calls;
} job_system;

static task_slot* open_slot(job_system* js) {
  for (int k = 0; k < MAX_TASKS; ++k)
    if (js->slots[k].used && js->slots[k].next < js->slots[k].items) return &js->slots[k];
  return NULL;
}

/* Runs the next range of `t`; called and returns with the mutex held. */
static void run_range(job_system* js, task_slot* t, int on_worker) {
  const int32_t start = t->next++;
  pthread_mutex_unlock(&js->mutex);
  t->fn(start, start + 1, t->context);
  pthread_mutex_lock(&js->mutex);
  t->done += 1;
  js->ranges += 1;
  js->ranges_on_workers += on_worker;
  pthread_cond_broadcast(&js->changed);
}

static void* worker_main(void* arg) {
  job_system* js = arg;
  pthread_mutex_lock(&js->mutex);
  for (;;) {
    task_slot* t = NULL;
    while (!js->stop && !(t = open_slot(js))) pthread_cond_wait(&js->changed, &js->mutex);
    if (!t) break;
    run_range(js, t, 1);
  }
  pthread_mutex_unlock(&js->mutex);
  return NULL;
}

static void* enqueue_task(mica_task_fn task, int32_t item_count, int32_t min_range, void* context, void* user) {
  job_system* js = user;
  if (js->inline_) {
    js->enqueued += 1;
    js->ranges += 1;
    task(0, item_count, context);
    return NULL;
  }
  pthread_mutex_lock(&js->mutex);
  task_slot* t = NULL;
  for (int k = 0; k < MAX_TASKS && !t; ++k)
    if (!js->slots[k].used) t = &js->slots[k];
  if (!t || !task || item_count < 1 || min_range < 1) {
    js->bad_calls += 1;
    pthread_mutex_unlock(&js->mutex);
    task(0, item_count, context);
    return NULL;
  }
  t->fn = task;
  t->context = context;
  t->items = item_count;
  t->next = t->done = 0;
  t->used = 1;
  js->enqueued += 1;
  if (item_count > js->largest_item_count) js->largest_item_count = item_count;
  pthread_cond_broadcast(&js->changed);
  pthread_mutex_unlock(&js->mutex);
  return t;
}

static void finish_task(void* handle, void* user) {
  job_system* js = user;
  task_slot* t = handle;
  pthread_mutex_lock(&js->mutex);
  if (t < js->slots || t >= js->slots + MAX_TASKS || !t->used) js->bad_calls += 1;
  while (t->done < t->items) {
    if (js->help && t->next < t->items)
      run_range(js, t, 0);
    else
      pthread_cond_wait(&js->changed, &js->mutex);
  }
  t->used = 0;
  js->finished += 1;
  pthread_mutex_unlock(&js->mutex);
}

static void job_system_start(job_system* js, int workers, int help, int inline_) {
  memset(js, 0, sizeof *js);
  js->worker_count = workers;
  js->help = help;
  js->inline_ = inline_;
  pthread_mutex_init(&js->mutex, NULL);
  pthread_cond_init(&js->changed, NULL);
  for (int k = 0; k < workers; ++k) assert_int_equal(pthread_create(&js->workers[k], NULL, worker_main, js), 0);
}

static void job_system_stop(job_system* js) {
  pthread_mutex_lock(&js->mutex);
  js->stop = 1;
  pthread_cond_broadcast(&js->changed);
  pthread_mutex_unlock(&js->mutex);
  for (int k = 0; k < js->worker_count; ++k) pthread_join(js->workers[k], NULL);
  pthread_cond_destroy(&js->changed);
  pthread_mutex_destroy(&js->mutex);
}

static void use_job_system(mica_world_def* def, job_system* js, int32_t worker_count) {
  def->enqueue_task = enqueue_task;
  def->finish_task = finish_task;
  def->task_user = js;
  def->task_worker_count = worker_count;
}

/* ---- The scene: a sphere pressed into a soft cube fixed at its base, 20 steps. ---- */

#define STEPS 20
#define MAX_NODES 512

typedef struct run {
  double x[STEPS][3 * MAX_NODES], v[STEPS][3 * MAX_NODES], force[STEPS][3];
  int32_t nodes;
} run;

static void press(const mica_world_def* def, run* out) {
  mica_world* w = NULL;
  OK(NULL, mica_world_create(def, &w));
  box_scene_def sd = box_scene_def_default();
  sd.cells[0] = sd.cells[1] = sd.cells[2] = 6;
  sd.tool_radius = 0.02;
  sd.tool_position[0] = 0.05;
  sd.tool_position[1] = 0.1 + 0.02 + 0.001;
  sd.tool_position[2] = 0.05;
  sd.drag_velocity[2] = 0.05; /* a grasp too: the face x = 0.1 is dragged sideways */
  box_scene s;
  OK(w, box_scene_create(w, &sd, &s));
  const double q[4] = {1, 0, 0, 0};
  double p[3] = {sd.tool_position[0], sd.tool_position[1], sd.tool_position[2]};
  for (int k = 0; k < STEPS; ++k) {
    p[1] -= 0.001;
    OK(w, mica_tool_set_pose(w, s.tool, p, q));
    OK(w, mica_step(w, 0.01));
    OK(w, mica_body_get_positions(w, s.body, out->x[k], MAX_NODES, &out->nodes));
    OK(w, mica_body_get_velocities(w, s.body, out->v[k], MAX_NODES, &out->nodes));
    OK(w, mica_tool_get_force(w, s.tool, out->force[k], NULL, NULL));
  }
  mica_world_destroy(w);
}

static void assert_same_bits(const run* a, const run* b, const char* what) {
  assert_int_equal(a->nodes, b->nodes);
  for (int k = 0; k < STEPS; ++k) {
    const size_t n = sizeof(double) * 3 * (size_t)a->nodes;
    if (memcmp(a->x[k], b->x[k], n) != 0) fail_msg("%s: positions differ at step %d", what, k);
    if (memcmp(a->v[k], b->v[k], n) != 0) fail_msg("%s: velocities differ at step %d", what, k);
    if (memcmp(a->force[k], b->force[k], sizeof a->force[k]) != 0)
      fail_msg("%s: tool force differs at step %d (%.17g against %.17g N)", what, k, a->force[k][1], b->force[k][1]);
  }
}

static run reference, hosted; /* large: not on the stack */

/* `def` on a job system of `workers` threads (help, inline_: as job_system_start) with
 * task_worker_count `count`, compared with `reference`. */
static void press_on_host(mica_world_def def, job_system* js, int workers, int help, int inline_, int32_t count,
                          const char* what) {
  job_system_start(js, workers, help, inline_);
  use_job_system(&def, js, count);
  press(&def, &hosted);
  job_system_stop(js);
  assert_same_bits(&reference, &hosted, what);
}

/* threads = 2 on the world's workers against the host's job system, for each MICA sweep (the
 * factored one's loops: rotations and assembly; Gauss-Seidel adds the colour-ordered sweep). */
static void test_host_steps_match_own_workers(void** state) {
  (void)state;
  const int32_t sweeps[2] = {MICA_SWEEP_FACTORED, MICA_SWEEP_GAUSS_SEIDEL};
  for (int k = 0; k < 2; ++k) {
    mica_world_def def = mica_world_def_default();
    def.mica_sweep = sweeps[k];
    def.tolerance = 1e-6;
    def.threads = 2;
    press(&def, &reference);
    assert_true(reference.force[STEPS - 1][1] > 0.1); /* the sphere presses the cube */

    def.threads = 1;
    /* One worker and the stepping thread, as threads = 2. */
    job_system js;
    press_on_host(def, &js, 1, 0, 0, 2, "1 host worker, task_worker_count 2");
    /* The callbacks were called, each task waited for, every range on the worker. */
    assert_true(js.enqueued > STEPS);
    assert_int_equal(js.finished, js.enqueued);
    assert_int_equal(js.largest_item_count, 1); /* at most task_worker_count - 1 items */
    assert_int_equal(js.ranges_on_workers, js.ranges);
    assert_int_equal(js.bad_calls, 0);

    /* Three workers, four threads in all, the caller helping in finish_task: the same bits
     * (the work is cut the same whatever the thread count). */
    press_on_host(def, &js, 3, 1, 0, 4, "3 host workers helped by finish_task, task_worker_count 4");
    assert_int_equal(js.finished, js.enqueued);
    assert_int_equal(js.largest_item_count, 3);
    assert_int_equal(js.bad_calls, 0);

    /* A host that runs the task inside enqueue_task and returns NULL: finish_task is not called. */
    press_on_host(def, &js, 0, 0, 1, 2, "the task run inside enqueue_task");
    assert_true(js.enqueued > STEPS);
    assert_int_equal(js.finished, 0);
  }
}

/* task_worker_count = 1: the serial code (as threads = 1), the callbacks never called. */
static void test_one_worker_never_calls_the_host(void** state) {
  (void)state;
  mica_world_def def = mica_world_def_default();
  def.tolerance = 1e-6;
  press(&def, &reference);
  job_system js;
  press_on_host(def, &js, 1, 0, 0, 1, "task_worker_count 1");
  assert_int_equal(js.enqueued, 0);
  assert_int_equal(js.finished, 0);
}

/* The defaults: no job system (tests/capi/test_bad_input_world.c refuses half of one). */
static void test_defaults_have_no_job_system(void** state) {
  (void)state;
  const mica_world_def def = mica_world_def_default();
  assert_null(def.enqueue_task);
  assert_null(def.finish_task);
  assert_null(def.task_user);
  assert_int_equal(def.task_worker_count, 0);
}

/* A def from a 0.6 header ends before task_worker_count: what lies beyond (bytes no pointer
 * should be called through) is never read, and threads = 2 runs on the world's own workers. */
static void test_older_def_uses_own_workers(void** state) {
  (void)state;
  union {
    mica_world_def d;
    unsigned char bytes[sizeof(mica_world_def)];
  } old;
  memset(&old, 0xcd, sizeof old);
  assert_int_equal(mica_world_def_init(&old.d, (uint32_t)offsetof(mica_world_def, task_worker_count), 600), MICA_OK);
  old.d.threads = 2;
  old.d.tolerance = 1e-6;
  press(&old.d, &hosted);
  mica_world_def def = mica_world_def_default();
  def.threads = 2;
  def.tolerance = 1e-6;
  press(&def, &reference);
  assert_same_bits(&reference, &hosted, "a 0.6 def");
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_host_steps_match_own_workers),
      cmocka_unit_test(test_one_worker_never_calls_the_host),
      cmocka_unit_test(test_defaults_have_no_job_system),
      cmocka_unit_test(test_older_def_uses_own_workers),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
