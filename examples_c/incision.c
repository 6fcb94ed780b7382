/* SPDX-License-Identifier: Apache-2.0 */
/* An incision (scenes/incision_scene.h): a blade (mica_tool_def.blade) goes into the top of the
 * 10 cm cube of 20^3 cells and cuts a 3 cm line at 1 cm/s, 8 mm deep, while a hook
 * grasps the tissue on one side and draws it back so the cut opens. Each step goes to
 * <out>/incision.csv (time, phase, the blade tip, the force the tissue puts on the blade and its
 * part against the cutting direction, the body's topology version and node count); at the end
 * the body is written as <out>/incision.vtk (scripts/plot_incision.py draws both).
 * The program checks that the blade cut (nodes were added), that the force stayed finite and
 * pushed back against the blade while it cut, and that the cut opened (a node on the hook's side
 * of the line lies more than 2 mm from its twin on the other side) and nothing flew off (no node
 * moved 3 cm), and exits 1 if not.
 *
 * With --nidus the same incision goes into the nidus (data/nidus/nidus.msh, 9668 tets) instead,
 * through the top of the lesion, with the same hook and the same checks.
 *
 * usage: incision [--nidus] [output-folder]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mica/mica.h>

#include "cli.h"
#include "incision_scene.h"

static const char kUsage[] =
    "usage: incision [--nidus] [output-folder]\n"
    "A blade cuts a 3 cm line, 8 mm deep, at 1 cm/s into the top of a soft 10 cm cube fixed at its\n"
    "base (with --nidus: into the nidus, data/nidus/nidus.msh), while a hook grasps one side and\n"
    "draws it back so the cut opens. Writes incision.csv (per\n"
    "step: time, phase, blade tip, blade force, topology version, nodes) and incision.vtk (the body\n"
    "at the end) into the output folder. Exits 1 if the blade did not cut, the force was not finite\n"
    "or did not push back, the cut did not open, or a node moved 3 cm (a piece flew off).\n"
    "  output-folder  where the files go (default .)\n"
    "  --nidus        cut the nidus instead of the cube (run from the repository root)\n"
    "  --help         this text\n";

int main(int argc, char** argv) {
  static const char* const options[] = {"--nidus", NULL};
  const int cli = cli_check(argc, argv, kUsage, options);
  if (cli >= 0) return cli;
  const char* out_dir = ".";
  incision_scene_def def = incision_scene_def_default();
  def.cells = 20; /* 5 mm cells: the cut follows element faces */
  int positional = 0;
  for (int i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--nidus") == 0) {
      def.cells = 0; /* the nidus at def.mesh */
    } else if (positional++ == 0) {
      out_dir = argv[i];
    } else {
      fprintf(stderr, "%s: bad arguments\n\n%s", argv[0], kUsage);
      return 2;
    }
  }
  if (!cli_make_folder(argv[0], out_dir)) return 2;

  incision_scene s;
  if (incision_scene_create(&def, &s) != MICA_OK) {
    fprintf(stderr, "%s\n", s.error);
    return 1;
  }
  mica_world* w = s.press.world;
  printf("incision: %s, %d nodes, %d tets; a blade %.0f mm deep along %.0f mm at %.0f mm/s, %d steps\n",
         def.cells ? "cube" : "nidus", (int)s.press.nodes, (int)s.press.tets, 1e3 * def.depth, 1e3 * def.length,
         1e3 * def.speed, (int)s.steps);
  char path[1024];
  snprintf(path, sizeof path, "%s/incision.csv", out_dir);
  FILE* csv = fopen(path, "w");
  if (!csv) {
    fprintf(stderr, "cannot write %s\n", path);
    incision_scene_destroy(&s);
    return 1;
  }
  fprintf(csv, "t_s,phase,tip_x_m,tip_y_m,tip_z_m,force_x_N,force_y_N,force_z_N,force_along_N,topology_version,nodes\n");
  int ok = 1;
  double largest_push = 0;
  for (int32_t k = 1; k <= s.steps && ok; ++k) {
    if (incision_scene_step(&s, k) < 0) {
      fprintf(stderr, "step %d: %s\n", (int)k, s.error);
      ok = 0;
      break;
    }
    double f[3], along = 0;
    uint64_t version = 0;
    int32_t nodes = 0;
    if (incision_scene_blade_force(&s, f, &along) < 0 || mica_body_get_topology_version(w, s.press.body, &version) < 0 ||
        mica_body_get_counts(w, s.press.body, &nodes, NULL, NULL) < 0) {
      fprintf(stderr, "%s\n", mica_world_last_error(w));
      ok = 0;
      break;
    }
    const char* phase = k <= s.entry_steps ? "entry" : k <= s.entry_steps + s.cut_steps ? "cut" : "hold";
    fprintf(csv, "%.4f,%s,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%llu,%d\n", k * def.dt, phase, s.tip[0], s.tip[1],
            s.tip[2], f[0], f[1], f[2], along, (unsigned long long)version, (int)nodes);
    if (!(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2]))) {
      fprintf(stderr, "check failed: the blade force is not finite at step %d\n", (int)k);
      ok = 0;
    }
    if (along > largest_push) largest_push = along;
  }
  fclose(csv);

  /* The cut opened: the widest gap between a node and its twin (same rest position). */
  int32_t nodes = 0;
  mica_body_get_counts(w, s.press.body, &nodes, NULL, NULL);
  double* rest = malloc(sizeof(double) * 6 * (size_t)nodes);
  double gap = 0, moved = 0;
  if (ok && rest) {
    double* x = rest + 3 * (size_t)nodes;
    mica_body_get_rest_positions(w, s.press.body, rest, nodes, NULL);
    mica_body_get_positions(w, s.press.body, x, nodes, NULL);
    for (int32_t i = 0; i < nodes; ++i) { /* nothing flies off: the farthest any node went */
      const double d[3] = {x[3 * i] - rest[3 * i], x[3 * i + 1] - rest[3 * i + 1], x[3 * i + 2] - rest[3 * i + 2]};
      moved = fmax(moved, sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
    }
    for (int32_t i = s.press.nodes; i < nodes; ++i) /* the copies follow the body's first nodes */
      for (int32_t j = 0; j < s.press.nodes; ++j)
        if (rest[3 * i] == rest[3 * j] && rest[3 * i + 1] == rest[3 * j + 1] && rest[3 * i + 2] == rest[3 * j + 2]) {
          const double d[3] = {x[3 * i] - x[3 * j], x[3 * i + 1] - x[3 * j + 1], x[3 * i + 2] - x[3 * j + 2]};
          gap = fmax(gap, sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
        }
  }
  free(rest);
  snprintf(path, sizeof path, "%s/incision.vtk", out_dir);
  if (ok && mica_body_write_vtk(w, s.press.body, path) < 0) {
    fprintf(stderr, "%s\n", mica_world_last_error(w));
    ok = 0;
  }
  printf("%d node copies made; the blade pushed back up to %.3f N; the cut opened %.1f mm; no node moved more than %.1f mm\n",
         (int)(nodes - s.press.nodes), largest_push, 1e3 * gap, 1e3 * moved);
  printf("CSV %s/incision.csv, the cut body %s\n", out_dir, path);
  incision_scene_destroy(&s);
  if (ok && nodes == s.press.nodes) fprintf(stderr, "check failed: the blade did not cut\n"), ok = 0;
  if (ok && !(largest_push > 0)) fprintf(stderr, "check failed: the tissue never pushed back on the blade\n"), ok = 0;
  if (ok && !(gap > 0.002)) fprintf(stderr, "check failed: the cut opened %.2f mm, less than 2 mm\n", 1e3 * gap), ok = 0;
  if (ok && !(moved < 0.03)) fprintf(stderr, "check failed: a node moved %.1f mm (a piece flew off)\n", 1e3 * moved), ok = 0;
  return ok ? 0 : 1;
}
