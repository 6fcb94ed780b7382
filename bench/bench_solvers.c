/* SPDX-License-Identifier: Apache-2.0 */
/* What each solver costs and how far it is from the exact answer, side by side in one run.
 *
 * Scene: a cube (E = 2e4 Pa) fixed at its base, a sphere pressing into the top while a grasp
 * drags one side, dt = 10 ms. Every configuration replays the same 40 steps; for each step the
 * wall time of mica_step is recorded and the velocities are compared with the exact reference
 * (MICA_SOLVER_DIRECT: CHOLMOD + exact Delassus matrix) run alongside.
 *
 * usage: bench_solvers [cells-per-side]      (default 8: 3 x 8^3 x 6 = 3072 tets)
 */
#define _GNU_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <mica/mica.h>
#include "cli.h"

#include "bench_common.h"
#include "box_scene.h"

#define STEPS 40

typedef struct {
  mica_world* world;
  mica_body_id body;
  mica_tool_id tool;
  int32_t nodes;
} scene;

static int make_scene(scene* s, int32_t solver, double tol, int32_t cells) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = -9.81;
  wd.solver = solver;
  wd.tolerance = tol > 0 ? tol : 1e-8; /* unused by DIRECT */
  wd.max_iterations = 1000000;
  if (mica_world_create(&wd, &s->world) != MICA_OK) return 0;
  /* The cube [0, 0.1]^3 of scenes/box_scene.h, its base fixed, the face x = 0.1 dragged along z. */
  box_scene_def def = box_scene_def_default();
  def.body.youngs_modulus = 2e4;
  def.body.rayleigh_alpha = 2;
  def.cells[0] = def.cells[1] = def.cells[2] = cells;
  def.drag_velocity[2] = 0.05;
  def.tool_radius = 0.03;
  def.tool_margin = 0.002;
  def.tool_position[0] = 0.05;
  def.tool_position[1] = 0.13;
  def.tool_position[2] = 0.05;
  box_scene bs;
  if (box_scene_create(s->world, &def, &bs) != MICA_OK) return 0;
  s->body = bs.body;
  s->tool = bs.tool;
  s->nodes = bs.nodes;
  return 1;
}

static const char kUsage[] =
    "usage: bench_solvers [cells-per-side]\n"
    "What each solver costs and how far it is from the exact answer: a cube (E = 2e4 Pa) fixed at its\n"
    "base, a sphere pressing into the top while a grasp drags one side, 40 steps of 10 ms, each\n"
    "configuration against MICA_SOLVER_DIRECT run alongside.\n"
    "  cells-per-side  the cube's mesh (default 8: 3072 tets)\n"
    "  --help          this text\n";

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  int cells = 8;
  if (argc > 1 && !cli_int(argv[0], "cells-per-side", argv[1], 2, 64, &cells)) return 2;
  struct {
    const char* name;
    int32_t solver;
    double tol;
  } configs[] = {{"exact (DIRECT)", MICA_SOLVER_DIRECT, 0},  {"MICA tol 1e-2", MICA_SOLVER_MICA, 1e-2},
                 {"MICA tol 1e-4", MICA_SOLVER_MICA, 1e-4}, {"MICA tol 1e-6", MICA_SOLVER_MICA, 1e-6},
                 {"MICA tol 1e-8", MICA_SOLVER_MICA, 1e-8}, {"PCG tol 1e-6", MICA_SOLVER_PCG, 1e-6},
                 {"PCG tol 1e-10", MICA_SOLVER_PCG, 1e-10}};
  const int nconf = (int)(sizeof configs / sizeof configs[0]);
  scene ref;
  if (!make_scene(&ref, MICA_SOLVER_DIRECT, 0, cells)) {
    fprintf(stderr, "scene: %s\n", mica_world_last_error(ref.world));
    return 1;
  }
  printf("# bench_solvers: %d^3 cells x 6 tets, %d nodes, %d steps of 10 ms, sphere press + grasp drag + gravity\n",
         cells, ref.nodes, STEPS);
  printf("# command: build/bench/bench_solvers %d\n", cells);
  printf("%-16s %10s %10s %10s %14s %14s\n", "solver", "median ms", "p95 ms", "iters/step", "max |dv| m/s",
         "tool Fy err N");
  double* v = malloc(sizeof(double) * 3 * (size_t)ref.nodes);
  double* vr = malloc(sizeof(double) * 3 * (size_t)ref.nodes);
  for (int c = 0; c < nconf; ++c) {
    scene s, r;
    if (!make_scene(&s, configs[c].solver, configs[c].tol, cells) || !make_scene(&r, MICA_SOLVER_DIRECT, 0, cells))
      return 1;
    double ms[STEPS], worst_dv = 0, worst_f = 0;
    long iterations = 0;
    for (int k = 0; k < STEPS; ++k) {
      const double y = 0.13 - 0.0005 * (k < 30 ? k : 30); /* press 1.5 cm, then hold */
      const double p[3] = {0.05, y, 0.05}, q[4] = {1, 0, 0, 0};
      mica_tool_set_pose(s.world, s.tool, p, q);
      mica_tool_set_pose(r.world, r.tool, p, q);
      const double t0 = now_ms();
      if (mica_step(s.world, 0.01) < 0) {
        fprintf(stderr, "%s: %s\n", configs[c].name, mica_world_last_error(s.world));
        return 1;
      }
      ms[k] = now_ms() - t0;
      mica_step(r.world, 0.01);
      mica_world_stats st = {.struct_size = sizeof st};
      mica_world_get_stats(s.world, &st);
      iterations += st.solver_iterations;
      mica_body_get_velocities(s.world, s.body, v, s.nodes, NULL);
      mica_body_get_velocities(r.world, r.body, vr, r.nodes, NULL);
      for (int32_t i = 0; i < 3 * s.nodes; ++i) worst_dv = fmax(worst_dv, fabs(v[i] - vr[i]));
      double f[3], fr[3];
      mica_tool_get_force(s.world, s.tool, f, NULL, NULL);
      mica_tool_get_force(r.world, r.tool, fr, NULL, NULL);
      worst_f = fmax(worst_f, fabs(f[1] - fr[1]));
    }
    qsort(ms, STEPS, sizeof ms[0], cmp);
    printf("%-16s %10.3f %10.3f %10.1f %14.3g %14.3g\n", configs[c].name, ms[STEPS / 2], ms[(STEPS * 95) / 100],
           (double)iterations / STEPS, worst_dv, worst_f);
    mica_world_destroy(s.world);
    mica_world_destroy(r.world);
  }
  free(v);
  free(vr);
  mica_world_destroy(ref.world);
  return 0;
}
