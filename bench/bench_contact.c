/* SPDX-License-Identifier: Apache-2.0 */
/* Force quality of tool contact: does the force a held tool feels settle, and does it grow
 * smoothly while the tool goes deeper?
 *
 * Scene (scenes/press_scene.h): the cube of examples_c/sphere_indent.c (10 cm, fixed at
 * its bottom, E = 1e4 Pa, nu = 0.4, rho = 1000, Rayleigh alpha = 2/s, beta = 0, no gravity),
 * cells^3 cubes x 5 tets. A tool starts 5 mm above the top face over its centre, goes down at
 * constant speed to 10 mm below it in 1 s, and is held there for 1 s. Tools: a sphere R = 2 cm;
 * a capsule of radius 1 cm and half-length 2 cm lying along x; a box of half-extents 2 cm; a
 * hull of 8 points (a 3 cm high frustum with irregular quadrilateral ends, its 3.6 cm wide
 * bottom turned against the grid). Margin 1.5 mm. Solvers: exact (MICA_SOLVER_DIRECT) and MICA
 * with the factored sweep (tolerance 1e-8, cap 20000), optionally MICA's Gauss-Seidel sweep.
 * The nidus case: a 2 mm sphere (margin 0.5 mm) 0.5 mm above the top of data/nidus/nidus.msh
 * over its centroid (held by its lowest fifth, as bench_nidus.c), down 2 mm into it at 10 mm/s,
 * held 1 s, dt = 10 ms.
 *
 * Per run, from the vertical tool force F of each step:
 * - alt run: during the hold, the longest run of consecutive sign changes of the step-to-step
 *   change dF (changes below 1e-5 of the final force are round-off and skipped);
 * - late chg: the largest |dF| / |F_end| after the first 0.5 s of the hold (the chatter
 *   amplitude that remains);
 * - load drop: the largest relative drop (F[k-1] - F[k]) / F[k-1] between consecutive loading
 *   steps once the tool is deeper than 2 mm (0.5 mm on the nidus) below the undeformed surface;
 * - ms/step: the median wall time of mica_step over the run; iters: mean solver iterations per
 *   step; capped: steps that stopped at the iteration cap.
 * The thresholds: alt run <= 3, late chg < 1e-3, load drop < 1 %; a row passes when all
 * three hold (the issue asks the loading one for the sphere; it is reported for every tool).
 *
 * usage: bench_contact [--quick | --full] [--gauss-seidel] [--no-nidus] [--csv FILE] [--tol T]
 *                      [--cells LIST] [--dt LIST] [--shape NAME] [--trace] [--run-limit S] [--nidus-only] [--solver NAME]
 *   default  cells 8 at dt 1, 5, 10, 20 ms and cells 12 at dt 10, 20 ms; every tool; exact and
 *            MICA factored; the nidus (exact and MICA factored). About 9 minutes on one core
 *            (docs/accuracy-vs-time.md, "Force quality").
 *   --full   cells 8, 12, 16 x dt 1, 5, 10, 20 ms (the whole grid): hours on one core
 *            (16 cells cost 0.1-2 s per step, 2000 steps at 1 ms); --cells/--dt pick a part
 *   --quick  cells 12, dt 10 ms, every tool, exact and MICA factored; no nidus
 * Run it on one core with CHOLMOD's BLAS and OpenMP on the calling thread:
 *   OMP_THREAD_LIMIT=1 OPENBLAS_NUM_THREADS=1 taskset -c 1 build/bench/bench_contact --csv out/contact.csv
 */
#define _GNU_SOURCE
#include <math.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <mica/mica.h>

#include "bench_common.h"
#include "cli.h"
#include "press_scene.h"

static int trace = 0;             /* --trace: one line per step */
static double run_limit_s = 120;  /* --run-limit: wall-clock seconds for one run */

typedef struct {
  int32_t shape, cells; /* cells 0: the nidus */
  double dt;
  int32_t solver, sweep;
} config;

typedef struct {
  int32_t steps_done, steps; /* fewer done than planned: the run hit --run-limit */
  int32_t nodes, tets, alt_run, capped, contacts;
  double force, late, drop, ms_median, iterations;
  int pass_alt, pass_late, pass_drop;
} result;

static const char* solver_name(int32_t solver, int32_t sweep) {
  if (solver == MICA_SOLVER_DIRECT) return "exact";
  if (solver == MICA_SOLVER_PCG) return "PCG";
  return sweep == MICA_SWEEP_FACTORED ? "MICA-F" : "MICA-GS";
}

