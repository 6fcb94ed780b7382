/* SPDX-License-Identifier: Apache-2.0 */
/* The nidus (data/nidus/nidus.msh, a 44 x 25 x 18 mm lesion-like blob of 9.7k tets held by its
 * lowest fifth) pressed by a forceps tip, a 4 mm sphere, from 0.5 mm above its top down to `depth`
 * below it over two thirds of the steps, then held (scenes/press_scene.h, the nidus mode; MICA with
 * the factored sweep at tolerance 1e-6, dt = 10 ms).
 *
 * Each step goes to <out>/nidus_press.csv (time, phase, the sphere's centre, its depth below the
 * undeformed surface, the force the tissue puts on it, the active contacts). At the last step the
 * body is written as <out>/nidus_press.vtk: its deformed nodes, tets and each tet's von Mises
 * stress (mica_body_write_vtk), what scripts/plot_tissue.py draws. The program checks that the
 * force is finite, pushes the sphere up at the end and that the surface under the sphere went
 * down by at least a quarter of the sphere's depth (less than all of it: the contact acts within
 * the tool's 1.5 mm margin, and the tissue also gives way sideways), and exits 1 if not.
 *
 * usage: nidus_press [output-folder] [mesh] [steps] [depth-mm]; defaults . data/nidus/nidus.msh 60 4
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <mica/mica.h>

#include "cli.h"
#include "press_scene.h"

static const char kUsage[] =
    "usage: nidus_press [output-folder] [mesh] [steps] [depth-mm]\n"
    "The nidus held by its lowest fifth, pressed by a 4 mm sphere (a forceps tip) from 0.5 mm above\n"
    "its top down to depth-mm below it over two thirds of the steps (10 ms each), then held. Writes\n"
    "nidus_press.csv (per step: time, phase, sphere centre, depth, force, contacts) and, at the last\n"
    "step, nidus_press.vtk (the deformed body with each tet's von Mises stress) into the output\n"
    "folder. Exits 1 if the force is not finite or does not push the sphere up at the end, or if the\n"
    "surface under the sphere did not go down by a quarter of the sphere's depth.\n"
    "  output-folder  where the files go (default .)\n"
    "  mesh           the nidus mesh (default data/nidus/nidus.msh, from the repository root)\n"
    "  steps          steps of the whole press, >= 3 (default 60)\n"
    "  depth-mm       final depth of the sphere's lowest point below the surface, in (0, 8] (default 4)\n"
    "  --help         this text\n";

#define CHECK(call)                                                                                \
  do {                                                                                             \
    const mica_status s_ = (call);                                                                 \
    if (s_ < 0) {                                                                                  \
      fprintf(stderr, "%s failed: %s\n  %s\n", #call, mica_status_string(s_), mica_world_last_error(s.world)); \
      press_scene_destroy(&s);                                                                     \
      return 1;                                                                                    \
    }                                                                                              \
  } while (0)

/* A whole number or a finite number from the command line; 0 if `text` is not all of one. */
static int parse_int(const char* text, long* out) {
  char* end;
  errno = 0;
  *out = strtol(text, &end, 10);
  return errno == 0 && end != text && *end == 0;
}

