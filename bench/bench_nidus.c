/* SPDX-License-Identifier: Apache-2.0 */
/* The nidus-scale scene of Arikatla et al. 2016: a lesion-like blob of about 9.7k tets and
 * 2.7k nodes (8.2k DOF, data/nidus/nidus.msh, made by data/nidus/make_nidus.py), touched by a
 * forceps tip, timed per step on one core. The paper ran this scale at about 100 ms per step
 * on a 2016 core; the target here is 5 ms.
 *
 * Scene: the blob (E = 1e4 Pa, nu = 0.4, rho = 1000, Rayleigh alpha = 2 1/s, co-rotational,
 * consistent mass, no gravity: the tissue around a lesion carries it) held by its lowest fifth
 * (fixed nodes, as if attached to the surrounding tissue). A 2 mm sphere (the forceps tip)
 * starts 0.5 mm above the top of the blob over its centre, presses 2 mm into it at 10 mm/s,
 * then moves between 1 and 3 mm deep once a second (every timed step has a moving tool in
 * contact). MICA at tolerance 1e-6 (cap 100000), dt = 10 ms. The first `warm-up` steps
 * (approach and first contact) are not timed; then `steps` steps are, with mica_step's
 * wall-clock time taken around the call.
 *
 * Memory: VmRSS (/proc/self/status) before and after mica_body_create_from_file, and after the
 * first step (when the solver's buffers exist), divided by the tets; and what the world holds
 * after that step, VmRSS once glibc's malloc_trim has returned the heap's free pages (what
 * the allocator keeps of the analysis's and factorization's temporaries for reuse is not the
 * world's). The baseline is taken after a trim too.
 *
 * Per step (mica_world_stats): CG iterations, velocity solves (the factored sweep's rounds) and
 * factorizations made or started; the timed steps by kind (one solve, two or more, with a
 * factorization) with their mean ms, which shows where the p95 comes from.
 *
 * usage: bench_nidus [mesh] [tolerance] [steps] [warm-up] [E] [dt] [gauss-seidel steps] [refactor interval] [linear]
 *          defaults: data/nidus/nidus.msh 1e-6 200 40 1e4 0.01 30 6; runs MICA with the factored
 *          sweep (the first step's factor), again with the factor refreshed in the background every
 *          `refactor interval` steps (0 skips it), then with the paper's Gauss-Seidel sweep (0 steps
 *          skip it), and prints each and their ratios; `linear` makes the body linear (constant
 *          stiffness: the factor is exact and never changes; the interval is then moot)
 *        bench_nidus --defaults [mesh] [steps]
 *          the press with the default world as mica_world_def_default() gives it (tolerance 1e-8,
 *          cap 200; gravity off), then with solver DIRECT, then with MICA's Gauss-Seidel sweep (the
 *          0.4 defaults), `steps` timed steps each (default 110): total seconds and steps not converged
 *        bench_nidus --neo-hookean [mesh] [steps] [refactor interval]
 *          the press with a co-rotational body, then with a neo-Hookean one (MICA_MODEL_NEO_HOOKEAN),
 *          in this one process: MICA's factored sweep at tolerance 1e-6, the factor refreshed in the
 *          background every `refactor interval` steps (default 6), `steps` timed steps each (default
 *          200); each one's figures, then the two medians and their ratio (goal: at most 2x)
 *        bench_nidus --scaling <out.csv> [max-tets] [factored|gauss-seidel]
 *          time per step against tets on box grids (MICA's factored sweep unless told otherwise): a 0.1 m cube of n^3 cubes x 6 tets
 *          (E = 2e4 Pa, alpha = 2, gravity, base fixed), a 2 cm sphere 6 mm deep +- 3 mm at
 *          1 Hz, MICA tol 1e-6; 9 warm-up steps, then 20 timed (10 above 40k tets); 1k to 100k
 *          tets, with the memory per tet of each box.
 * Run it with CHOLMOD's BLAS and OpenMP kept to one thread (the step runs on the calling thread;
 * the refreshed variant adds one background thread, so leave it a second core; pin the scaling
 * curve to one):
 *   OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 build/bench/bench_nidus
 *   OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 taskset -c 1 build/bench/bench_nidus --scaling out/scaling.csv
 */
