/* SPDX-License-Identifier: Apache-2.0 */
/* A render mesh of about 100k vertices embedded in the nidus (data/nidus/nidus.msh) under a
 * pressing tool: the time to place its vertices and compute its normals after each step
 * (mica_embedding_update, one core), against the time the memory it must read and write takes at
 * this machine's bandwidth, and the time to bind it (mica_embedding_create).
 *
 * The mesh: the nidus's rest surface with each edge cut into `divisions` parts and each triangle
 * into divisions^2 (scenes/fine_surface.h; 9 gives 114k vertices), each vertex then moved along its
 * normal by a random offset in [-0.3, 0.3] mm (fixed seed): about half fall inside the body, half
 * just outside it (projected within the default 1 mm radius). The scene: scenes/press_scene.h on the nidus, a 4 mm sphere pressed 3 mm
 * deep and held, MICA with the factored sweep at tolerance 1e-6, dt = 10 ms.
 *
 * Figures:
 * - update median ms: the median wall-clock time of mica_embedding_update (positions and normals)
 *   called once after each step (the step has just run through the caches, as in a host's frame);
 * - bandwidth ratio: that time over bytes / bandwidth, where bytes is what the update reads and
 *   writes (per vertex its binding, a tet, 3 weights and its index, 32 B, its scratch slot and its
 *   entry in a list of the vertices to finish, 12 B, read, its position and normal, 48 B, written;
 *   per triangle its corners, 8 B read (4 for two triangles that share an edge, summed as a pair;
 *   a triangle summed alone reads 12); per body node its position, 24 B, and per tet its 4 nodes,
 *   16 B, read) and bandwidth is the copy rate measured here (memcpy of 256 MiB, best of 5,
 *   counting read and written bytes as STREAM's copy does);
 * - bind ms: the median wall-clock time of mica_embedding_create over 5 binds.
 * Goals: update <= 1 ms, ratio <= 3, bind < 100 ms.
 *
 * usage: bench_embedding [mesh] [divisions] [steps]; defaults data/nidus/nidus.msh 9 60
 * Run it from the repository root: build/bench/bench_embedding
 */
#define _GNU_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mica/mica.h>

#include "bench_common.h"
#include "cli.h"
#include "fine_surface.h"
#include "press_scene.h"

static const char* const kUsage =
    "usage: bench_embedding [mesh] [divisions] [steps]\n"
    "A fine render mesh (the mesh's surface triangles split into divisions^2, jittered by 0.3 mm)\n"
    "embedded in the nidus under a pressing tool: mica_embedding_update after each step (median ms,\n"
    "and its ratio to the time its bytes take at the measured memory bandwidth), and\n"
    "mica_embedding_create (median ms of 5). Defaults: data/nidus/nidus.msh 9 60.\n"
    "  --help  this text\n"
    "Run it from the repository root: build/bench/bench_embedding\n";

