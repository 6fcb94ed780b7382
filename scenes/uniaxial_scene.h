/* SPDX-License-Identifier: Apache-2.0 */
/* Uniaxial compression of a cube on frictionless ends, and its closed-form answer for the stable
 * neo-Hookean material: the large-strain check that tests/capi/test_neo_hookean.c asserts and
 * that bench/study/study_anchors.c measures for every model, built here once. Plain C99 against
 * the public API only (mica.h).
 *
 * uniaxial_scene_create adds to the world, in this order:
 * - `body`: the cube [0, side]^3, mica_body_create_box(def->body, cells^3, tets_per_cell);
 * - `planes[0..2]`: the nodes of x = 0, y = 0 and z = 0, each sliding in its plane
 *   (MICA_LPC_PLANE): two symmetry planes and the frictionless base;
 * - `plate`: the nodes of the top face z = side, sliding in it (frictionless): moved along z
 *   with mica_lpc_set_velocity, it compresses the cube.
 * The deformation is homogeneous, which linear tets represent exactly: what the body answers
 * differs from the closed form only by the model (and the solver's tolerance).
 *
 *   uniaxial_scene_def def = uniaxial_scene_def_default();    // 0.1 m, 4^3 cells x 6 tets
 *   def.body.model = MICA_MODEL_NEO_HOOKEAN;
 *   uniaxial_scene s;
 *   uniaxial_scene_create(world, &def, &s);
 *   ... move s.plate, step ...
 *   double stretch, lateral, nominal;
 *   uniaxial_scene_measure(world, &s, &stretch, &lateral, &nominal);
 *   double want = uniaxial_neo_hookean_nominal_stress(def.body.youngs_modulus,
 *                                                     def.body.poisson_ratio, stretch, NULL);
 */
#ifndef MICA_SCENES_UNIAXIAL_SCENE_H
#define MICA_SCENES_UNIAXIAL_SCENE_H

#include <stdint.h>

#include <mica/mica.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct uniaxial_scene_def {
  mica_body_def body;    /* the material; default mica_body_def_default() with E = 1e4 Pa, nu = 0.45 */
  double side;           /* m, the cube's edge; default 0.1 */
  int32_t cells;         /* cubes along each axis; default 4 */
  int32_t tets_per_cell; /* 5 or 6; default 6 */
} uniaxial_scene_def;

typedef struct uniaxial_scene {
  mica_body_id body;
  mica_lpc_id planes[3]; /* x = 0, y = 0, z = 0, each sliding in its plane */
  mica_lpc_id plate;     /* the top face, sliding in its plane, moved along z */
  double side;
  int32_t nodes, tets;
} uniaxial_scene;

/* The defaults listed in uniaxial_scene_def. */
uniaxial_scene_def uniaxial_scene_def_default(void);

/* Adds the body, its three planes and the plate to `world`. Returns the first failing call's
 * status (mica_world_last_error says why; what was added before stays in the world). */
mica_status uniaxial_scene_create(mica_world* world, const uniaxial_scene_def* def, uniaxial_scene* s);

/* What the body reached: the axial stretch (the top's height over the side), the lateral stretch
 * (the far side's width over the side) and the nominal stress P_zz (Pa): the plate's reaction
 * over the rest area, negative in compression. */
mica_status uniaxial_scene_measure(mica_world* world, const uniaxial_scene* s, double* stretch, double* lateral,
                                   double* nominal);

/* The closed-form nominal stress P_zz (Pa) of libmica's stable neo-Hookean material of Young's
 * modulus E and Poisson ratio nu (docs/materials.md: mu = mu_L, lambda = lambda_L + mu_L,
 * alpha = 1 + mu / lambda) under uniaxial stress at axial stretch `stretch`: F = diag(t, t, s),
 * J = t^2 s, P = mu F + lambda (J - alpha) cof F; the lateral stretch t (into *lateral, may be
 * NULL) solves P_xx = 0 by a 1D Newton iteration. */
double uniaxial_neo_hookean_nominal_stress(double E, double nu, double stretch, double* lateral);

/* The same for a linear (Hooke) material, which the linear and the co-rotational models are in
 * this test (no rotation): P_zz = E (s - 1), lateral stretch 1 - nu (s - 1). */
double uniaxial_hooke_nominal_stress(double E, double nu, double stretch, double* lateral);

#ifdef __cplusplus
}
#endif

#endif /* MICA_SCENES_UNIAXIAL_SCENE_H */