#define _GNU_SOURCE
#include <malloc.h>
#include <math.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <mica/mica.h>

#include "bench_common.h"
#include "box_scene.h"
#include "cli.h"
#include "node_selection.h"
#include "press_scene.h"

static double quantile(double* v, int n, double q) {
  qsort(v, (size_t)n, sizeof v[0], cmp);
  int k = (int)ceil(q * n) - 1;
  return v[k < 0 ? 0 : k >= n ? n - 1 : k];
}

static long status_kb(const char* key) {
  FILE* f = fopen("/proc/self/status", "r");
  if (!f) return -1;
  char line[256];
  long v = -1;
  const size_t n = strlen(key);
  while (fgets(line, sizeof line, f))
    if (strncmp(line, key, n) == 0) {
      v = strtol(line + n, NULL, 10);
      break;
    }
  fclose(f);
  return v;
}


#define CHECK(call)                                                                                   \
  do {                                                                                                \
    const mica_status s_ = (call);                                                                    \
    if (s_ < 0) {                                                                                     \
      fprintf(stderr, "%s: %s\n  %s\n", #call, mica_status_string(s_), mica_world_last_error(world)); \
      return 1;                                                                                       \
    }                                                                                                 \
  } while (0)

typedef struct {
  double median, p95, max, mean, cpu_median, iterations, solves, mem_create_b_per_tet, mem_step_b_per_tet,
      mem_held_b_per_tet, force;
  double reversals; /* fraction of contact nodes' velocity changes that reverse from step to step */
  double stage_ms[MICA_STAGE_COUNT]; /* mean wall-clock ms per timed step in each stage */
  int32_t nodes, tets, capped, contacts;
  int32_t factorizations; /* made or started in the background, over the timed steps */
  /* Timed steps by kind: [0] one solve, [1] two or more, [2] with a factorization made or started. */
  int32_t kind_steps[3];
  double kind_ms[3]; /* their mean wall-clock ms */
} figures;

/* Steps a world with a sphere pressing from `y0` down by `depth` at `speed`, then moving up
 * and down by `wobble` around there once a second (so every timed step has a moving tool in
 * contact, as under a hand); times the steps after the warm-up. Chatter (the contact issue's
 * measure, read outside the timed call): over the nodes within
 * `reach` of the tool's centre, the fraction of steps whose velocity change dv_k = v_k - v_k-1
 * points against the last one (dv_k . dv_k-1 < 0). The contact issue measured 73 % on this scene
 * in 0.4 (21 % on a cube). */
static int press(mica_world* world, mica_body_id body, mica_tool_id tool, const double c[3], double y0, double depth,
                 double speed, double wobble, double reach, double dt, int warmup, int steps, figures* out) {
  double* ms = malloc(sizeof(double) * (size_t)steps);
  double* cpu = malloc(sizeof(double) * (size_t)steps);
  const size_t n3 = 3 * (size_t)out->nodes;
  double *x = malloc(sizeof(double) * n3), *v = malloc(sizeof(double) * n3), *v_last = calloc(n3, sizeof(double)),
         *dv_last = calloc(n3, sizeof(double));
  long iterations = 0, solves = 0, changes = 0, reversals = 0;
  out->capped = 0;
  out->factorizations = 0;
  for (int k = 0; k < warmup + steps; ++k) {
    const double t = (k + 1) * dt, t_in = depth / speed;
    const double travel = t < t_in ? speed * t : depth + wobble * sin(2 * M_PI * (t - t_in));
    const double p[3] = {c[0], y0 - travel, c[2]}, q[4] = {1, 0, 0, 0};
    CHECK(mica_tool_set_pose(world, tool, p, q));
    const double t0 = now_ms(), c0 = thread_cpu_ms();
    const mica_status s = mica_step(world, dt);
    const double elapsed = now_ms() - t0, cpu_elapsed = thread_cpu_ms() - c0;
    CHECK(s);
    CHECK(mica_body_get_positions(world, body, x, out->nodes, NULL));
    CHECK(mica_body_get_velocities(world, body, v, out->nodes, NULL));
    for (int32_t i = 0; i < out->nodes; ++i) {
      double* dv = dv_last + 3 * i;
      const double d[3] = {v[3 * i] - v_last[3 * i], v[3 * i + 1] - v_last[3 * i + 1], v[3 * i + 2] - v_last[3 * i + 2]};
      const double r[3] = {x[3 * i] - p[0], x[3 * i + 1] - p[1], x[3 * i + 2] - p[2]};
      if (k >= warmup && r[0] * r[0] + r[1] * r[1] + r[2] * r[2] < reach * reach) {
        const double dot = d[0] * dv[0] + d[1] * dv[1] + d[2] * dv[2];
        changes += dot != 0;
        reversals += dot < 0;
      }
      for (int a = 0; a < 3; ++a) dv[a] = d[a];
    }
    memcpy(v_last, v, sizeof(double) * n3);
    if (k < warmup) continue;
    mica_world_stats st;
    memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    CHECK(mica_world_get_stats(world, &st));
    ms[k - warmup] = elapsed;
    cpu[k - warmup] = cpu_elapsed;
    for (int g = 0; g < MICA_STAGE_COUNT; ++g) out->stage_ms[g] += st.stages[g].ms_last_step / steps;
    iterations += st.solver_iterations;
    solves += st.solves;
    out->factorizations += st.factorizations;
    const int kind = st.factorizations > 0 ? 2 : st.solves > 1 ? 1 : 0;
    out->kind_steps[kind] += 1;
    out->kind_ms[kind] += elapsed;
    if (!st.converged) ++out->capped;
  }
  double f[3];
  CHECK(mica_tool_get_force(world, tool, f, NULL, &out->contacts));
  out->force = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  double sum = 0;
  for (int k = 0; k < steps; ++k) sum += ms[k];
  out->mean = sum / steps;
  out->median = quantile(ms, steps, 0.5);
  out->p95 = quantile(ms, steps, 0.95);
  out->max = quantile(ms, steps, 1.0);
  out->cpu_median = quantile(cpu, steps, 0.5);
  free(cpu);
  out->iterations = (double)iterations / steps;
  out->solves = (double)solves / steps;
  for (int kind = 0; kind < 3; ++kind)
    if (out->kind_steps[kind]) out->kind_ms[kind] /= out->kind_steps[kind];
  out->reversals = changes ? (double)reversals / (double)changes : 0;
  free(ms);
  free(x);
  free(v);
  free(v_last);
  free(dv_last);
  return 0;
}

static const char* sweep_name(int32_t sweep) { return sweep == MICA_SWEEP_FACTORED ? "factored" : "gauss-seidel"; }

/* The solver of a world def in words ("MICA (factored sweep, refactor_interval 0)"). */
static void solver_text(const mica_world_def* wd, char* text, size_t size) {
  if (wd->solver == MICA_SOLVER_MICA)
    snprintf(text, size, "MICA (%s sweep, refactor_interval %d)", sweep_name(wd->mica_sweep), (int)wd->refactor_interval);
  else
    snprintf(text, size, "%s", wd->solver == MICA_SOLVER_DIRECT ? "DIRECT" : "PCG");
}

/* The benchmark's world: MICA with `sweep` at tolerance `tol` (cap 100000), no gravity (the
 * lesion is carried by the tissue around it). */
static mica_world_def bench_world(double tol, int32_t sweep, int32_t refactor) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = 0;
  wd.solver = MICA_SOLVER_MICA;
  wd.tolerance = tol;
  wd.max_iterations = 100000;
  wd.mica_sweep = sweep;
  wd.refactor_interval = refactor;
  return wd;
}