static int run(const config* c, double tol, result* r) {
  memset(r, 0, sizeof *r);
  press_scene_def def = press_scene_def_default();
  def.shape = c->shape;
  def.cells = c->cells;
  def.dt = c->dt;
  def.solver = c->solver;
  def.sweep = c->sweep;
  def.tolerance = tol;
  double drop_depth = 0.002;
  if (c->cells == 0) { /* the nidus, as bench_nidus.c presses it */
    def.size = 0.002;
    def.margin = 0.0005;
    def.gap = 0.0005;
    def.depth = 0.002;
    def.load_time = (def.gap + def.depth) / 0.01;
    drop_depth = 0.0005;
  }
  press_scene s;
  if (press_scene_create(&def, &s) < 0) {
    fprintf(stderr, "%s\n", s.error);
    return 1;
  }
  r->nodes = s.nodes;
  r->tets = s.tets;
  double* f = malloc(sizeof(double) * (size_t)(s.steps + 1));
  double* ms = malloc(sizeof(double) * (size_t)s.steps);
  long iterations = 0;
  f[0] = 0;
  r->steps = s.steps;
  const double t_run = now_ms();
  for (int32_t k = 1; k <= s.steps; ++k) {
    if (now_ms() - t_run > 1e3 * run_limit_s) break;
    r->steps_done = k;
    double force[3];
    const double t0 = now_ms();
    const mica_status st = press_scene_step(&s, k, force, &r->contacts);
    ms[k - 1] = now_ms() - t0;
    if (st < 0) {
      fprintf(stderr, "%s %d cells dt %g ms %s: %s\n", press_scene_shape_name(c->shape), c->cells, 1e3 * c->dt,
              solver_name(c->solver, c->sweep), s.error);
      press_scene_destroy(&s);
      free(f);
      free(ms);
      return 1;
    }
    mica_world_stats stats;
    memset(&stats, 0, sizeof stats);
    stats.struct_size = sizeof stats;
    mica_world_get_stats(s.world, &stats);
    iterations += stats.solver_iterations;
    if (!stats.converged) ++r->capped;
    f[k] = force[1];
    if (trace)
      printf("#   step %4d %s depth %+.5f m  F %.6f N  dF %+.3e  contacts %d  iters %d%s\n", k, k > s.load_steps ? "hold" : "load",
             press_scene_depth(&s, k), f[k], f[k] - f[k - 1], r->contacts, stats.solver_iterations,
             stats.converged ? "" : "  (cap)");
  }
  if (r->steps_done < s.steps) { /* timed out: no figures but the time per step */
    qsort(ms, (size_t)r->steps_done, sizeof ms[0], cmp);
    r->ms_median = ms[r->steps_done / 2];
    r->iterations = (double)iterations / r->steps_done;
    r->force = f[r->steps_done];
    r->late = r->drop = NAN;
    r->alt_run = -1;
    press_scene_destroy(&s);
    free(f);
    free(ms);
    return 0;
  }
  const int32_t n = s.steps, nl = s.load_steps;
  r->force = f[n];
  const double ref = fabs(f[n]) > 0 ? fabs(f[n]) : 1;
  /* Hold: steps nl+1 .. n have the tool still. */
  int run_len = 0;
  double last = 0;
  for (int32_t k = nl + 2; k <= n; ++k) {
    const double d = f[k] - f[k - 1];
    if (fabs(d) < 1e-5 * ref) continue; /* round-off: neither continues nor breaks a run */
    if (last != 0 && d * last < 0) {
      if (++run_len > r->alt_run) r->alt_run = run_len;
    } else {
      run_len = 0;
    }
    last = d;
  }
  const int32_t late_from = nl + 1 + (int32_t)(0.5 / c->dt + 0.5);
  for (int32_t k = late_from + 1; k <= n; ++k) r->late = fmax(r->late, fabs(f[k] - f[k - 1]) / ref);
  for (int32_t k = 2; k <= nl; ++k)
    if (press_scene_depth(&s, k - 1) > drop_depth && f[k - 1] > 0)
      r->drop = fmax(r->drop, (f[k - 1] - f[k]) / f[k - 1]);
  qsort(ms, (size_t)n, sizeof ms[0], cmp);
  r->ms_median = n % 2 ? ms[n / 2] : 0.5 * (ms[n / 2 - 1] + ms[n / 2]);
  r->iterations = (double)iterations / n;
  r->pass_alt = r->alt_run <= 3;
  r->pass_late = r->late < 1e-3;
  r->pass_drop = r->drop < 0.01;
  press_scene_destroy(&s);
  free(f);
  free(ms);
  return 0;
}

