/* SPDX-License-Identifier: Apache-2.0 */
/* A sphere pressed into a soft cube and pulled out again (the scene of Figure 1 of
 * Arikatla et al. 2016).
 *
 * A 10 cm cube of soft tissue is fixed at its bottom face (a projection constraint on the
 * nodes of y = 0). A rigid 2 cm sphere, moved by the host every step, comes down at
 * constant speed, indents the top face to 15 mm, holds, goes back up and away. The MICA
 * solver resolves the contact; the force the tissue puts on the sphere is what a haptic
 * device would render.
 *
 * Each step prints time, indentation depth, the vertical tool force (positive: the tissue
 * pushes the sphere up), the active contacts and the MICA iterations, and writes them to
 * <out>/sphere_indent.csv. VTK frames of the cube (sphere_indent_*.vtk) open in ParaView
 * as a time series; the sphere's centre per step is in the CSV (tool_y_m).
 *
 * Gravity is off, so the depth is measured from the undeformed top face and the peak force
 * can be set against the Hertz estimate for a sphere on an elastic half-space,
 * F = 4/3 E/(1 - nu^2) sqrt(R) d^1.5 (for orientation only: the cube is finite, fixed at
 * its bottom, coarsely meshed and indented far beyond d << R).
 *
 * The motion is scaled to the number of steps: loading 1/3 of them, hold 1/6, unloading
 * 1/3, then 1/6 with the sphere clear of the cube. The program checks that the force is
 * finite, pushes the sphere up (never pulls), grows during loading and is zero after
 * release, and exits 1 if not.
 *
 * usage: sphere_indent [output-folder] [steps]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <mica/mica.h>

#include "cli.h"
#include "press_scene.h"

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
    "usage: sphere_indent [output-folder] [steps]\n"
    "A 2 cm sphere pressed 15 mm into a soft 10 cm cube fixed at its bottom, held and pulled out\n"
    "(Figure 1 of Arikatla et al. 2016). Prints time, depth, tool force, contacts and iterations;\n"
    "writes sphere_indent.csv and VTK frames (sphere_indent_*.vtk) into the output folder. Exits 1\n"
    "if the force is not finite, pulls, does not grow while loading or stays after release.\n"
    "  output-folder  where the files go (made if missing; default .)\n"
    "  steps          10 ms steps of the whole press, at least 12 (default 300)\n"
    "  --help         this text\n";

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  const char* out_dir = argc > 1 ? argv[1] : ".";
  int steps = 300;
  if (argc > 2 && !cli_int(argv[0], "steps", argv[2], 12, 1000000, &steps)) return 2;
  if (!cli_make_folder(argv[0], out_dir)) return 1;
  /* The scene, built by scenes/press_scene.c (shared with the benchmarks and the bindings'
   * reference): the cube [-L/2, L/2] x [0, L] x [-L/2, L/2], L = 10 cm, fixed at its bottom face
   * y = 0, and the sphere centred above (0, L, 0), its lowest point start_gap above the top face.
   * MICA with the factored sweep, the sweep a haptic host should use (docs/solvers.md). */
  const press_scene_def def = press_scene_sphere_indent_def();
  const double E = def.youngs_modulus, nu = def.poisson_ratio, rho = def.density, dt = def.dt;
  const double R = def.size, margin = def.margin, start_gap = def.gap, max_depth = def.depth;
  const int cells_per_side = def.cells, vtk_every = 10;
  press_scene scene;
  if (press_scene_create(&def, &scene) != MICA_OK) {
    fprintf(stderr, "%s\n", scene.error);
    return 1;
  }
  mica_world* world = scene.world;
  const mica_tool_id sphere = scene.tool;
  const double L = scene.center[1]; /* the top face */
  const double y_start = scene.y_start;
  const int32_t nodes = scene.nodes, tets = scene.tets;

  /* Trajectory: down over n_load steps, hold, up over n_unload steps, rest. */
  const int n_load = steps / 3, n_hold = steps / 6, n_unload = steps / 3;
  const double travel = start_gap + max_depth, speed = travel / (n_load * dt);
  const double E_star = E / (1 - nu * nu);
  printf("sphere indentation: cube %.2f m (%d^3 cells, %d nodes, %d tets), E = %.3g Pa, nu = %.2f, "
         "rho = %.0f kg/m^3\n",
         L, cells_per_side, nodes, tets, E, nu, rho);
  printf("sphere R = %.3f m, margin %.4f m, speed %.4f m/s to depth %.4f m; dt = %.3f s, %d steps; "
         "MICA tol %.0e, cap %d\n",
         R, margin, speed, max_depth, dt, steps, def.tolerance, def.max_iterations);
  printf("%7s %10s %12s %8s %6s %5s\n", "t (s)", "depth (m)", "force_y (N)", "contacts", "iters", "conv");

  char path[1024];
  snprintf(path, sizeof path, "%s/sphere_indent.csv", out_dir);
  FILE* csv = fopen(path, "w");
  if (!csv) {
    fprintf(stderr, "cannot write %s\n", path);
    return 1;
  }
  fprintf(csv, "t_s,phase,tool_y_m,depth_m,force_x_N,force_y_N,force_z_N,contacts,iterations,converged\n");

  double peak_force = 0, peak_depth = 0, last_load_force = 0;
  int bad_finite = 0, bad_sign = 0, not_growing = 0, not_released = 0, not_converged = 0;
  for (int k = 0; k <= steps; ++k) {
    /* Tool height for the end of step k. */
    double y;
    const char* phase;
    if (k <= n_load) {
      y = y_start - speed * k * dt;
      phase = "load";
    } else if (k <= n_load + n_hold) {
      y = y_start - travel;
      phase = "hold";
    } else if (k <= n_load + n_hold + n_unload) {
      y = y_start - travel + speed * (k - n_load - n_hold) * dt;
      phase = "unload";
    } else {
      y = y_start;
      phase = "clear";
    }
    const double pos[3] = {0, y, 0};
    double force[3] = {0, 0, 0};
    int32_t contacts = 0;
    mica_world_stats stats = {.struct_size = sizeof stats};
    if (k > 0) {
      CHECK(mica_tool_set_pose(world, sphere, pos, scene.orientation));
      const mica_status s = mica_step(world, dt);
      CHECK(s);
      CHECK(mica_tool_get_force(world, sphere, force, NULL, &contacts));
      CHECK(mica_world_get_stats(world, &stats));
      if (s == MICA_WARN_NOT_CONVERGED) ++not_converged;
    } else {
      stats.converged = 1;
    }
    const double depth = L - (y - R); /* > 0: below the undeformed top face */
    const double fy = force[1];
    fprintf(csv, "%.4f,%s,%.9g,%.9g,%.9g,%.9g,%.9g,%d,%d,%d\n", k * dt, phase, y, depth, force[0], fy, force[2],
            contacts, stats.solver_iterations, stats.converged);
    printf("%7.2f %10.5f %12.5f %8d %6d %5d  %s\n", k * dt, depth, fy, contacts, stats.solver_iterations,
           stats.converged, phase);

    if (!isfinite(force[0]) || !isfinite(fy) || !isfinite(force[2])) ++bad_finite;
    if (fy < -1e-9) ++bad_sign;
    if (fy > peak_force) {
      peak_force = fy;
      peak_depth = depth;
    }
    /* While the sphere goes deeper (after first touch) the force must not drop by more than 1 %. */
    if (k <= n_load && depth > 0.002) {
      if (fy < 0.99 * last_load_force) ++not_growing;
      last_load_force = fy;
    }
    if (k > n_load + n_hold + n_unload && (fabs(fy) > 1e-6 || contacts != 0)) ++not_released;

    if (k % vtk_every == 0) {
      snprintf(path, sizeof path, "%s/sphere_indent_%04d.vtk", out_dir, k / vtk_every);
      CHECK(mica_world_write_vtk(world, path));
    }
  }
  fclose(csv);

  const double hertz = 4.0 / 3.0 * E_star * sqrt(R) * pow(peak_depth, 1.5);
  mica_world_stats stats = {.struct_size = sizeof stats};
  CHECK(mica_world_get_stats(world, &stats));
  printf("peak force %.4f N at depth %.4f m; Hertz half-space estimate there "
         "4/3 E/(1-nu^2) sqrt(R) d^1.5 = %.4f N (ratio %.2f)\n",
         peak_force, peak_depth, hertz, hertz > 0 ? peak_force / hertz : 0.0);
  printf("mean %.3f ms per step over %lld steps; %d steps stopped at the iteration cap\n",
         stats.stages[MICA_STAGE_SOLVE].ms_total / (double)stats.step_count, (long long)stats.step_count,
         not_converged);
  printf("CSV %s/sphere_indent.csv, VTK frames %s/sphere_indent_*.vtk (every %d steps)\n", out_dir, out_dir,
         vtk_every);
  press_scene_destroy(&scene);

  int failed = 0;
  if (bad_finite) { fprintf(stderr, "check failed: %d steps with a non-finite force\n", bad_finite); failed = 1; }
  if (bad_sign) { fprintf(stderr, "check failed: %d steps where the tissue pulls the sphere down\n", bad_sign); failed = 1; }
  if (not_growing) { fprintf(stderr, "check failed: the force dropped in %d loading steps\n", not_growing); failed = 1; }
  if (not_released) { fprintf(stderr, "check failed: %d steps with force or contacts after release\n", not_released); failed = 1; }
  if (!(peak_force > 0)) { fprintf(stderr, "check failed: no indentation force at all\n"); failed = 1; }
  return failed;
}