static int nidus(const char* path, const mica_world_def* wd, int steps, int warmup, double E, double dt, int32_t model,
                 figures* result) {
  mica_world* world = NULL;
  if (mica_world_create(wd, &world) != MICA_OK) {
    fprintf(stderr, "%s\n", mica_world_last_error(NULL));
    return 1;
  }
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = E;
  bd.poisson_ratio = 0.4;
  bd.density = 1000;
  bd.rayleigh_alpha = 2;
  bd.model = model;
  figures fig;
  memset(&fig, 0, sizeof fig);
  malloc_trim(0);
  const long rss0 = status_kb("VmRSS:");
  mica_body_id body;
  CHECK(mica_body_create_from_file(world, &bd, path, &body));
  const long rss1 = status_kb("VmRSS:");
  CHECK(mica_body_get_counts(world, body, &fig.nodes, &fig.tets, NULL));
  /* The top of the blob over its centre (scenes/press_scene.h): c is its centroid lifted onto the
   * surface, lo and hi its bounds. */
  double lo[3], hi[3], c[3];
  CHECK(press_scene_top(world, body, lo, hi, c));
  /* Held by its lowest fifth. */
  const double cut[3] = {0, lo[1] + 0.2 * (hi[1] - lo[1]), 0}, up[3] = {0, 1, 0};
  int32_t n = 0;
  mica_lpc_id base;
  CHECK(scene_fix_plane(world, body, cut, up, 0, &n, &base));
  const double R = 0.002, y0 = c[1] + R + 0.0005;
  mica_tool_def td = mica_tool_def_default();
  td.radius = R;
  td.margin = 0.0005;
  td.position[0] = c[0];
  td.position[1] = y0;
  td.position[2] = c[2];
  mica_tool_id tool;
  CHECK(mica_tool_create(world, &td, &tool));
  CHECK(mica_step(world, dt) < 0 ? -1 : MICA_OK); /* the first step allocates the solver's buffers */
  const long rss2 = status_kb("VmRSS:");
  malloc_trim(0);
  const long held = status_kb("VmRSS:");
  if (press(world, body, tool, c, y0, 0.0025, 0.01, 0.001, R + td.margin, dt, warmup - 1, steps, &fig)) return 1;
  fig.mem_create_b_per_tet = 1024.0 * (double)(rss1 - rss0) / fig.tets;
  fig.mem_step_b_per_tet = 1024.0 * (double)(rss2 - rss0) / fig.tets;
  fig.mem_held_b_per_tet = 1024.0 * (double)(held - rss0) / fig.tets;
  char m[300];
  machine(m, sizeof m);
  const long threads = status_kb("Threads:");
  printf("# bench_nidus: %s\n", m);
  printf("# mesh %s: %d nodes (%d DOF), %d tets, %.1f x %.1f x %.1f mm; held by %d nodes (lowest fifth)\n", path,
         fig.nodes, 3 * fig.nodes, fig.tets, 1e3 * (hi[0] - lo[0]), 1e3 * (hi[1] - lo[1]), 1e3 * (hi[2] - lo[2]), n);
  char solver[96];
  solver_text(wd, solver, sizeof solver);
  printf("# E = %.3g Pa, nu = 0.4, rho = 1000, alpha = 2; forceps tip: sphere R = %.1f mm, 2 mm deep +- 1 mm at 1 Hz; "
"%s tol %.0e (cap %d), dt = %g ms; %s body; %d warm-up steps, %d timed; %ld thread(s) in the process\n",
         E, 1e3 * R, solver, wd->tolerance, (int)wd->max_iterations, 1e3 * dt,
         model == MICA_MODEL_LINEAR ? "linear" : model == MICA_MODEL_NEO_HOOKEAN ? "neo-Hookean" : "co-rotational", warmup,
         steps, threads);
  printf("total s (timed steps) %.2f\n", 1e-3 * fig.mean * steps);
  printf("median ms/step        %.3f\n", fig.median);
  printf("p95 ms/step           %.3f\n", fig.p95);
  printf("max ms/step           %.3f\n", fig.max);
  printf("mean ms/step          %.3f\n", fig.mean);
  printf("median CPU ms/step    %.3f (the stepping thread's CPU time: less polluted by other load)\n", fig.cpu_median);
  printf("iterations/step       %.1f (mean over timed steps; %d stopped at the cap)\n", fig.iterations, fig.capped);
  printf("solves/step           %.2f (velocity solves: the factored sweep's rounds, each solving every body)\n",
         fig.solves);
  printf("factorizations        %d in the %d timed steps (made, or started in the background)\n", fig.factorizations,
         steps);
  printf("steps by kind         one solve: %d, mean %.2f ms; two or more solves: %d, mean %.2f ms; with a "
         "factorization: %d, mean %.2f ms\n",
         fig.kind_steps[0], fig.kind_ms[0], fig.kind_steps[1], fig.kind_ms[1], fig.kind_steps[2], fig.kind_ms[2]);
  printf("tool force            %.4f N, %d contacts at the end\n", fig.force, fig.contacts);
  /* Where a step's time goes (the step's own stage timers; the re-linearisation's check counts in rotations). */
  static const char* stage_names[MICA_STAGE_COUNT] = {"loads", "rotations", "elements", "damping", "constraints",
                                                      "solve", "integrate", "collide", "forces"};
  printf("mean ms/step by stage");
  for (int g = 0; g < MICA_STAGE_COUNT; ++g)
    if (fig.stage_ms[g] >= 0.0005) printf(" %s %.3f", stage_names[g], fig.stage_ms[g]);
  printf("\n");
  printf("velocity reversals    %.1f %% of the contact nodes' velocity changes (issue: at most 25 %%; 0.4: 73 %%)\n",
         100 * fig.reversals);
  printf("memory, body creation %.0f B/tet (VmRSS %ld -> %ld kB)\n", fig.mem_create_b_per_tet, rss0, rss1);
  printf("memory, after 1 step  %.0f B/tet (VmRSS %ld kB); held %.0f B/tet (VmRSS %ld kB after malloc_trim)\n",
         fig.mem_step_b_per_tet, rss2, fig.mem_held_b_per_tet, held);
  mica_world_destroy(world);
  *result = fig;
  return 0;
}

