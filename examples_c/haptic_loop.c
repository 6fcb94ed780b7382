/* SPDX-License-Identifier: Apache-2.0 */
/* A haptic loop as an engine would run it: a simulation thread stepping at 60 Hz and a servo
 * thread polling the device at 1 kHz, concurrently. The device is the Geomagic Touch when
 * OpenHaptics' libHD is present (MICA_HD_LIBRARY), else a simulated stylus that presses into
 * a soft block for a second and lets go. Prints the rates and forces and writes
 * haptic_loop.csv (servo samples: time, raw and filtered force) for the paper's Figure 1 b/c.
 *
 * usage: haptic_loop [output-folder] [seconds] [--record FILE]
 */
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <mica/mica.h>

#include "box_scene.h"
#include "wall_clock.h"
#include "cli.h"
#include <mica/mica_device.h>

#define SERVO_HZ 1000
#define MAX_SAMPLES 200000

typedef struct {
  mica_world* world;
  mica_device_id device;
  atomic_int running;
  double seconds;
  /* servo samples, written by the servo thread only */
  int samples;
  double t[MAX_SAMPLES], raw[MAX_SAMPLES], filtered[MAX_SAMPLES];
  long failures;
} loop;

/* The stylus goes 1.5 cm down into the block over 0.5 s, holds 0.5 s, and lifts off. */
static void press(double t, double p[3], void* user) {
  (void)user;
  const double depth = t < 0.5 ? 0.015 * t / 0.5 : t < 1.0 ? 0.015 : t < 1.5 ? 0.015 * (1.5 - t) / 0.5 : 0;
  p[0] = 0.002;
  p[1] = 0.021 - depth; /* the sphere (radius 2 cm) touches the top face y = 0 at p_y = 0.02 */
  p[2] = 0.001;
}

static void* servo_thread(void* arg) {
  loop* L = arg;
  const double start = now_s();
  double deadline = start;
  while (atomic_load(&L->running)) {
    double force[3];
    if (mica_device_poll(L->world, L->device, NULL, force) < 0) L->failures++;
    mica_device_stats st = {.struct_size = sizeof st};
    mica_device_get_stats(L->world, L->device, &st);
    if (L->samples < MAX_SAMPLES) {
      L->t[L->samples] = now_s() - start;
      L->raw[L->samples] = st.last_raw_force[1];
      L->filtered[L->samples] = force[1];
      L->samples++;
    }
    deadline += 1.0 / SERVO_HZ;
    sleep_until(deadline);
  }
  return NULL;
}

