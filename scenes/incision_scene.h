/* SPDX-License-Identifier: Apache-2.0 */
/* An incision: a blade cuts a line into a soft body while a hook holds one side and retracts it,
 * and a forceps tip rests beside the cut. The scene of examples_c/incision.c and
 * bench/bench_incision.c, built on press_scene.h (the cube or the nidus, E = 1e4 Pa, nu = 0.4,
 * MICA with the factored sweep; press_scene's sphere is the forceps tip). Plain C99 against the
 * public API only (mica.h).
 *
 * The blade: a capsule of radius 0.25 mm and edge length 3 cm (mica_tool_def.blade), its edge
 * in the x-y plane leaning 45 degrees forward, as a scalpel is held; it cuts along its local x,
 * forward and down. Its tip (the edge's lower end) starts 1 mm above the surface point at the
 * incision's start, goes in forward and down to `depth` below it (the entry), then forward along
 * +x for `length` at `speed`, then stays. The incision line runs along x through the body's top
 * point (press_scene_top), centred on it.
 * The hook (`hook` = 1): a grab of the surface nodes within 4 mm of the point 5 mm to the +z side
 * of the line's middle; once the blade has passed the middle, its handle draws back along +z at
 * 1 cm/s for up to 8 mm, so the cut opens.
 * The forceps (`forceps` = 1): a 4 mm sphere 12 mm to the -z side of the line's middle, its lowest
 * point 1 mm below the surface, held there from the start.
 *
 *   incision_scene_def def = incision_scene_def_default();   // the cube, cut
 *   incision_scene s;
 *   if (incision_scene_create(&def, &s) != MICA_OK) { puts(s.error); ... }
 *   for (int k = 1; k <= s.steps; ++k) incision_scene_step(&s, k);
 *   incision_scene_destroy(&s);
 */
#ifndef MICA_SCENES_INCISION_SCENE_H
#define MICA_SCENES_INCISION_SCENE_H

#include <stdint.h>

#include <mica/mica.h>

#include "press_scene.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct incision_scene_def {
  int32_t cells;              /* the cube, cells per side (> 0); 0: the nidus at `mesh`; default 12 */
  const char* mesh;           /* default "data/nidus/nidus.msh" */
  double length;              /* m, the incision along x after the entry; default 0.03 */
  double depth;               /* m, the blade tip's depth below the surface; default 0.008 */
  double speed;               /* m/s; default 0.01 */
  double dt;                  /* s; default 0.01 */
  double cutting_resistance;  /* N/m of edge; default 40 */
  int32_t blade;              /* 1: the blade cuts; 0: the same capsule on the same path, not a blade */
  int32_t hook;               /* 1: the hook retracts one side; default 1 */
  int32_t forceps;            /* 1: the forceps tip rests beside the cut; default 0 */
  int32_t refactor_interval;  /* mica_world_def.refactor_interval; default 0 */
} incision_scene_def;

typedef struct incision_scene {
  incision_scene_def def;
  press_scene press;          /* its world, body and (as the forceps) tool */
  mica_tool_id blade;
  mica_lpc_id hook;           /* MICA_NULL_ID without the hook */
  double start[3];            /* the surface point the incision starts from */
  double tip[3];              /* where the blade's tip is (end of the last step) */
  double hook_at[3];          /* the hook handle's position */
  int32_t entry_steps;        /* steps 1 .. entry_steps go in */
  int32_t cut_steps;          /* then cut_steps along the line */
  int32_t steps;              /* entry, cut, and a tenth of the cut's steps held */
  char error[512];
} incision_scene;

incision_scene_def incision_scene_def_default(void);

/* Builds the world, body, blade, hook and forceps. On failure returns the status (< 0), leaves
 * nothing allocated and puts the reason into s->error. */
mica_status incision_scene_create(const incision_scene_def* def, incision_scene* s);

/* Moves the blade (and the hook) for the end of step k (1-based) and steps once; returns
 * mica_step's status (s->error says why on failure). */
mica_status incision_scene_step(incision_scene* s, int32_t k);

/* The force the tissue puts on the blade (N) and, in `along`, its part against the blade's cutting
 * direction (its local x): what the hand pushes through. */
mica_status incision_scene_blade_force(const incision_scene* s, double force[3], double* along);

void incision_scene_destroy(incision_scene* s);

#ifdef __cplusplus
}
#endif

#endif
