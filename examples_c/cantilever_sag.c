/* SPDX-License-Identifier: Apache-2.0 */
/* A soft block fixed at one end sags under gravity.
 *
 * Prints the tip deflection over time against the static Euler-Bernoulli estimate for a
 * cantilever under its own weight, w = q L^4 / (8 E I), and writes VTK frames that ParaView
 * opens (a series: File > Open > cantilever_*.vtk).
 *
 * usage: cantilever_sag [output-folder] [steps]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <mica/mica.h>

#include "cli.h"
#include "node_selection.h"

#define CHECK(call)                                                                       \
  do {                                                                                    \
    mica_status s_ = (call);                                                              \
    if (s_ < 0) {                                                                         \
      fprintf(stderr, "%s failed: %s\n  %s\n", #call, mica_status_string(s_),             \
              mica_world_last_error(world));                                              \
      return 1;                                                                           \
    }                                                                                     \
  } while (0)

static const char kUsage[] =
    "usage: cantilever_sag [output-folder] [steps]\n"
    "A 1 m x 0.1 m x 0.1 m block (E = 3e7 Pa), clamped at x = 0, sags under gravity in the default\n"
    "world; prints the tip deflection against the Euler-Bernoulli estimate w = q L^4 / (8 E I) and\n"
    "writes cantilever.csv and VTK frames (cantilever_*.vtk) into the output folder.\n"
    "  output-folder  where the files go (made if missing; default .)\n"
    "  steps          5 ms steps (default 200)\n"
    "  --help         this text\n";

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  const char* out_dir = argc > 1 ? argv[1] : ".";
  int steps = 200;
  if (argc > 2 && !cli_int(argv[0], "steps", argv[2], 1, 1000000, &steps)) return 2;
  if (!cli_make_folder(argv[0], out_dir)) return 1;
  const double L = 1.0, H = 0.1, E = 3e7, nu = 0.3, rho = 1000.0, g = 9.81, dt = 0.005;
  mica_world* world = NULL;

  mica_world_def wdef = mica_world_def_default();
  wdef.gravity[0] = 0; wdef.gravity[1] = 0; wdef.gravity[2] = -g;
  if (mica_world_create(&wdef, &world) != MICA_OK) {
    fprintf(stderr, "mica_world_create: %s\n", mica_world_last_error(NULL));
    return 1;
  }

  mica_body_def bdef = mica_body_def_default();
  bdef.youngs_modulus = E;
  bdef.poisson_ratio = nu;
  bdef.density = rho;
  bdef.rayleigh_alpha = 4.0; /* 1/s: settles the sag within a second or two */
  const double lo[3] = {0, 0, 0}, hi[3] = {L, H, H};
  const int32_t cells[3] = {60, 6, 6};
  mica_body_id beam;
  CHECK(mica_body_create_box(world, &bdef, lo, hi, cells, 5, &beam));

  /* Clamp the face x = 0. */
  const double origin[3] = {0, 0, 0}, normal[3] = {1, 0, 0};
  mica_lpc_id clamp;
  CHECK(scene_fix_plane(world, beam, origin, normal, 1e-9, NULL, &clamp)); /* scenes/node_selection.h */

  /* The tip: nodes on the face x = L. */
  const double tip_point[3] = {L, 0, 0}, tip_normal[3] = {-1, 0, 0};
  int32_t tip_count = 0;
  int32_t* tip = scene_select_plane(world, beam, tip_point, tip_normal, 1e-9, &tip_count);
  if (!tip || tip_count == 0) {
    fprintf(stderr, "no node on the face x = L\n");
    return 1;
  }

  int32_t nodes = 0;
  CHECK(mica_body_get_counts(world, beam, &nodes, NULL, NULL));
  double* x = malloc(sizeof(double) * 3 * (size_t)nodes);
  double* x0 = malloc(sizeof(double) * 3 * (size_t)nodes);
  CHECK(mica_body_get_rest_positions(world, beam, x0, nodes, NULL));

  const double I = H * H * H * H / 12.0, q = rho * g * H * H;
  const double w_beam = q * L * L * L * L / (8.0 * E * I);
  printf("cantilever %.2f x %.2f x %.2f m, E = %.3g Pa, nu = %.2f, rho = %.0f kg/m^3, dt = %.3f s\n", L, H, H, E,
         nu, rho, dt);
  printf("static Euler-Bernoulli tip deflection under own weight: %.5f m\n", w_beam);
  printf("%8s %12s %10s\n", "t (s)", "tip w (m)", "w / w_EB");

  char path[1024];
  snprintf(path, sizeof path, "%s/cantilever.csv", out_dir);
  FILE* csv = fopen(path, "w");
  if (!csv) {
    fprintf(stderr, "cannot write %s\n", path);
    return 1;
  }
  fprintf(csv, "t_s,tip_deflection_m,euler_bernoulli_m\n");
  double w = 0;
  for (int k = 0; k <= steps; ++k) {
    if (k > 0) CHECK(mica_step(world, dt));
    CHECK(mica_body_get_positions(world, beam, x, nodes, NULL));
    w = 0;
    for (int32_t t = 0; t < tip_count; ++t) w += x0[3 * tip[t] + 2] - x[3 * tip[t] + 2];
    w /= tip_count;
    fprintf(csv, "%.6f,%.9g,%.9g\n", k * dt, w, w_beam);
    if (k % 20 == 0) {
      printf("%8.2f %12.5f %10.3f\n", k * dt, w, w / w_beam);
      snprintf(path, sizeof path, "%s/cantilever_%04d.vtk", out_dir, k / 20);
      CHECK(mica_body_write_vtk(world, beam, path));
    }
  }
  fclose(csv);
  mica_world_stats stats = {.struct_size = sizeof stats};
  CHECK(mica_world_get_stats(world, &stats));
  printf("final tip deflection %.5f m = %.3f x Euler-Bernoulli; %.3f ms per step (last)\n", w, w / w_beam,
         stats.ms_last_step);
  printf("time per stage over %lld steps (ms per step):", (long long)stats.step_count);
  for (int k = 0; k < MICA_STAGE_COUNT; ++k)
    if (stats.stages[k].runs_total > 0)
      printf(" %s %.3f", mica_stage_name(k), stats.stages[k].ms_total / (double)stats.step_count);
  printf("\n");
  printf("VTK frames written to %s/cantilever_*.vtk\n", out_dir);
  free(x);
  free(x0);
  free(tip);
  mica_world_destroy(world);
  return 0;
}