#define CHECK(world, call)                                                                             \
  do {                                                                                                 \
    const mica_status s_ = (call);                                                                     \
    if (s_ < 0) {                                                                                      \
      fprintf(stderr, "%s: %s\n  %s\n", #call, mica_status_string(s_), mica_world_last_error(world)); \
      exit(1);                                                                                         \
    }                                                                                                  \
  } while (0)

static double median(double* v, int n) {
  qsort(v, (size_t)n, sizeof v[0], cmp);
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* Bytes per second of a large memcpy (read + written), the best of 5. */
static double copy_bandwidth(void) {
  const size_t bytes = (size_t)256 << 20;
  char *a = malloc(bytes), *b = malloc(bytes);
  if (!a || !b) {
    fprintf(stderr, "out of memory\n");
    exit(1);
  }
  memset(a, 1, bytes);
  memset(b, 2, bytes);
  double best = HUGE_VAL;
  for (int k = 0; k < 5; ++k) {
    const double t0 = now_ms();
    memcpy(k % 2 ? a : b, k % 2 ? b : a, bytes);
    const double ms = now_ms() - t0;
    best = ms < best ? ms : best;
  }
  const volatile char sink = a[bytes / 2] + b[bytes / 3]; /* keeps the copies */
  (void)sink;
  free(a);
  free(b);
  return 2.0 * (double)bytes / (best * 1e-3);
}

/* Moves each vertex along its rest normal by a random offset in [-amplitude, amplitude]. */
static void jitter(mica_world* world, mica_body_id body, fine_surface* fine, double amplitude) {
  const mica_embedding_def def = mica_embedding_def_default();
  mica_embedding_id e;
  double* normals = malloc(sizeof(double) * 3 * (size_t)fine->vertex_count);
  double* xyz = malloc(sizeof(double) * 3 * (size_t)fine->vertex_count);
  CHECK(world, mica_embedding_create(world, body, &def, fine->xyz, fine->vertex_count, fine->triangles,
                                     fine->triangle_count, &e));
  CHECK(world, mica_embedding_update(world, e, xyz, normals));
  CHECK(world, mica_embedding_destroy(world, e));
  uint64_t state = 88172645463325252ull;
  for (int32_t i = 0; i < fine->vertex_count; ++i) {
    state ^= state << 13, state ^= state >> 7, state ^= state << 17; /* xorshift64 */
    const double offset = amplitude * (2.0 * (double)(state >> 11) / 9007199254740992.0 - 1.0);
    for (int a = 0; a < 3; ++a) fine->xyz[3 * i + a] += offset * normals[3 * i + a];
  }
  free(normals);
  free(xyz);
}

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  const char* path = argc > 1 ? argv[1] : "data/nidus/nidus.msh";
  const int32_t divisions = argc > 2 ? atoi(argv[2]) : 9;
  const int steps = argc > 3 ? atoi(argv[3]) : 60;
  if (divisions < 1 || steps < 1) {
    fputs(kUsage, stderr);
    return 2;
  }
  char host[512];
  machine(host, sizeof host);
  printf("# command: build/bench/bench_embedding %s %d %d\n# machine: %s\n", path, (int)divisions, steps, host);

  const press_scene_def def = press_scene_nidus_touch_def(path, 0.01 * (steps / 2), 0.01 * (steps - steps / 2));
  press_scene s;
  if (press_scene_create(&def, &s) != MICA_OK) {
    fprintf(stderr, "%s\n", s.error);
    return 1;
  }
  fine_surface fine;
  CHECK(s.world, fine_surface_of_body(s.world, s.body, divisions, &fine));
  jitter(s.world, s.body, &fine, 3e-4);
  const int32_t n = fine.vertex_count, t = fine.triangle_count;

  double bind[5], bind_cpu[5];
  mica_embedding_id e = MICA_NULL_ID;
  const mica_embedding_def ed = mica_embedding_def_default();
  for (int k = 0; k < 5; ++k) {
    if (e != MICA_NULL_ID) CHECK(s.world, mica_embedding_destroy(s.world, e));
    const double t0 = now_ms(), c0 = thread_cpu_ms();
    CHECK(s.world, mica_embedding_create(s.world, s.body, &ed, fine.xyz, n, fine.triangles, t, &e));
    bind[k] = now_ms() - t0;
    bind_cpu[k] = thread_cpu_ms() - c0;
  }
  int32_t inside, projected, unbound;
  CHECK(s.world, mica_embedding_get_counts(s.world, e, NULL, &inside, &projected, &unbound));
  printf("mesh: %d vertices, %d triangles on a body of %d nodes, %d tets; %d inside, %d projected, %d unbound\n",
         (int)n, (int)t, (int)s.nodes, (int)s.tets, (int)inside, (int)projected, (int)unbound);

  double* xyz = malloc(sizeof(double) * 3 * (size_t)n);
  double* normals = malloc(sizeof(double) * 3 * (size_t)n);
  double* update = malloc(sizeof(double) * (size_t)s.steps);
  double* update_cpu = malloc(sizeof(double) * (size_t)s.steps);
  memcpy(xyz, fine.xyz, sizeof(double) * 3 * (size_t)n);
  for (int32_t k = 1; k <= s.steps; ++k) {
    CHECK(s.world, press_scene_step(&s, k, NULL, NULL));
    const double t0 = now_ms(), c0 = thread_cpu_ms();
    CHECK(s.world, mica_embedding_update(s.world, e, xyz, normals));
    update[k - 1] = now_ms() - t0;
    update_cpu[k - 1] = thread_cpu_ms() - c0;
  }
  const double bandwidth = copy_bandwidth();
  const double bytes = 92.0 * n + 8.0 * t + 24.0 * s.nodes + 16.0 * s.tets;
  const double update_ms = median(update, s.steps), bind_ms = median(bind, 5);
  const double floor_ms = 1e3 * bytes / bandwidth;
  printf("memory: %.1f MB to move at %.1f GB/s (memcpy, read + written): %.3f ms\n", bytes * 1e-6, bandwidth * 1e-9,
         floor_ms);
  printf("update median ms %.3f\n", update_ms);
  printf("bandwidth ratio %.2f\n", update_ms / floor_ms);
  printf("bind ms %.1f\n", bind_ms);
  /* The thread's CPU time leaves out what other processes took of the core meanwhile. */
  printf("(CPU time of the calling thread: update median ms %.3f, bind median ms %.1f)\n", median(update_cpu, s.steps),
         median(bind_cpu, 5));
  printf("goals: update <= 1 ms, ratio <= 3, bind < 100 ms\n");
  free(xyz);
  free(normals);
  free(update);
  free(update_cpu);
  fine_surface_free(&fine);
  press_scene_destroy(&s);
  return 0;
}
