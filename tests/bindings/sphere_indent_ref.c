/* SPDX-License-Identifier: Apache-2.0 */
/* The reference for the binding tests: the scene of examples_c/sphere_indent.c (same parameters
 * and solver, the same operations in the same order), printing the tool force of every step at
 * full precision.
 * Each binding replays the scene and compares its forces with this output.
 *
 * usage: sphere_indent_ref [steps] [out.csv]     (default: 30 steps, to standard output)
 * output: one line per step k = 1..steps: "k,force_x,force_y,force_z,contacts" (N, %.17g)
 */
#include <stdio.h>
#include <stdlib.h>

#include <mica/mica.h>

#include "press_scene.h"

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
  /* The scene of examples_c/sphere_indent.c, built by the same code (scenes/press_scene.c), with
   * MICA's factored sweep (mica_world_def's default, which the bindings replay). */
  const press_scene_def def = press_scene_sphere_indent_def();
  const double dt = def.dt, start_gap = def.gap, max_depth = def.depth;
  press_scene scene;
  if (press_scene_create(&def, &scene) != MICA_OK) {
    fprintf(stderr, "%s\n", scene.error);
    return 1;
  }
  mica_world* world = scene.world;
  const mica_tool_id sphere = scene.tool;
  const double y_start = scene.y_start;

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
    CHECK(mica_tool_set_pose(world, sphere, pos, scene.orientation));
    CHECK(mica_step(world, dt));
    CHECK(mica_tool_get_force(world, sphere, force, NULL, &contacts));
    fprintf(out, "%d,%.17g,%.17g,%.17g,%d\n", k, force[0], force[1], force[2], contacts);
  }
  press_scene_destroy(&scene);
  return fclose(out) == 0 ? 0 : 1;
}
