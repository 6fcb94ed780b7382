/* SPDX-License-Identifier: Apache-2.0 */
/* What cutting costs a step: a scripted 3 cm incision, 8 mm deep, at 1 cm/s through the nidus
 * (data/nidus/nidus.msh; scenes/incision_scene.h with the forceps tip resting beside the line, no
 * hook), against the same scene with the same capsule on the same path that is not a blade (it
 * pushes the tissue, it does not cut it), the two worlds stepped in turn in one run so that both
 * see the same machine load.
 *
 * Figures (each step's time is the stepping thread's CPU time, mica_step only):
 * - cut/uncut median ratio, cut/uncut p99 ratio: the two worlds' medians and 99th percentiles of
 *   their step times, and the ratios (goals: median <= 1.5, p99 <= 2.0);
 * - steps that waited for a factorization: steps of the cut world whose solver factored a body's
 *   system on the stepping thread after the first step (0 expected when the factor stays ahead);
 * - the blade force's largest step-to-step jump (N), and the cuts made.
 *
 * usage: bench_incision [mesh]; default data/nidus/nidus.msh
 * Run it from the repository root: build/bench/bench_incision
 */
#define _GNU_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mica/mica.h>

#include "bench_common.h"
#include "cli.h"
#include "incision_scene.h"

static const char* const kUsage =
    "usage: bench_incision [mesh]\n"
    "A 3 cm incision at 1 cm/s through the nidus with a forceps tip beside it, against the same\n"
    "scene uncut, stepped in turn: the step times' medians and 99th percentiles and their ratios,\n"
    "the steps that waited for a factorization and the blade force's largest jump.\n"
    "Default mesh: data/nidus/nidus.msh.\n"
    "  --help  this text\n"
    "Run it from the repository root: build/bench/bench_incision\n";

static double percentile(double* v, int n, double p) {
  qsort(v, (size_t)n, sizeof *v, cmp);
  const int k = (int)ceil(p * n) - 1;
  return v[k < 0 ? 0 : k >= n ? n - 1 : k];
}

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  if (argc > 2) {
    fprintf(stderr, "%s: bad arguments\n\n%s", argv[0], kUsage);
    return 2;
  }
  incision_scene_def def = incision_scene_def_default();
  def.cells = 0;
  def.mesh = argc > 1 ? argv[1] : "data/nidus/nidus.msh";
  def.hook = 0;
  def.forceps = 1;
  incision_scene cut, uncut;
  if (incision_scene_create(&def, &cut) != MICA_OK) {
    fprintf(stderr, "%s\n", cut.error);
    return 1;
  }
  def.blade = 0;
  if (incision_scene_create(&def, &uncut) != MICA_OK) {
    fprintf(stderr, "%s\n", uncut.error);
    incision_scene_destroy(&cut);
    return 1;
  }
  const int n = cut.steps;
  double* t_cut = malloc(sizeof(double) * (size_t)n);
  double* t_uncut = malloc(sizeof(double) * (size_t)n);
  int waited = 0, failed = 0;
  double last_force = 0, jump = 0;
  mica_world_stats stats;
  memset(&stats, 0, sizeof stats);
  stats.struct_size = sizeof stats;
  for (int k = 1; k <= n && !failed; ++k) {
    double start = thread_cpu_ms();
    failed |= incision_scene_step(&uncut, k) < 0;
    t_uncut[k - 1] = thread_cpu_ms() - start;
    start = thread_cpu_ms();
    failed |= incision_scene_step(&cut, k) < 0;
    t_cut[k - 1] = thread_cpu_ms() - start;
    mica_world_get_stats(cut.press.world, &stats);
    if (k > 1 && stats.factor_waits > 0) ++waited;
    double f[3], along = 0;
    incision_scene_blade_force(&cut, f, &along);
    const double magnitude = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    if (k > 1) jump = fmax(jump, fabs(magnitude - last_force));
    last_force = magnitude;
  }
  if (failed) fprintf(stderr, "a step failed: %s%s\n", cut.error, uncut.error);
  uint64_t version = 0;
  int32_t nodes = 0;
  mica_body_get_topology_version(cut.press.world, cut.press.body, &version);
  mica_body_get_counts(cut.press.world, cut.press.body, &nodes, NULL, NULL);
  const double med_cut = percentile(t_cut, n, 0.5), med_uncut = percentile(t_uncut, n, 0.5);
  const double p99_cut = percentile(t_cut, n, 0.99), p99_uncut = percentile(t_uncut, n, 0.99);
  char where[512];
  machine(where, sizeof where);
  printf("bench_incision: the nidus (%d tets), a 3 cm incision 8 mm deep at 1 cm/s with a forceps tip beside it, %d steps of 10 ms\n",
         (int)cut.press.tets, n);
  printf("machine: %s\n", where);
  printf("cuts made %llu, node copies %d\n", (unsigned long long)version, (int)(nodes - cut.press.nodes));
  printf("step CPU ms: cut median %.3f p99 %.3f; uncut median %.3f p99 %.3f\n", med_cut, p99_cut, med_uncut, p99_uncut);
  printf("cut/uncut median ratio %.2f\n", med_cut / med_uncut);
  printf("cut/uncut p99 ratio %.2f\n", p99_cut / p99_uncut);
  printf("steps that waited for a factorization %d\n", waited);
  printf("blade force largest step-to-step jump %.3f N\n", jump);
  printf("command: taskset -c 1 build/bench/bench_incision   (from the repository root)\n");
  free(t_cut);
  free(t_uncut);
  incision_scene_destroy(&cut);
  incision_scene_destroy(&uncut);
  return failed ? 1 : 0;
}