/* Whether `v` is in the comma-separated list (NULL: every value). */
static int in_list(const char* list, double v) {
  if (!list) return 1;
  const char* p = list;
  while (*p) {
    char* end;
    const double x = strtod(p, &end);
    if (end == p) return 0;
    if (fabs(x - v) < 1e-9 * fmax(1, fabs(v))) return 1;
    p = *end == ',' ? end + 1 : end;
    if (*end != ',' && *end) return 0;
  }
  return 0;
}

static const char kUsage[] =
    "usage: bench_contact [--quick | --full] [--gauss-seidel] [--no-nidus] [--csv FILE] [--tol T]\n"
    "                     [--cells LIST] [--dt LIST] [--shape NAME] [--trace] [--run-limit S] [--nidus-only] [--solver NAME]\n"
    "  a tool pressed 10 mm into a 10 cm cube at constant speed over 1 s and held 1 s; per run:\n"
    "  the end force, the longest run of alternating step-to-step changes in the hold, the largest\n"
    "  relative change after 0.5 s of hold, the largest relative drop while loading, ms per step\n"
    "  (default) cells 8 x dt 1, 5, 10, 20 ms, cells 12 at dt 10, 20 ms, + the nidus (~10 min)\n"
    "  --full          cells 8, 12, 16 x dt 1, 5, 10, 20 ms, + the nidus (hours)\n"
    "  --quick         cells 12, dt 10 ms (no nidus)\n"
    "  --gauss-seidel  also MICA with the paper's Gauss-Seidel sweep (slow)\n"
    "  --no-nidus      skip the nidus case\n"
    "  --csv FILE      also write the rows to FILE (its folder is made if missing)\n"
    "  --tol T         MICA tolerance (default 1e-8; cap 20000)\n"
    "  --cells LIST    only these cells per side (comma list, e.g. 8,16), from 8, 12, 16\n"
    "  --dt LIST       only these time steps in ms (comma list), from 1, 5, 10, 20\n"
    "                  (with --cells or --dt, the grid is every combination of the two lists)\n"
    "  --shape NAME    only this tool: sphere, capsule, box or hull\n"
    "  --trace         print every step (depth, force, change, contacts, iterations)\n"
    "  --run-limit S   give up a run after S s of wall time (default 120): a TIMEOUT row\n"
    "  --nidus-only    only the nidus case\n"
    "  --solver NAME   only this solver: exact, MICA-F or MICA-GS (with --gauss-seidel)\n"
    "  every tool (sphere, capsule, box, hull), exact (DIRECT) and MICA factored\n"
    "  --help          this text\n";

/* Whether each item of the comma-separated `list` is a number (cli_double says which is not). */
static int check_list(const char* program, const char* what, const char* list) {
  char item[64];
  for (const char* p = list;; ++p) {
    const size_t n = strcspn(p, ",");
    snprintf(item, sizeof item, "%.*s", (int)n, p);
    double unused;
    if (!cli_double(program, what, item, 0, 1e6, &unused)) return 0;
    p += n;
    if (!*p) return 1;
  }
}