#define CHECK(call)                                                                                   \
  do {                                                                                                \
    mica_status s_ = (call);                                                                          \
    if (s_ < 0) {                                                                                     \
      fprintf(stderr, "%s: %s\n  %s\n", #call, mica_status_string(s_), mica_world_last_error(world)); \
      return 1;                                                                                       \
    }                                                                                                 \
  } while (0)

static const char kUsage[] =
    "usage: haptic_loop [output-folder] [seconds] [--record FILE]\n"
    "A 60 Hz simulation thread and a 1 kHz servo thread: the Geomagic Touch when OpenHaptics' libHD\n"
    "is found (MICA_HD_LIBRARY), else a simulated stylus pressing into a soft block. Prints the rates\n"
    "and forces and writes haptic_loop.csv (time, raw and rendered force) into the output folder.\n"
    "  output-folder  where the CSV goes (made if missing; default .)\n"
    "  seconds        how long the loop runs (default 2)\n"
    "  --record FILE  record the session (mica_world_record_start; its folder is made if missing);\n"
    "                 mica_replay replays it\n"
    "  --help         this text\n";

int main(int argc, char** argv) {
  static const char* const options[] = {"--record FILE", NULL};
  const int cli = cli_check(argc, argv, kUsage, options);
  if (cli >= 0) return cli;
  const char* positional[2] = {".", "2"};
  const char* record = NULL;
  for (int i = 1, n = 0; i < argc; ++i) {
    if (strcmp(argv[i], "--record") == 0)
      record = argv[++i]; /* cli_check saw the value */
    else if (n < 2)
      positional[n++] = argv[i];
  }
  const char* out_dir = positional[0];
  static loop L;
  if (!cli_double(argv[0], "seconds", positional[1], 0.01, 86400, &L.seconds)) return 2;
  /* The folders first: the session is not run to find out at its end that they are missing. */
  if (!cli_make_folder(argv[0], out_dir) || (record && !cli_make_parent(argv[0], record))) return 1;
  mica_world* world = NULL;
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = 0;
  wd.solver = MICA_SOLVER_MICA;
  wd.tolerance = 1e-5;
  wd.max_iterations = 2000;
  if (mica_world_create(&wd, &world) != MICA_OK) {
    fprintf(stderr, "%s\n", mica_world_last_error(NULL));
    return 1;
  }
  if (record) CHECK(mica_world_record_start(world, record));
  /* The soft block (scenes/box_scene.h): 10 cm wide, its top face at y = 0, fixed at its bottom
   * face, a 2 cm sphere above it. */
  box_scene_def def = box_scene_block_def();
  def.body.youngs_modulus = 8e3;
  def.body.poisson_ratio = 0.4;
  def.body.rayleigh_alpha = 2;
  box_scene scene;
  CHECK(box_scene_create(world, &def, &scene));
  const mica_tool_id tool = scene.tool;

  /* The Touch if OpenHaptics is there, else the simulated stylus. */
  mica_device_def dd = mica_device_def_default();
  dd.tool = tool;
  dd.backend = MICA_DEVICE_TOUCH;
  if (mica_device_create(world, &dd, &L.device) != MICA_OK) {
    printf("no Touch (%s): using the simulated stylus\n", mica_world_last_error(world));
    dd.backend = MICA_DEVICE_SIMULATED;
    dd.trajectory = press;
    CHECK(mica_device_create(world, &dd, &L.device));
  }
  mica_device_info info = {.struct_size = sizeof info};
  CHECK(mica_device_get_info(world, L.device, &info));
  printf("device: %s, max force %.2f N\n", info.name, info.max_force);

  L.world = world;
  atomic_store(&L.running, 1);
  pthread_t servo;
  pthread_create(&servo, NULL, servo_thread, &L);
  /* The simulation thread: 60 Hz in real time. */
  const double start = now_s();
  int steps = 0;
  double deadline = start, worst_step_ms = 0;
  while (now_s() - start < L.seconds) {
    const double t0 = now_s();
    CHECK(mica_step(world, 1.0 / 60.0));
    const double ms = 1e3 * (now_s() - t0);
    if (ms > worst_step_ms) worst_step_ms = ms;
    ++steps;
    if (steps % 15 == 0) {
      double f[3];
      mica_tool_get_force(world, tool, f, NULL, NULL);
      printf("t %.2f s  tool force %.3f N\n", now_s() - start, f[1]);
    }
    deadline += 1.0 / 60.0;
    sleep_until(deadline);
  }
  atomic_store(&L.running, 0);
  pthread_join(servo, NULL);
  if (record) {
    CHECK(mica_world_record_stop(world));
    printf("recorded %d steps into %s (mica_replay replays them)\n", steps, record);
  }
  const double elapsed = now_s() - start;
  mica_device_stats st = {.struct_size = sizeof st};
  CHECK(mica_device_get_stats(world, L.device, &st));
  printf("simulation %.1f Hz (worst step %.1f ms), servo %.0f Hz, %ld device failures, %lld limited polls\n",
         steps / elapsed, worst_step_ms, L.samples / elapsed, L.failures, (long long)st.clamped);

  char path[1024];
  snprintf(path, sizeof path, "%s/haptic_loop.csv", out_dir);
  FILE* csv = fopen(path, "w");
  if (!csv) {
    fprintf(stderr, "cannot write %s\n", path);
    return 1;
  }
  fprintf(csv, "t_s,raw_force_y_N,filtered_force_y_N\n");
  for (int k = 0; k < L.samples; ++k) fprintf(csv, "%.6f,%.9g,%.9g\n", L.t[k], L.raw[k], L.filtered[k]);
  fclose(csv);
  printf("servo samples written to %s\n", path);
  CHECK(mica_device_destroy(world, L.device));
  mica_world_destroy(world);
  return 0;
}
