/* SPDX-License-Identifier: Apache-2.0 */
/* What one servo cycle costs, and how steady the 1 kHz period is, while the simulation thread
 * steps a large scene as fast as it can (the worst case for the servo thread's core).
 *
 * usage: bench_servo [seconds] [cells-per-side]   (default 10 s, 12^3 x 6 = 10368 tets)
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
#include "wall_clock.h"

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
    "usage: bench_servo [seconds] [cells-per-side]\n"
    "What one servo cycle costs, and how steady the 1 kHz period is, while a simulation thread steps a\n"
    "cube of cells^3 x 6 tets as fast as it can (MICA, Gauss-Seidel sweep, tolerance 1e-4).\n"
    "  seconds         how long it runs (default 10)\n"
    "  cells-per-side  the cube's mesh (default 12: 10368 tets)\n"
    "  --help          this text\n";

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  const double seconds = argc > 1 ? atof(argv[1]) : 10.0;
  const int32_t cells = argc > 2 ? atoi(argv[2]) : 12;
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = 0;
  wd.solver = MICA_SOLVER_MICA;
  wd.mica_sweep = MICA_SWEEP_GAUSS_SEIDEL; /* the paper's sweep */
  wd.tolerance = 1e-4;
  wd.max_iterations = 500;
  mica_world* world;
  if (mica_world_create(&wd, &world) != MICA_OK) return 1;
  /* The soft block of scenes/box_scene.h, its base fixed, the sphere at the origin. */
  box_scene_def def = box_scene_block_def();
  def.body.youngs_modulus = 1e4;
  def.cells[0] = def.cells[1] = def.cells[2] = cells;
  def.tool_position[1] = 0;
  box_scene scene;
  if (box_scene_create(world, &def, &scene) != MICA_OK) return 1;
  const int32_t tets = scene.tets;
  const mica_tool_id tool = scene.tool;
  mica_device_def dd = mica_device_def_default();
  dd.backend = MICA_DEVICE_SIMULATED;
  dd.trajectory = press;
  dd.tool = tool;
  mica_device_id device;
  if (mica_device_create(world, &dd, &device) != MICA_OK) return 1;

  sim s = {world, 1, 0};
  pthread_t thread;
  pthread_create(&thread, NULL, simulate, &s);
  /* The servo loop on this thread: absolute 1 ms deadlines. */
  const long cycles = (long)(seconds * 1000);
  double* cost = malloc(sizeof(double) * (size_t)cycles);
  double* period = malloc(sizeof(double) * (size_t)cycles);
  double deadline = now_s(), last = deadline;
  for (long k = 0; k < cycles; ++k) {
    const double t0 = now_s();
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
  pthread_join(thread, NULL);
  for (long k = 0; k < cycles; ++k) period[k] = fabs(period[k] - 1.0);
  qsort(cost, (size_t)cycles, sizeof(double), cmp);
  qsort(period + 1, (size_t)cycles - 1, sizeof(double), cmp);
  const long m = cycles - 1;
  printf("# bench_servo: %.0f s, %ld servo cycles, simulation of %d tets stepping alongside (%.1f steps/s)\n",
         seconds, cycles, tets, (double)s.steps / seconds);
  printf("# command: build/bench/bench_servo %g %d\n", seconds, cells);
  printf("poll cost (us):       median %.2f  p99 %.2f  p99.9 %.2f  max %.2f\n", cost[cycles / 2],
         cost[(long)(cycles * 0.99)], cost[(long)(cycles * 0.999)], cost[cycles - 1]);
  printf("period jitter (ms):   median %.3f  p99 %.3f  p99.9 %.3f  max %.3f   (|period - 1 ms|)\n", period[1 + m / 2],
         period[1 + (long)(m * 0.99)], period[1 + (long)(m * 0.999)], period[cycles - 1]);
  free(cost);
  free(period);
  mica_device_destroy(world, device);
  mica_world_destroy(world);
  return 0;
}