static int scaling(const char* csv_path, int max_tets, int32_t sweep) {
  FILE* csv = fopen(csv_path, "w");
  if (!csv) {
    fprintf(stderr, "cannot write %s\n", csv_path);
    return 1;
  }
  char m[300];
  machine(m, sizeof m);
  fprintf(csv, "# bench_nidus --scaling: %s; MICA %s sweep\n", m, sweep_name(sweep));
  fprintf(csv, "cells,nodes,tets,ms_median,ms_p95,iterations,ms_per_iteration,mem_B_per_tet,force_N,ms_rotations,"
               "ms_elements,ms_solve,mem_held_B_per_tet\n");
  printf("# bench_nidus --scaling: %s\n", m);
  printf("# command: OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 taskset -c 1 build/bench/bench_nidus --scaling %s %d %s\n", csv_path, max_tets,
         sweep_name(sweep));
  /* The last three columns: mean ms per step of the stages rotations, elements and solve. */
  printf("%6s %8s %8s %10s %10s %10s %12s %10s %9s %9s %9s %10s\n", "cells", "nodes", "tets", "median ms", "p95 ms",
         "iters", "ms/iter", "B/tet", "rot ms", "elem ms", "solve ms", "held B/tet");
  const int sizes[] = {6, 8, 11, 14, 18, 22, 26, 30};
  for (int s = 0; s < 8; ++s) {
    const int n = sizes[s];
    if (6L * n * n * n > max_tets) break;
    mica_world* world = NULL;
    mica_world_def wd = mica_world_def_default();
    wd.solver = MICA_SOLVER_MICA;
    wd.tolerance = 1e-6;
    wd.max_iterations = 100000;
    wd.mica_sweep = sweep;
    if (mica_world_create(&wd, &world) != MICA_OK) return 1;
    /* The cube [0, 0.1]^3 of scenes/box_scene.h, its base fixed, the sphere 1 mm above its top. */
    box_scene_def def = box_scene_def_default();
    def.body.youngs_modulus = 2e4;
    def.body.rayleigh_alpha = 2;
    def.cells[0] = def.cells[1] = def.cells[2] = n;
    def.tool_margin = 0.002;
    const double c[3] = {0.05, 0, 0.05}, y0 = 0.1 + 0.02 + 0.001;
    def.tool_position[0] = c[0];
    def.tool_position[1] = y0;
    def.tool_position[2] = c[2];
    figures fig;
    memset(&fig, 0, sizeof fig);
    malloc_trim(0);
    const long rss0 = status_kb("VmRSS:");
    box_scene scene;
    CHECK(box_scene_create(world, &def, &scene));
    const mica_body_id body = scene.body;
    const mica_tool_id tool = scene.tool;
    fig.nodes = scene.nodes;
    fig.tets = scene.tets;
    CHECK(mica_step(world, 0.01) < 0 ? -1 : MICA_OK);
    const long rss1 = status_kb("VmRSS:");
    const int steps = fig.tets > 40000 ? 10 : 20;
    if (press(world, body, tool, c, y0, 0.007, 0.1, 0.003, def.tool_radius + def.tool_margin, 0.01, 9, steps, &fig))
      return 1;
    fig.mem_step_b_per_tet = 1024.0 * (double)(rss1 - rss0) / fig.tets;
    malloc_trim(0);
    fig.mem_held_b_per_tet = 1024.0 * (double)(status_kb("VmRSS:") - rss0) / fig.tets;
    const double* st = fig.stage_ms;
    fprintf(csv, "%d,%d,%d,%.4f,%.4f,%.1f,%.5f,%.0f,%.5g,%.4f,%.4f,%.4f,%.0f\n", n, fig.nodes, fig.tets, fig.median,
            fig.p95, fig.iterations, fig.iterations > 0 ? fig.median / fig.iterations : NAN, fig.mem_step_b_per_tet,
            fig.force, st[MICA_STAGE_ROTATIONS], st[MICA_STAGE_ELEMENTS], st[MICA_STAGE_SOLVE], fig.mem_held_b_per_tet);
    fflush(csv);
    printf("%6d %8d %8d %10.3f %10.3f %10.1f %12.5f %10.0f %9.3f %9.3f %9.3f %10.0f\n", n, fig.nodes, fig.tets, fig.median,
           fig.p95, fig.iterations, fig.iterations > 0 ? fig.median / fig.iterations : NAN, fig.mem_step_b_per_tet,
           st[MICA_STAGE_ROTATIONS], st[MICA_STAGE_ELEMENTS], st[MICA_STAGE_SOLVE], fig.mem_held_b_per_tet);
    fflush(stdout);
    fprintf(stderr, "progress %d %d\n", s + 1, 8);
    mica_world_destroy(world);
  }
  fclose(csv);
  return 0;
}