static int parse_double(const char* text, double* out) {
  char* end;
  errno = 0;
  *out = strtod(text, &end);
  return errno == 0 && end != text && *end == 0 && isfinite(*out);
}

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  const char* out_dir = argc > 1 ? argv[1] : ".";
  const char* mesh = argc > 2 ? argv[2] : "data/nidus/nidus.msh";
  long steps = 60;
  double depth_mm = 4;
  if (argc > 5 || (argc > 3 && (!parse_int(argv[3], &steps) || steps < 3 || steps > 100000)) ||
      (argc > 4 && (!parse_double(argv[4], &depth_mm) || depth_mm <= 0 || depth_mm > 8))) {
    fprintf(stderr, "%s: bad arguments\n\n%s", argv[0], kUsage);
    return 2;
  }

  const double dt = 0.01;
  press_scene_def def = press_scene_nidus_touch_def(mesh, dt * (double)(2 * steps / 3), dt * (double)(steps - 2 * steps / 3));
  def.depth = 1e-3 * depth_mm;
  press_scene s;
  if (press_scene_create(&def, &s) != MICA_OK) {
    fprintf(stderr, "%s\n", s.error);
    return 1;
  }
  printf("nidus: %d nodes, %d tets; a %.0f mm sphere to %.1f mm deep over (%.1f, %.1f, %.1f) mm in %d steps\n",
         (int)s.nodes, (int)s.tets, 1e3 * def.size, depth_mm, 1e3 * s.center[0], 1e3 * s.center[1],
         1e3 * s.center[2], (int)s.steps);

  /* The surface node nearest the point the sphere comes down on: it must go down. */
  double* x = malloc(sizeof(double) * 3 * (size_t)s.nodes);
  if (!x) {
    press_scene_destroy(&s);
    return 1;
  }
  CHECK(mica_body_get_rest_positions(s.world, s.body, x, s.nodes, NULL));
  int32_t under = 0;
  double best = HUGE_VAL;
  for (int32_t i = 0; i < s.nodes; ++i) {
    const double d[3] = {x[3 * i] - s.center[0], x[3 * i + 1] - s.center[1], x[3 * i + 2] - s.center[2]};
    const double r = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
    if (r < best) best = r, under = i;
  }
  const double rest_y = x[3 * under + 1];

  char path[1024];
  snprintf(path, sizeof path, "%s/nidus_press.csv", out_dir);
  FILE* csv = fopen(path, "w");
  if (!csv) {
    fprintf(stderr, "cannot write %s\n", path);
    free(x);
    press_scene_destroy(&s);
    return 1;
  }
  fprintf(csv, "t_s,phase,tool_x_m,tool_y_m,tool_z_m,tool_radius_m,depth_m,force_x_N,force_y_N,force_z_N,contacts\n");
  double force[3] = {0, 0, 0};
  for (int32_t k = 1; k <= s.steps; ++k) {
    int32_t contacts = 0;
    const mica_status status = press_scene_step(&s, k, force, &contacts);
    if (status < 0) {
      fprintf(stderr, "step %d: %s\n", (int)k, s.error);
      fclose(csv);
      free(x);
      press_scene_destroy(&s);
      return 1;
    }
    double p[3], q[4];
    CHECK(mica_tool_get_pose(s.world, s.tool, p, q));
    fprintf(csv, "%.4f,%s,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d\n", k * dt, k <= s.load_steps ? "load" : "hold",
            p[0], p[1], p[2], def.size, press_scene_depth(&s, k), force[0], force[1], force[2], (int)contacts);
  }
  fclose(csv);
  snprintf(path, sizeof path, "%s/nidus_press.vtk", out_dir);
  CHECK(mica_body_write_vtk(s.world, s.body, path));
  CHECK(mica_body_get_positions(s.world, s.body, x, s.nodes, NULL));
  const double sink = rest_y - x[3 * under + 1];
  printf("at %.1f mm deep: force (%.4f, %.4f, %.4f) N; the surface under the sphere %.2f mm down\n",
         1e3 * press_scene_depth(&s, s.steps), force[0], force[1], force[2], 1e3 * sink);
  printf("CSV %s/nidus_press.csv, the deformed body %s\n", out_dir, path);
  free(x);
  press_scene_destroy(&s);

  const int finite = isfinite(force[0]) && isfinite(force[1]) && isfinite(force[2]);
  if (!finite || !(force[1] > 0)) fprintf(stderr, "check failed: the force at the end does not push the sphere up\n");
  if (!(sink > 0.25 * depth_mm * 1e-3))
    fprintf(stderr, "check failed: the surface under the sphere went %.3g mm down, the sphere %.3g mm\n", 1e3 * sink,
            depth_mm);
  return finite && force[1] > 0 && sink > 0.25 * depth_mm * 1e-3 ? 0 : 1;
}
