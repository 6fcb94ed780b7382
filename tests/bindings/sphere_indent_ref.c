/* SPDX-License-Identifier: Apache-2.0 */
/* The reference for the binding tests: the scene of examples_c/sphere_indent.c (same parameters,
 * same operations in the same order), printing the tool force of every step at full precision.
 * Each binding replays the scene and compares its forces with this output.
 *
 * usage: sphere_indent_ref [steps] [out.csv]     (default: 30 steps, to standard output)
 * output: one line per step k = 1..steps: "k,force_x,force_y,force_z,contacts" (N, %.17g)
 */
#include <stdio.h>
#include <stdlib.h>

#include <mica/mica.h>

#define CHECK(call)                                                                              \
  do {                                                                                           \
    mica_status s_ = (call);                                                                     \
    if (s_ < 0) {                                                                                \
      fprintf(stderr, "%s failed: %s\n  %s\n", #call, mica_status_string(s_), mica_world_last_error(world)); \
      return 1;                                                                                  \
    }                                                                                            \
  } while (0)

int main(int argc, char** argv) {
  const int steps = argc > 1 ? atoi(argv[1]) : 30;
  if (steps < 12) {
    fprintf(stderr, "usage: sphere_indent_ref [steps >= 12] [out.csv]\n");
    return 1;
  }
  FILE* out = argc > 2 ? fopen(argv[2], "w") : stdout;
  if (!out) {
    fprintf(stderr, "cannot write %s\n", argv[2]);
    return 1;
  }
  const double L = 0.1, E = 1e4, nu = 0.4, rho = 1000.0, dt = 0.01;
  const double R = 0.02, margin = 0.0015, start_gap = 0.005, max_depth = 0.015;
  const int cells_per_side = 12;
  mica_world* world = NULL;

  mica_world_def wdef = mica_world_def_default();
  wdef.gravity[0] = wdef.gravity[1] = wdef.gravity[2] = 0;
  wdef.solver = MICA_SOLVER_MICA;
  wdef.max_iterations = 2000;
  wdef.tolerance = 1e-6;
  if (mica_world_create(&wdef, &world) != MICA_OK) {
    fprintf(stderr, "mica_world_create: %s\n", mica_world_last_error(NULL));
    return 1;
  }

  mica_body_def bdef = mica_body_def_default();
  bdef.youngs_modulus = E;
  bdef.poisson_ratio = nu;
  bdef.density = rho;
  bdef.rayleigh_alpha = 2.0;
  bdef.rayleigh_beta = 0.005;
  const double lo[3] = {-L / 2, 0, -L / 2}, hi[3] = {L / 2, L, L / 2};
  const int32_t cells[3] = {cells_per_side, cells_per_side, cells_per_side};
  mica_body_id cube;
  CHECK(mica_body_create_box(world, &bdef, lo, hi, cells, 5, &cube));

  const double origin[3] = {0, 0, 0}, up[3] = {0, 1, 0};
  int32_t count = 0;
  CHECK(mica_body_select_nodes_by_plane(world, cube, origin, up, 1e-9, 1, NULL, 0, &count));
  int32_t* bottom = malloc(sizeof(int32_t) * (size_t)count);
  if (!bottom) return 1;
  CHECK(mica_body_select_nodes_by_plane(world, cube, origin, up, 1e-9, 1, bottom, count, &count));
  mica_lpc_def fixed = mica_lpc_def_default();
  fixed.kind = MICA_LPC_FIXED;
  mica_lpc_id base;
  CHECK(mica_add_lpc(world, cube, bottom, count, &fixed, &base));
  free(bottom);

  const double identity[4] = {1, 0, 0, 0};
  const double y_start = L + R + start_gap;
  mica_tool_def tdef = mica_tool_def_default();
  tdef.shape = MICA_TOOL_SPHERE;
  tdef.radius = R;
  tdef.margin = margin;
  tdef.position[0] = 0;
  tdef.position[1] = y_start;
  tdef.position[2] = 0;
  mica_tool_id sphere;
  CHECK(mica_tool_create(world, &tdef, &sphere));

  const int n_load = steps / 3, n_hold = steps / 6, n_unload = steps / 3;
  const double travel = start_gap + max_depth, speed = travel / (n_load * dt);
  for (int k = 1; k <= steps; ++k) {
    double y;
    if (k <= n_load)
      y = y_start - speed * k * dt;
    else if (k <= n_load + n_hold)
      y = y_start - travel;
    else if (k <= n_load + n_hold + n_unload)
      y = y_start - travel + speed * (k - n_load - n_hold) * dt;
    else
      y = y_start;
    const double pos[3] = {0, y, 0};
    double force[3] = {0, 0, 0};
    int32_t contacts = 0;
    CHECK(mica_tool_set_pose(world, sphere, pos, identity));
    CHECK(mica_step(world, dt));
    CHECK(mica_tool_get_force(world, sphere, force, NULL, &contacts));
    fprintf(out, "%d,%.17g,%.17g,%.17g,%d\n", k, force[0], force[1], force[2], contacts);
  }
  mica_world_destroy(world);
  return fclose(out) == 0 ? 0 : 1;
}