/* The default world against the solvers it replaced: the same press with mica_world_def_default()
 * as it comes (only gravity off: tolerance 1e-8, cap 200), then with solver DIRECT (the default
 * before 0.5), then with MICA's Gauss-Seidel sweep (the default sweep before 0.5). */
static int defaults(const char* path, int steps) {
  printf("# command: OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 build/bench/bench_nidus --defaults %s %d\n", path, steps);
  const char* names[3] = {"the default world", "solver DIRECT", "MICA, Gauss-Seidel sweep"};
  figures fig[3];
  for (int k = 0; k < 3; ++k) {
    mica_world_def wd = mica_world_def_default();
    wd.gravity[1] = 0;
    if (k == 1) wd.solver = MICA_SOLVER_DIRECT;
    if (k == 2) wd.mica_sweep = MICA_SWEEP_GAUSS_SEIDEL;
    printf("\n## %s\n", names[k]);
    if (nidus(path, &wd, steps, 2, 1e4, 0.01, MICA_MODEL_COROTATIONAL, &fig[k])) return 1;
  }
  printf("\n%-26s %12s %14s %18s\n", "world", "total s", "median ms/step", "steps not converged");
  for (int k = 0; k < 3; ++k)
    printf("%-26s %12.2f %14.2f %11d of %d\n", names[k], 1e-3 * fig[k].mean * steps, fig[k].median, fig[k].capped, steps);
  return 0;
}

