/* SPDX-License-Identifier: Apache-2.0 */
/* A box body fixed at its base, a grasp dragging one face, and a sphere over it: the scene the
 * examples, benchmarks and study press into (examples_c/convergence_vs_stiffness.c,
 * examples_c/haptic_loop.c, bench/bench_servo.c, bench/bench_solvers.c, bench_nidus --scaling,
 * bench/study/study_sweep.c and study_filter.c), built here once. Each program keeps its own world
 * (solver, tolerance, gravity) and moves the tool itself. Plain C99 against the public API only
 * (mica.h).
 *
 * box_scene_create adds to the world, in this order:
 * - `body`: mica_body_create_box(def->body, lo, hi, cells, tets_per_cell);
 * - `base`: the nodes of the face y = lo[1], fixed;
 * - `drag` (when drag_velocity is not zero): the nodes of the face x = hi[0], moved at drag_velocity;
 * - `tool` (when tool_radius > 0): a sphere of tool_radius and tool_margin at tool_position.
 *
 *   box_scene_def def = box_scene_def_default();   // [0, 0.1]^3, 8^3 cells x 6 tets, 2 cm sphere
 *   def.body.youngs_modulus = 2e4;
 *   box_scene s;
 *   if (box_scene_create(world, &def, &s) != MICA_OK) puts(mica_world_last_error(world));
 */
#ifndef MICA_SCENES_BOX_SCENE_H
#define MICA_SCENES_BOX_SCENE_H

#include <stdint.h>

#include <mica/mica.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct box_scene_def {
  mica_body_def body;      /* the material; default mica_body_def_default() */
  double lo[3], hi[3];     /* m, the box; default [0, 0.1]^3 */
  int32_t cells[3];        /* cubes along x, y, z; default 8 each */
  int32_t tets_per_cell;   /* 5 or 6; default 6 */
  double drag_velocity[3]; /* m/s of the face x = hi[0]; default zero: no drag */
  double tool_radius;      /* m, the sphere; default 0.02; 0: no tool */
  double tool_margin;      /* m, its contact margin; default mica_tool_def_default()'s */
  double tool_position[3]; /* m, its centre; default the origin */
} box_scene_def;

typedef struct box_scene {
  mica_body_id body;
  mica_lpc_id base;
  mica_lpc_id drag;        /* MICA_NULL_ID without a drag */
  mica_tool_id tool;       /* MICA_NULL_ID without a tool */
  int32_t nodes, tets;
} box_scene;

/* The defaults listed in box_scene_def. */
box_scene_def box_scene_def_default(void);

/* The soft block of the haptic programs (examples_c/haptic_loop.c, bench/bench_servo.c,
 * bench/study/study_filter.c): the defaults but the box [-0.05, 0.05] x [-0.1, 0] x [-0.05, 0.05]
 * (its top face at y = 0) and the sphere at (0, 0.05, 0). */
box_scene_def box_scene_block_def(void);

/* Adds the body, its base, the drag and the tool to `world`. Returns the first failing call's
 * status (mica_world_last_error says why; what was added before stays in the world). */
mica_status box_scene_create(mica_world* world, const box_scene_def* def, box_scene* s);

#ifdef __cplusplus
}
#endif

#endif /* MICA_SCENES_BOX_SCENE_H */