int main(int argc, char** argv) {
  static const char* const options[] = {"--quick",     "--full",      "--gauss-seidel", "--no-nidus",   "--csv FILE",
                                        "--tol T",     "--cells LIST", "--dt LIST",     "--shape NAME", "--trace",
                                        "--run-limit S", "--nidus-only", "--solver NAME", NULL};
  const int cli = cli_check(argc, argv, kUsage, options);
  if (cli >= 0) return cli;
  int quick = 0, full = 0, gs = 0, nidus = 1, nidus_only = 0;
  const char* csv_path = NULL;
  const char* only_cells = NULL; /* comma lists: keep only these cells / dt (ms) */
  const char* only_dt = NULL;
  const char* only_shape = NULL; /* one tool */
  const char* only_solver = NULL; /* one solver */
  double tol = 1e-8;
  int ok = 1;
  for (int i = 1; i < argc && ok; ++i) { /* cli_check saw that each option with a value has one */
    if (strcmp(argv[i], "--quick") == 0) quick = 1;
    else if (strcmp(argv[i], "--full") == 0) full = 1;
    else if (strcmp(argv[i], "--gauss-seidel") == 0) gs = 1;
    else if (strcmp(argv[i], "--no-nidus") == 0) nidus = 0;
    else if (strcmp(argv[i], "--csv") == 0) csv_path = argv[++i];
    else if (strcmp(argv[i], "--tol") == 0) ok = cli_double(argv[0], "--tol", argv[++i], 1e-15, 1, &tol);
    else if (strcmp(argv[i], "--cells") == 0) ok = check_list(argv[0], "--cells", only_cells = argv[++i]);
    else if (strcmp(argv[i], "--dt") == 0) ok = check_list(argv[0], "--dt", only_dt = argv[++i]);
    else if (strcmp(argv[i], "--shape") == 0) only_shape = argv[++i];
    else if (strcmp(argv[i], "--trace") == 0) trace = 1;
    else if (strcmp(argv[i], "--run-limit") == 0) ok = cli_double(argv[0], "--run-limit", argv[++i], 0.1, 86400, &run_limit_s);
    else if (strcmp(argv[i], "--nidus-only") == 0) nidus_only = 1;
    else if (strcmp(argv[i], "--solver") == 0) only_solver = argv[++i];
    else {
      fprintf(stderr, "%s: %s: this program takes options only (--help lists them)\n", argv[0], argv[i]);
      ok = 0;
    }
  }
  if (ok && quick && full) {
    fprintf(stderr, "%s: --quick and --full exclude each other\n", argv[0]);
    ok = 0;
  }
  if (!ok) return 2;
  if (csv_path && !cli_make_parent(argv[0], csv_path)) return 1;
  if (quick && !nidus_only) nidus = 0;
  if (nidus_only) nidus = 1;

  const int32_t shapes[4] = {MICA_TOOL_SPHERE, MICA_TOOL_CAPSULE, MICA_TOOL_BOX, MICA_TOOL_HULL};
  const double dts[4] = {0.001, 0.005, 0.01, 0.02};
  const int32_t cell_sizes[3] = {8, 12, 16};
  int32_t solvers[3][2] = {{MICA_SOLVER_DIRECT, 0}, {MICA_SOLVER_MICA, MICA_SWEEP_FACTORED},
                           {MICA_SOLVER_MICA, MICA_SWEEP_GAUSS_SEIDEL}};
  const int nsolvers = gs ? 3 : 2;
  config* plan = malloc(sizeof(config) * 200);
  int np = 0;
  for (int si = 0; si < 4; ++si) {
    if (nidus_only || (only_shape && strcmp(only_shape, press_scene_shape_name(shapes[si])) != 0)) continue;
    for (int ci = 0; ci < 3; ++ci)
      for (int di = 0; di < 4; ++di) {
        const int32_t cells = cell_sizes[ci];
        const double dt = dts[di];
        int take;
        if (full) take = 1;
        else if (quick) take = cells == 12 && dt == 0.01;
        else take = cells == 8 || (cells == 12 && dt >= 0.01);
        if (only_cells || only_dt) take = in_list(only_cells, cells) && in_list(only_dt, 1e3 * dt);
        if (!take) continue;
        for (int so = 0; so < nsolvers; ++so)
          if (!only_solver || strcmp(only_solver, solver_name(solvers[so][0], solvers[so][1])) == 0)
          plan[np++] = (config){shapes[si], cells, dt, solvers[so][0], solvers[so][1]};
      }
  }
  if (nidus && (!only_shape || strcmp(only_shape, "sphere") == 0))
    for (int so = 0; so < nsolvers; ++so)
      if (!only_solver || strcmp(only_solver, solver_name(solvers[so][0], solvers[so][1])) == 0)
        plan[np++] = (config){MICA_TOOL_SPHERE, 0, 0.01, solvers[so][0], solvers[so][1]};

  char m[300];
  machine(m, sizeof m);
  const char* omp = getenv("OMP_THREAD_LIMIT");
  const char* blas = getenv("OPENBLAS_NUM_THREADS");
  char cmdline[1024] = "";
  size_t len = 0;
  for (int i = 0; i < argc && len < sizeof cmdline; ++i)
    len += (size_t)snprintf(cmdline + len, sizeof cmdline - len, "%s%s", i ? " " : "", argv[i]);
  printf("# bench_contact: %s\n", m);
  printf("# command: OMP_THREAD_LIMIT=%s OPENBLAS_NUM_THREADS=%s %s\n", omp ? omp : "(unset)", blas ? blas : "(unset)",
         cmdline);
  printf("# cube 10 cm (cells^3 x 5 tets, fixed bottom), E = 1e4 Pa, nu = 0.4, rho = 1000, alpha = 2/s, beta = 0, "
         "no gravity; tool 5 mm above -> 10 mm deep in 1 s, held 1 s; margin 1.5 mm; MICA tol %.0e cap 20000\n",
         tol);
  printf("# nidus: 2 mm sphere, 0.5 mm above -> 2 mm deep at 10 mm/s, held 1 s, margin 0.5 mm, dt 10 ms\n");
  printf("# thresholds: alt run <= 3, late chg < 1e-3 (after 0.5 s of hold), load drop < 1%% (deeper than 2 mm; "
         "0.5 mm on the nidus)\n");
  FILE* csv = NULL;
  if (csv_path) {
    csv = fopen(csv_path, "w");
    if (!csv) {
      fprintf(stderr, "cannot write %s\n", csv_path);
      return 1;
    }
    fprintf(csv, "# bench_contact: %s; command: OMP_THREAD_LIMIT=%s OPENBLAS_NUM_THREADS=%s %s\n", m,
            omp ? omp : "(unset)", blas ? blas : "(unset)", cmdline);
    fprintf(csv, "body,shape,cells,nodes,tets,dt_ms,solver,force_N,alt_run,late_rel,load_drop_rel,ms_median,"
                 "iters_mean,capped,contacts,pass_alt,pass_late,pass_drop,pass\n");
  }
  printf("%-6s %-8s %5s %6s %-8s %9s %7s %9s %9s %9s %8s %6s  %s\n", "body", "shape", "cells", "dt ms", "solver",
         "F end N", "alt run", "late chg", "load drop", "ms/step", "iters", "capped", "verdict");
  fflush(stdout);
  int failed_runs = 0, failing_rows = 0;
  const double t_start = now_ms();
  for (int i = 0; i < np; ++i) {
    const config* c = &plan[i];
    result r;
    fprintf(stderr, "progress %d %d\n", i, np);
    if (run(c, tol, &r)) {
      ++failed_runs;
      continue;
    }
    const int timed_out = r.steps_done < r.steps;
    const int pass = !timed_out && r.pass_alt && r.pass_late && r.pass_drop;
    failing_rows += !pass;
    char verdict[64];
    if (timed_out)
      snprintf(verdict, sizeof verdict, "TIMEOUT: %d of %d steps in %g s", r.steps_done, r.steps, run_limit_s);
    else if (pass) snprintf(verdict, sizeof verdict, "pass");
    else
      snprintf(verdict, sizeof verdict, "FAIL:%s%s%s", r.pass_alt ? "" : " alt", r.pass_late ? "" : " late",
               r.pass_drop ? "" : " drop");
    const char* body = c->cells ? "cube" : "nidus";
    printf("%-6s %-8s %5d %6g %-8s %9.4f %7d %9.2e %8.3f%% %9.2f %8.1f %6d  %s\n", body,
           press_scene_shape_name(c->shape), c->cells, 1e3 * c->dt, solver_name(c->solver, c->sweep), r.force,
           r.alt_run, r.late, 100 * r.drop, r.ms_median, r.iterations, r.capped, verdict);
    fflush(stdout);
    if (csv) {
      fprintf(csv, "%s,%s,%d,%d,%d,%g,%s,%.6g,%d,%.4g,%.4g,%.4g,%.1f,%d,%d,%d,%d,%d,%d\n", body,
              press_scene_shape_name(c->shape), c->cells, r.nodes, r.tets, 1e3 * c->dt,
              solver_name(c->solver, c->sweep), r.force, r.alt_run, r.late, r.drop, r.ms_median, r.iterations,
              r.capped, r.contacts, r.pass_alt, r.pass_late, r.pass_drop, pass);
      fflush(csv);
    }
  }
  fprintf(stderr, "progress %d %d\n", np, np);
  printf("# %d runs, %d failing the thresholds, %d could not run; %.0f s\n", np, failing_rows, failed_runs,
         1e-3 * (now_ms() - t_start));
  if (csv) fclose(csv);
  free(plan);
  /* Failing thresholds is a finding, not an error of the benchmark. */
  return failed_runs ? 1 : 0;
}