/* The material's cost: the same press with a co-rotational body, then a neo-Hookean one, both with
 * the factored sweep and its background refresh, in one process (the same machine state). */
static int neo_hookean(const char* path, int steps, int refactor) {
  printf("# command: OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 build/bench/bench_nidus --neo-hookean %s %d %d\n", path,
         steps, refactor);
  const int32_t models[2] = {MICA_MODEL_COROTATIONAL, MICA_MODEL_NEO_HOOKEAN};
  const char* names[2] = {"co-rotational", "neo-Hookean"};
  figures fig[2];
  for (int k = 0; k < 2; ++k) {
    const mica_world_def wd = bench_world(1e-6, MICA_SWEEP_FACTORED, refactor);
    printf("\n## %s body, factored sweep, factor refreshed every %d steps\n", names[k], refactor);
    if (nidus(path, &wd, steps, 40, 1e4, 0.01, models[k], &fig[k])) return 1;
  }
  printf("\nmedian ms/step: co-rotational %.2f, neo-Hookean %.2f: %.2fx (goal: at most 2x); solves/step %.2f and %.2f\n",
         fig[0].median, fig[1].median, fig[1].median / fig[0].median, fig[0].solves, fig[1].solves);
  printf("median CPU ms/step (less polluted by other load): co-rotational %.2f, neo-Hookean %.2f: %.2fx\n",
         fig[0].cpu_median, fig[1].cpu_median, fig[1].cpu_median / fig[0].cpu_median);
  return 0;
}

