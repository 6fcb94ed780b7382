/* SPDX-License-Identifier: Apache-2.0 */
/* What one servo cycle costs, and how steady the 1 kHz period is, while the simulation thread
 * steps a large scene as fast as it can (the worst case for the servo thread's core).
 *
 * usage: bench_servo [seconds] [cells-per-side | mesh | idle] [refactor interval]
 *   a number: a cube of cells^3 x 6 tets (default 12: 10368), MICA's Gauss-Seidel sweep at 1e-4;
 *   a mesh (data/nidus/nidus.msh): bench_nidus's scene (scenes/press_scene.h), MICA's factored
 *   sweep at 1e-6, the factor refreshed every `refactor interval` steps on a background thread
 *   (default 4; 0: never), the sphere held by a simulated device 2 mm deep +- 1 mm at 1 Hz;
 *   "idle": nothing steps (the machine's own floor: its timer and scheduler).
 * The servo thread (this one) asks for SCHED_FIFO and says whether it got it.
 */
#define _GNU_SOURCE
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include <mica/mica.h>
#include <mica/mica_device.h>
#include "cli.h"

#include "bench_common.h"
#include "box_scene.h"
#include "press_scene.h"
#include "wall_clock.h"

/* The nidus: 2 mm deep +- 1 mm at 1 Hz below the undeformed top, like bench_nidus. */
static void press_nidus(double t, double p[3], void* user) {
  const press_scene* s = user;
  p[0] = s->center[0];
  p[1] = s->center[1] + s->lowest - (0.002 + 0.001 * sin(2 * M_PI * t));
  p[2] = s->center[2];
}

static void press(double t, double p[3], void* user) {
  (void)user;
  p[0] = 0.003;
  p[1] = 0.019 - 0.008 * (0.5 - 0.5 * cos(t)); /* slowly in and out, up to 8 mm deep */
  p[2] = 0.002;
}

typedef struct {
  mica_world* world;
  atomic_int running;
  long steps;
} sim;

static void* simulate(void* arg) {
  sim* s = arg;
  while (atomic_load(&s->running)) {
    mica_step(s->world, 0.01);
    s->steps++;
  }
  return NULL;
}

