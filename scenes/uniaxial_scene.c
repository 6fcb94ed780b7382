/* SPDX-License-Identifier: Apache-2.0 */
/* Uniaxial compression of a cube on frictionless ends: see uniaxial_scene.h. */
#include "uniaxial_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "node_selection.h"

uniaxial_scene_def uniaxial_scene_def_default(void) {
  uniaxial_scene_def d;
  memset(&d, 0, sizeof d);
  d.body = mica_body_def_default();
  d.body.youngs_modulus = 1e4;
  d.body.poisson_ratio = 0.45;
  d.side = 0.1;
  d.cells = 4;
  d.tets_per_cell = 6;
  return d;
}

/* The nodes with (p - point) . normal <= 0, sliding in the plane of the axis |normal|. */
static mica_status add_plane(mica_world* world, mica_body_id body, const double point[3], const double normal[3],
                             mica_lpc_id* out) {
  int32_t n = 0;
  int32_t* nodes = scene_select_plane(world, body, point, normal, 1e-9, &n);
  if (!nodes) return MICA_ERR_OUT_OF_MEMORY;
  mica_lpc_def d = mica_lpc_def_default();
  d.kind = MICA_LPC_PLANE;
  for (int k = 0; k < 3; ++k) d.direction[0][k] = fabs(normal[k]);
  const mica_status status = n > 0 ? mica_add_lpc(world, body, nodes, n, &d, out) : MICA_ERR_INVALID_ARGUMENT;
  free(nodes);
  return status;
}

mica_status uniaxial_scene_create(mica_world* world, const uniaxial_scene_def* def, uniaxial_scene* s) {
  memset(s, 0, sizeof *s);
  s->side = def->side;
  const double lo[3] = {0, 0, 0}, hi[3] = {def->side, def->side, def->side};
  const int32_t cells[3] = {def->cells, def->cells, def->cells};
  mica_status st = mica_body_create_box(world, &def->body, lo, hi, cells, def->tets_per_cell, &s->body);
  if (st < 0) return st;
  st = mica_body_get_counts(world, s->body, &s->nodes, &s->tets, NULL);
  if (st < 0) return st;
  const double origin[3] = {0, 0, 0}, axes[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int k = 0; k < 3; ++k) {
    st = add_plane(world, s->body, origin, axes[k], &s->planes[k]);
    if (st < 0) return st;
  }
  const double top[3] = {0, 0, def->side}, down[3] = {0, 0, -1}; /* selects z >= side */
  return add_plane(world, s->body, top, down, &s->plate);
}

mica_status uniaxial_scene_measure(mica_world* world, const uniaxial_scene* s, double* stretch, double* lateral,
                                   double* nominal) {
  double* x = malloc(sizeof(double) * 3 * (size_t)(s->nodes > 0 ? s->nodes : 1));
  if (!x) return MICA_ERR_OUT_OF_MEMORY;
  int32_t n = 0;
  mica_status st = mica_body_get_positions(world, s->body, x, s->nodes, &n);
  double height = 0, width = 0;
  for (int32_t i = 0; st >= 0 && i < n; ++i) {
    height = fmax(height, x[3 * i + 2]);
    width = fmax(width, x[3 * i]);
  }
  free(x);
  if (st < 0) return st;
  double f[3] = {0, 0, 0};
  st = mica_lpc_get_reaction(world, s->plate, f);
  if (st < 0) return st;
  if (stretch) *stretch = height / s->side;
  if (lateral) *lateral = width / s->side;
  /* The body pushes the plate up: the reaction on the body points down. */
  if (nominal) *nominal = -f[2] / (s->side * s->side);
  return MICA_OK;
}

double uniaxial_neo_hookean_nominal_stress(double E, double nu, double s, double* lateral) {
  const double lame = E * nu / ((1 + nu) * (1 - 2 * nu));
  const double mu = E / (2 * (1 + nu)), lambda = lame + mu, alpha = 1 + mu / lambda;
  double t = 1;
  for (int it = 0; it < 50; ++it) {
    const double g = mu * t + lambda * (t * t * s - alpha) * t * s;
    const double dg = mu + lambda * (3 * t * t * s - alpha) * s;
    const double step = g / dg;
    t -= step;
    if (fabs(step) < 1e-15) break;
  }
  if (lateral) *lateral = t;
  return mu * s + lambda * (t * t * s - alpha) * t * t;
}

double uniaxial_hooke_nominal_stress(double E, double nu, double s, double* lateral) {
  if (lateral) *lateral = 1 - nu * (s - 1);
  return E * (s - 1);
}