static const char* const kOptions[] = {"--defaults", "--neo-hookean", "--scaling", NULL};
static const char kUsage[] =
    "usage: bench_nidus [mesh] [tolerance] [steps] [warm-up] [E] [dt] [gauss-seidel steps] [refactor interval] [linear]\n"
    "       bench_nidus --defaults [mesh] [steps]\n"
    "       bench_nidus --neo-hookean [mesh] [steps] [refactor interval]\n"
    "       bench_nidus --scaling <out.csv> [max-tets] [factored|gauss-seidel]\n"
    "The nidus-scale scene (data/nidus/nidus.msh, 9668 tets) touched by a 2 mm forceps tip, timed per\n"
    "step on one core.\n"
    "  (no option)  MICA with the factored sweep, again with the factor refreshed every `refactor\n"
    "               interval` steps, then with the Gauss-Seidel sweep; defaults data/nidus/nidus.msh\n"
    "               1e-6 200 40 1e4 0.01 30 4; `linear` makes the body linear\n"
    "  --defaults   the default world as mica_world_def_default() gives it (tolerance 1e-8, cap\n"
    "               200), then solver DIRECT, then the Gauss-Seidel sweep: `steps` timed steps each\n"
    "               (default 110), total seconds and steps not converged\n"
    "  --neo-hookean  the press with a co-rotational body, then a neo-Hookean one, in one run: the\n"
    "               two medians and their ratio (factored sweep, refreshed every 6 steps; 200 steps)\n"
    "  --scaling    time per step against tets on box grids, 1k to 100k tets, into out.csv\n"
    "  --help       this text\n"
    "Run it as: OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 build/bench/bench_nidus\n";

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, kOptions);
  if (cli >= 0) return cli;
  if (argc > 1 && strcmp(argv[1], "--defaults") == 0) {
    int steps = 110;
    if (argc > 3 && !cli_int(argv[0], "steps", argv[3], 1, 1000000, &steps)) return 2;
    return defaults(argc > 2 ? argv[2] : "data/nidus/nidus.msh", steps);
  }
  if (argc > 1 && strcmp(argv[1], "--neo-hookean") == 0) {
    int steps = 200, refactor = 6;
    if ((argc > 3 && !cli_int(argv[0], "steps", argv[3], 1, 1000000, &steps)) ||
        (argc > 4 && !cli_int(argv[0], "refactor interval", argv[4], 0, 1000000, &refactor)))
      return 2;
    return neo_hookean(argc > 2 ? argv[2] : "data/nidus/nidus.msh", steps, refactor);
  }
  if (argc > 1 && strcmp(argv[1], "--scaling") == 0) {
    if (argc < 3) {
      fprintf(stderr, "usage: bench_nidus --scaling <out.csv> [max-tets] [factored|gauss-seidel]\n");
      return 2;
    }
    int max_tets = 110000;
    if (argc > 3 && !cli_int(argv[0], "max-tets", argv[3], 1, 100000000, &max_tets)) return 2;
    const int32_t sweep = argc > 4 && strcmp(argv[4], "gauss-seidel") == 0 ? MICA_SWEEP_GAUSS_SEIDEL : MICA_SWEEP_FACTORED;
    if (!cli_make_parent(argv[0], argv[2])) return 1;
    return scaling(argv[2], max_tets, sweep);
  }
  const char* path = argc > 1 ? argv[1] : "data/nidus/nidus.msh";
  double tol = 1e-6, E = 1e4, dt = 0.01;
  /* Every 6 steps: a nidus factorization and its copy take about 22 ms on the second core, more
   * than four 5 ms steps (with 4 the adopting steps wait for it). */
  int steps = 200, warmup = 40, gs_steps = 30, refactor = 6;
  if ((argc > 2 && !cli_double(argv[0], "tolerance", argv[2], 1e-15, 1, &tol)) ||
      (argc > 3 && !cli_int(argv[0], "steps", argv[3], 1, 1000000, &steps)) ||
      (argc > 4 && !cli_int(argv[0], "warm-up", argv[4], 2, 1000000, &warmup)) ||
      (argc > 5 && !cli_double(argv[0], "E", argv[5], 1, 1e12, &E)) ||
      (argc > 6 && !cli_double(argv[0], "dt", argv[6], 1e-6, 1, &dt)) ||
      (argc > 7 && !cli_int(argv[0], "gauss-seidel steps", argv[7], 0, 1000000, &gs_steps)) ||
      (argc > 8 && !cli_int(argv[0], "refactor interval", argv[8], 0, 1000000, &refactor)))
    return 2;
  const int linear = argc > 9 && strcmp(argv[9], "linear") == 0;
  printf("# command: OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 build/bench/bench_nidus %s %g %d %d %g %g %d %d%s\n", path,
         tol, steps, warmup, E, dt, gs_steps, refactor, linear ? " linear" : "");
  /* The MICA sweeps on the same scene, one after the other in this process: the factored one
   * with the factor of the first step, then with a background refresh every `refactor` steps
   * (its worker thread runs beside the step: give the process a second core to see what it is
   * worth), and the paper's Gauss-Seidel (hundreds of times slower) over fewer steps. */
  const int32_t model = linear ? MICA_MODEL_LINEAR : MICA_MODEL_COROTATIONAL;
  figures factored, refreshed, gs;
  printf("\n## factored sweep\n");
  const mica_world_def wf = bench_world(tol, MICA_SWEEP_FACTORED, 0), wr = bench_world(tol, MICA_SWEEP_FACTORED, refactor),
                       wg = bench_world(tol, MICA_SWEEP_GAUSS_SEIDEL, 0);
  if (nidus(path, &wf, steps, warmup, E, dt, model, &factored)) return 1;
  if (refactor > 0) {
    printf("\n## factored sweep, factor refreshed every %d steps in the background\n", refactor);
    if (nidus(path, &wr, steps, warmup, E, dt, model, &refreshed)) return 1;
    printf("\nmedian ms/step: factored %.2f, refreshed every %d steps %.2f: %.2fx\n", factored.median, refactor,
           refreshed.median, factored.median / refreshed.median);
  }
  if (gs_steps == 0) return 0;
  printf("\n## gauss-seidel sweep (the paper's)\n");
  if (nidus(path, &wg, gs_steps, warmup, E, dt, model, &gs)) return 1;
  printf("\nmedian ms/step: factored %.2f, gauss-seidel %.2f: %.1fx faster; target 5 ms (paper: ~100 ms)\n",
         factored.median, gs.median, gs.median / factored.median);
  return 0;
}