static const char kUsage[] =
    "usage: bench_servo [seconds] [cells-per-side | mesh | idle] [refactor interval]\n"
    "What one servo cycle costs, and how steady the 1 kHz period is, while a simulation thread steps a\n"
    "scene as fast as it can.\n"
    "  seconds            how long it runs (default 10)\n"
    "  cells-per-side     a cube of cells^3 x 6 tets (default 12: 10368), MICA's Gauss-Seidel sweep at 1e-4\n"
    "  mesh               a mesh file (data/nidus/nidus.msh): bench_nidus's scene, MICA's factored sweep at\n"
    "                     1e-6, the sphere held by a simulated device 2 mm deep +- 1 mm at 1 Hz\n"
    "  idle               nothing steps: the machine's own floor for the servo loop\n"
    "  refactor interval  with a mesh: refresh the factor every this many steps in the background\n"
    "                     (default 4; 0: never)\n"
    "  --help             this text\n"
    "Run it as: OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 build/bench/bench_servo 60 data/nidus/nidus.msh 4\n";

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  double seconds = 10.0;
  if (argc > 1 && !cli_double(argv[0], "seconds", argv[1], 0.1, 86400, &seconds)) return 2;
  const char* scene_arg = argc > 2 ? argv[2] : "12";
  /* "idle": the default cube built but never stepped: the machine's own floor for the servo loop. */
  const int idle = strcmp(scene_arg, "idle") == 0;
  const int use_mesh = !idle && strspn(scene_arg, "0123456789") != strlen(scene_arg);
  int cells = use_mesh ? 0 : 12, refactor = 4;
  if ((!use_mesh && !idle && !cli_int(argv[0], "cells-per-side", scene_arg, 2, 64, &cells)) ||
      (argc > 3 && !cli_int(argv[0], "refactor interval", argv[3], 0, 1000000, &refactor)))
    return 2;
  mica_world* world = NULL;
  mica_device_def dd = mica_device_def_default();
  dd.backend = MICA_DEVICE_SIMULATED;
  press_scene nidus;
  int32_t tets = 0;
  char what[256];
  if (use_mesh) {
    /* bench_nidus's scene: the 2 mm sphere on the mesh's top, the fast path. */
    press_scene_def def = press_scene_def_default();
    def.cells = 0;
    def.mesh = scene_arg;
    def.size = 0.002;
    def.margin = 0.0005;
    def.solver = MICA_SOLVER_MICA;
    def.sweep = MICA_SWEEP_FACTORED;
    def.tolerance = 1e-6;
    def.max_iterations = 100000;
    def.refactor_interval = refactor;
    if (press_scene_create(&def, &nidus) != MICA_OK) {
      fprintf(stderr, "%s\n", nidus.error);
      return 1;
    }
    world = nidus.world;
    tets = nidus.tets;
    dd.tool = nidus.tool;
    dd.trajectory = press_nidus;
    dd.trajectory_user = &nidus;
    snprintf(what, sizeof what, "%s: MICA factored sweep, tol 1e-6, refactor_interval %d", scene_arg, (int)refactor);
  } else {
    mica_world_def wd = mica_world_def_default();
    wd.gravity[1] = 0;
    wd.solver = MICA_SOLVER_MICA;
    wd.mica_sweep = MICA_SWEEP_GAUSS_SEIDEL; /* the paper's sweep */
    wd.tolerance = 1e-4;
    wd.max_iterations = 500;
    if (mica_world_create(&wd, &world) != MICA_OK) return 1;
    /* The soft block of scenes/box_scene.h, its base fixed, the sphere at the origin. */
    box_scene_def def = box_scene_block_def();
    def.body.youngs_modulus = 1e4;
    def.cells[0] = def.cells[1] = def.cells[2] = cells;
    def.tool_position[1] = 0;
    box_scene scene;
    if (box_scene_create(world, &def, &scene) != MICA_OK) return 1;
    tets = scene.tets;
    dd.tool = scene.tool;
    dd.trajectory = press;
    snprintf(what, sizeof what, idle ? "nothing (idle)" : "a cube of %d tets: MICA Gauss-Seidel sweep, tol 1e-4",
             (int)tets);
  }
  mica_device_id device;
  if (mica_device_create(world, &dd, &device) != MICA_OK) return 1;

  sim s = {world, 1, 0};
  pthread_t thread = 0;
  if (!idle) pthread_create(&thread, NULL, simulate, &s); /* before the servo asks for SCHED_FIFO: not inherited */
  /* A haptic host runs its servo thread at a real-time priority where it may (CAP_SYS_NICE or an
   * rtprio limit); without it, the kernel's fair scheduler. */
  struct sched_param prio = {.sched_priority = 80};
  const int fifo = pthread_setschedparam(pthread_self(), SCHED_FIFO, &prio) == 0;
  /* The servo loop on this thread: absolute 1 ms deadlines. */
  const long cycles = (long)(seconds * 1000);
  double* cost = malloc(sizeof(double) * (size_t)cycles);
  double* period = malloc(sizeof(double) * (size_t)cycles);
  double* late = malloc(sizeof(double) * (size_t)cycles);
  const double start = now_s();
  double deadline = start, last = deadline;
  for (long k = 0; k < cycles; ++k) {
    const double t0 = now_s();
    late[k] = 1e3 * (t0 - (start + 1e-3 * (double)k)); /* ms behind its scheduled start */
    mica_device_poll(world, device, NULL, NULL);
    const double t1 = now_s();
    cost[k] = 1e6 * (t1 - t0);
    period[k] = 1e3 * (t0 - last);
    last = t0;
    deadline += 1e-3;
    const double wait = deadline - now_s();
    if (wait > 0) {
      struct timespec ts = {0, (long)(wait * 1e9)};
      nanosleep(&ts, NULL);
    }
  }
  atomic_store(&s.running, 0);
  if (!idle) pthread_join(thread, NULL);
  long late_half = 0;
  for (long k = 0; k < cycles; ++k) late_half += late[k] > 0.5;
  qsort(late, (size_t)cycles, sizeof(double), cmp);
  for (long k = 0; k < cycles; ++k) period[k] = fabs(period[k] - 1.0);
  qsort(cost, (size_t)cycles, sizeof(double), cmp);
  qsort(period + 1, (size_t)cycles - 1, sizeof(double), cmp);
  const long m = cycles - 1;
  char host[300];
  machine(host, sizeof host);
  printf("# bench_servo: %s\n", host);
  printf("# %.0f s, %ld servo cycles (%s), simulation of %s stepping alongside (%.1f steps/s)\n", seconds, cycles,
         fifo ? "SCHED_FIFO 80" : "SCHED_FIFO refused: the fair scheduler", what, (double)s.steps / seconds);
  printf("# command: OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 build/bench/bench_servo %g %s%s%s\n", seconds, scene_arg,
         use_mesh ? " " : "", use_mesh ? (argc > 3 ? argv[3] : "4") : "");
  printf("poll cost (us):       median %.2f  p99 %.2f  p99.9 %.2f  max %.2f\n", cost[cycles / 2],
         cost[(long)(cycles * 0.99)], cost[(long)(cycles * 0.999)], cost[cycles - 1]);
  printf("period jitter (ms):   median %.3f  p99 %.3f  p99.9 %.3f  max %.3f   (|period - 1 ms|)\n", period[1 + m / 2],
         period[1 + (long)(m * 0.99)], period[1 + (long)(m * 0.999)], period[cycles - 1]);
  printf("late (ms):            median %.3f  p99 %.3f  p99.9 %.3f  max %.3f   (behind the 1 ms schedule); "
         "%ld of %ld cycles late by more than 0.5 ms\n",
         late[cycles / 2], late[(long)(cycles * 0.99)], late[(long)(cycles * 0.999)], late[cycles - 1], late_half,
         cycles);
  free(cost);
  free(period);
  free(late);
  mica_device_destroy(world, device);
  if (use_mesh) press_scene_destroy(&nidus);
  else mica_world_destroy(world);
  return 0;
}
