/* SPDX-License-Identifier: Apache-2.0 */
/* A tool pressed into a soft body and held: the scene of the force-quality benchmark
 * (bench/bench_contact.c), of examples_c/sphere_indent.c and of the bindings' reference run
 * (tests/bindings/sphere_indent_ref.c), which build it here and move the tool themselves
 * (mica_tool_set_pose on s.tool). Plain C99 against the public API only (mica.h).
 *
 * Two bodies:
 * - a box body (cells > 0): the cube of examples_c/sphere_indent.c, [-L/2, L/2] x [0, L] x
 *   [-L/2, L/2] with L = 10 cm, cells^3 cubes x 5 tets, fixed at its bottom face (y = 0); the
 *   tool comes down over (0, L, 0);
 * - the nidus (cells == 0): the mesh at `mesh` (data/nidus/nidus.msh), held by its lowest
 *   fifth as in bench/bench_nidus.c; the tool comes down over the centroid, onto the highest
 *   surface point above it.
 * Material E = 1e4 Pa, nu = 0.4, rho = 1000, co-rotational, consistent mass, Rayleigh alpha =
 * 2/s and beta = 0 unless changed; no gravity (the depth is then measured from the undeformed
 * surface).
 *
 * The tool: MICA_TOOL_SPHERE (radius `size`), MICA_TOOL_CAPSULE (radius size/2, half-length
 * `size`, its axis along world x: local z turned onto x), MICA_TOOL_BOX (half-extents `size`
 * each, faces along the axes) or MICA_TOOL_HULL (a frustum-like hull of 8 points, of height
 * 1.5 `size`, its irregular bottom quadrilateral turned against the grid; see press_scene.c).
 * Its lowest point starts `gap` above the surface, goes down at constant speed to `depth`
 * below it in `load_time`, and stays there for `hold_time`.
 *
 *   press_scene_def def = press_scene_def_default();   // sphere, 12 cells, 10 ms, exact
 *   def.shape = MICA_TOOL_BOX; def.solver = MICA_SOLVER_MICA; def.sweep = MICA_SWEEP_FACTORED;
 *   press_scene s;
 *   if (press_scene_create(&def, &s) != MICA_OK) { puts(s.error); ... }
 *   for (int k = 1; k <= s.steps; ++k) { double f[3]; press_scene_step(&s, k, f); ... }
 *   press_scene_destroy(&s);
 */
#ifndef MICA_SCENES_PRESS_SCENE_H
#define MICA_SCENES_PRESS_SCENE_H

#include <stddef.h>
#include <stdint.h>

#include <mica/mica.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct press_scene_def {
  int32_t shape;          /* MICA_TOOL_SPHERE, _CAPSULE, _BOX or _HULL; default sphere */
  int32_t cells;          /* box body: cells per side (> 0); 0: the nidus mesh; default 12 */
  const char* mesh;       /* the nidus mesh (cells == 0); default "data/nidus/nidus.msh" */
  double dt;              /* s; default 0.01 */
  int32_t solver;         /* MICA_SOLVER_*; default MICA_SOLVER_DIRECT (exact) */
  int32_t sweep;          /* MICA_SWEEP_* for MICA; default MICA_SWEEP_FACTORED */
  double tolerance;       /* iterative solvers; default 1e-8 */
  int32_t max_iterations; /* iterative solvers; default 20000 */
  double size;            /* m, the tool's size (see above); default 0.02 */
  double margin;          /* m, the tool's contact margin; default 0.0015 */
  double gap;             /* m, start height of the tool's lowest point over the surface; default 0.005 */
  double depth;           /* m, final depth of the tool's lowest point below the surface; default 0.01 */
  double load_time;       /* s, from the start to full depth at constant speed; default 1 */
  double hold_time;       /* s, held still at full depth; default 1 */
  double youngs_modulus;  /* Pa; default 1e4 */
  double poisson_ratio;   /* default 0.4 */
  double density;         /* kg/m^3; default 1000 */
  double rayleigh_alpha;  /* 1/s; default 2 */
  double rayleigh_beta;   /* s; default 0 */
  int32_t refactor_interval; /* MICA, factored sweep: refresh the factor every this many steps in
                                the background (mica_world_def.refactor_interval); default 0 */
} press_scene_def;

typedef struct press_scene {
  press_scene_def def;
  mica_world* world;
  mica_body_id body;
  mica_tool_id tool;
  int32_t nodes, tets;
  double center[3];       /* the point of the surface under the tool (undeformed) */
  double lowest;          /* m, the tool's lowest point below its origin (in its pose) */
  double y_start;         /* tool origin height at the start */
  double orientation[4];  /* the tool's fixed orientation (w, x, y, z) */
  int32_t load_steps;     /* steps 1 .. load_steps move down; */
  int32_t steps;          /* load_steps + hold steps */
  char error[512];        /* why press_scene_create or press_scene_step failed */
} press_scene;

/* The defaults listed in press_scene_def. */
press_scene_def press_scene_def_default(void);

/* The scene of examples_c/sphere_indent.c (Figure 1 of Arikatla et al. 2016): the defaults but
 * a 15 mm deep press (the example also lifts the sphere out again), Rayleigh beta = 0.005 s, and
 * MICA with the factored sweep at tolerance 1e-6, cap 2000. */
press_scene_def press_scene_sphere_indent_def(void);

/* The nidus at `mesh` touched by a 4 mm sphere: from 0.5 mm above down to 3 mm deep in `load_time`,
 * held for `hold_time`; MICA with the factored sweep at tolerance 1e-6 (the scene of
 * bench/bench_embedding.c and of the embedded-mesh tests). */
press_scene_def press_scene_nidus_touch_def(const char* mesh, double load_time, double hold_time);

/* Builds the world, body, fixation and tool. On failure returns the status (< 0), leaves
 * nothing allocated and puts the reason into s->error. */
mica_status press_scene_create(const press_scene_def* def, press_scene* s);

/* Depth (m) of the tool's lowest point below the undeformed surface at the end of step k
 * (k = 0: the start; negative while above). */
double press_scene_depth(const press_scene* s, int32_t k);

/* Sets the tool's pose for the end of step k (1-based), steps once, and returns mica_step's
 * status; `force` (may be NULL) receives the force the body puts on the tool (N), `contacts`
 * (may be NULL) the active contacts. On an error s->error says why. */
mica_status press_scene_step(press_scene* s, int32_t k, double force[3], int32_t* contacts);

void press_scene_destroy(press_scene* s);

/* Where a tool comes down onto `body` (the nidus of press_scene_create, bench/bench_nidus.c): its
 * rest bounds `lo`, `hi`, and in `top` the centroid of its rest nodes lifted onto its surface (the
 * highest crossing of the vertical line through the centroid with a surface triangle). Returns
 * MICA_ERR_INVALID_ARGUMENT when no surface lies above the centroid, MICA_ERR_OUT_OF_MEMORY, or
 * a failed getter's status. */
mica_status press_scene_top(mica_world* world, mica_body_id body, double lo[3], double hi[3], double top[3]);

/* "sphere", "capsule", "box", "hull" (or "?"). */
const char* press_scene_shape_name(int32_t shape);

#ifdef __cplusplus
}
#endif

#endif /* MICA_SCENES_PRESS_SCENE_H */
