/* SPDX-License-Identifier: Apache-2.0 */
/* A tool pressed into a soft body and held: see press_scene.h. */
#include "press_scene.h"

#include "node_selection.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

press_scene_def press_scene_def_default(void) {
  press_scene_def d;
  memset(&d, 0, sizeof d);
  d.shape = MICA_TOOL_SPHERE;
  d.cells = 12;
  d.mesh = "data/nidus/nidus.msh";
  d.dt = 0.01;
  d.solver = MICA_SOLVER_DIRECT;
  d.sweep = MICA_SWEEP_FACTORED;
  d.tolerance = 1e-8;
  d.max_iterations = 20000;
  d.size = 0.02;
  d.margin = 0.0015;
  d.gap = 0.005;
  d.depth = 0.01;
  d.load_time = 1.0;
  d.hold_time = 1.0;
  d.youngs_modulus = 1e4;
  d.poisson_ratio = 0.4;
  d.density = 1000;
  d.rayleigh_alpha = 2;
  d.rayleigh_beta = 0;
  return d;
}

press_scene_def press_scene_nidus_touch_def(const char* mesh, double load_time, double hold_time) {
  press_scene_def d = press_scene_def_default();
  d.cells = 0;
  d.mesh = mesh;
  d.solver = MICA_SOLVER_MICA;
  d.tolerance = 1e-6;
  d.size = 0.004;
  d.gap = 0.0005;
  d.depth = 0.003;
  d.load_time = load_time;
  d.hold_time = hold_time;
  return d;
}

press_scene_def press_scene_sphere_indent_def(void) {
  press_scene_def d = press_scene_def_default();
  d.depth = 0.015;
  d.rayleigh_beta = 0.005;
  d.solver = MICA_SOLVER_MICA;
  d.sweep = MICA_SWEEP_FACTORED;
  d.tolerance = 1e-6;
  d.max_iterations = 2000;
  return d;
}

const char* press_scene_shape_name(int32_t shape) {
  switch (shape) {
    case MICA_TOOL_SPHERE: return "sphere";
    case MICA_TOOL_CAPSULE: return "capsule";
    case MICA_TOOL_BOX: return "box";
    case MICA_TOOL_HULL: return "hull";
    default: return "?";
  }
}

static mica_status fail(press_scene* s, mica_status status, const char* fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(s->error, sizeof s->error, fmt, ap);
  va_end(ap);
  if (s->world) mica_world_destroy(s->world);
  s->world = NULL;
  return status < 0 ? status : MICA_ERR_INVALID_ARGUMENT;
}

#define TRY(call, what)                                                                                  \
  do {                                                                                                   \
    const mica_status st_ = (call);                                                                      \
    if (st_ < 0) return fail(s, st_, "%s: %s: %s", what, mica_status_string(st_), mica_world_last_error(s->world)); \
  } while (0)

/* The hull: an irregular quadrilateral at the bottom (y = -0.75 size) and a smaller one turned
 * against it at the top (y = +0.75 size), corners at the angles and radii (in size) below. */
static void hull_points(double size, double out[24]) {
  static const double bottom[4][2] = {{20, 1.0}, {105, 0.85}, {200, 0.95}, {290, 0.8}};
  static const double top[4][2] = {{60, 0.6}, {150, 0.5}, {250, 0.65}, {330, 0.55}};
  for (int i = 0; i < 4; ++i) {
    const double a = bottom[i][0] * M_PI / 180, b = top[i][0] * M_PI / 180;
    out[3 * i + 0] = size * bottom[i][1] * cos(a);
    out[3 * i + 1] = -0.75 * size;
    out[3 * i + 2] = size * bottom[i][1] * sin(a);
    out[12 + 3 * i + 0] = size * top[i][1] * cos(b);
    out[12 + 3 * i + 1] = 0.75 * size;
    out[12 + 3 * i + 2] = size * top[i][1] * sin(b);
  }
}

mica_status press_scene_top(mica_world* world, mica_body_id body, double lo[3], double hi[3], double top[3]) {
  int32_t nodes = 0;
  mica_status st = mica_body_get_counts(world, body, &nodes, NULL, NULL);
  if (st < 0) return st;
  double* x = malloc(sizeof(double) * 3 * (size_t)(nodes > 0 ? nodes : 1));
  if (!x) return MICA_ERR_OUT_OF_MEMORY;
  st = mica_body_get_rest_positions(world, body, x, nodes, NULL);
  if (st < 0) {
    free(x);
    return st;
  }
  double* c = top;
  c[0] = c[1] = c[2] = 0;
  for (int a = 0; a < 3; ++a) {
    lo[a] = HUGE_VAL;
    hi[a] = -HUGE_VAL;
  }
  for (int32_t i = 0; i < nodes; ++i)
    for (int a = 0; a < 3; ++a) {
      lo[a] = fmin(lo[a], x[3 * i + a]);
      hi[a] = fmax(hi[a], x[3 * i + a]);
      c[a] += x[3 * i + a] / nodes;
    }
  int32_t ntri = 0;
  mica_body_get_surface(world, body, NULL, 0, &ntri);
  int32_t* tri = malloc(sizeof(int32_t) * 3 * (size_t)(ntri > 0 ? ntri : 1));
  if (!tri) {
    free(x);
    return MICA_ERR_OUT_OF_MEMORY;
  }
  st = mica_body_get_surface(world, body, tri, ntri, &ntri);
  double y = -HUGE_VAL;
  for (int32_t t = 0; st >= 0 && t < ntri; ++t) {
    const double* a = x + 3 * tri[3 * t];
    const double* b = x + 3 * tri[3 * t + 1];
    const double* d = x + 3 * tri[3 * t + 2];
    const double det = (b[0] - a[0]) * (d[2] - a[2]) - (d[0] - a[0]) * (b[2] - a[2]);
    if (fabs(det) < 1e-18) continue;
    const double u = ((c[0] - a[0]) * (d[2] - a[2]) - (d[0] - a[0]) * (c[2] - a[2])) / det;
    const double v = ((b[0] - a[0]) * (c[2] - a[2]) - (c[0] - a[0]) * (b[2] - a[2])) / det;
    if (u < 0 || v < 0 || u + v > 1) continue;
    y = fmax(y, a[1] + u * (b[1] - a[1]) + v * (d[1] - a[1]));
  }
  free(tri);
  free(x);
  if (st < 0) return st;
  if (!isfinite(y)) return MICA_ERR_INVALID_ARGUMENT;
  c[1] = y;
  return MICA_OK;
}

/* The nidus: where the tool comes down (press_scene_top) into s->center. */
static mica_status nidus_top(press_scene* s, double lo[3], double hi[3]) {
  const mica_status st = press_scene_top(s->world, s->body, lo, hi, s->center);
  if (st == MICA_ERR_INVALID_ARGUMENT) return fail(s, st, "no surface above the centroid of %s", s->def.mesh);
  TRY(st, "press_scene_top");
  return MICA_OK;
}

static mica_status fix_below(press_scene* s, double y, double tol) {
  const double point[3] = {0, y, 0}, up[3] = {0, 1, 0};
  int32_t n = 0;
  mica_lpc_id lpc;
  const mica_status st = scene_fix_plane(s->world, s->body, point, up, tol, &n, &lpc);
  if (n <= 0 && st != MICA_ERR_OUT_OF_MEMORY) return fail(s, MICA_ERR_INVALID_ARGUMENT, "no node to hold below y = %g", y);
  TRY(st, "hold the nodes below the cut");
  return MICA_OK;
}

mica_status press_scene_create(const press_scene_def* def, press_scene* s) {
  memset(s, 0, sizeof *s);
  s->def = *def;
  const press_scene_def* d = &s->def;
  if (!(d->dt > 0) || d->cells < 0 || !(d->size > 0) || !(d->load_time > 0) || d->hold_time < 0 ||
      (d->shape != MICA_TOOL_SPHERE && d->shape != MICA_TOOL_CAPSULE && d->shape != MICA_TOOL_BOX &&
       d->shape != MICA_TOOL_HULL))
    return fail(s, MICA_ERR_INVALID_ARGUMENT, "press_scene_create: bad definition");

  mica_world_def wd = mica_world_def_default();
  wd.gravity[0] = wd.gravity[1] = wd.gravity[2] = 0;
  wd.solver = d->solver;
  wd.mica_sweep = d->sweep;
  wd.tolerance = d->tolerance;
  wd.max_iterations = d->max_iterations;
  wd.refactor_interval = d->refactor_interval;
  if (mica_world_create(&wd, &s->world) != MICA_OK)
    return fail(s, MICA_ERR_INVALID_ARGUMENT, "mica_world_create: %s", mica_world_last_error(NULL));

  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = d->youngs_modulus;
  bd.poisson_ratio = d->poisson_ratio;
  bd.density = d->density;
  bd.rayleigh_alpha = d->rayleigh_alpha;
  bd.rayleigh_beta = d->rayleigh_beta;
  if (d->cells > 0) {
    const double L = 0.1, lo[3] = {-L / 2, 0, -L / 2}, hi[3] = {L / 2, L, L / 2};
    const int32_t cells[3] = {d->cells, d->cells, d->cells};
    TRY(mica_body_create_box(s->world, &bd, lo, hi, cells, 5, &s->body), "mica_body_create_box");
    TRY(mica_body_get_counts(s->world, s->body, &s->nodes, &s->tets, NULL), "mica_body_get_counts");
    const mica_status st = fix_below(s, 0, 1e-9);
    if (st < 0) return st;
    s->center[0] = 0;
    s->center[1] = L;
    s->center[2] = 0;
  } else {
    TRY(mica_body_create_from_file(s->world, &bd, d->mesh, &s->body), d->mesh);
    TRY(mica_body_get_counts(s->world, s->body, &s->nodes, &s->tets, NULL), "mica_body_get_counts");
    double lo[3], hi[3];
    mica_status st = nidus_top(s, lo, hi);
    if (st < 0) return st;
    st = fix_below(s, lo[1] + 0.2 * (hi[1] - lo[1]), 0);
    if (st < 0) return st;
  }

  mica_tool_def td = mica_tool_def_default();
  td.shape = d->shape;
  td.margin = d->margin;
  s->orientation[0] = 1;
  double hull[24];
  switch (d->shape) {
    case MICA_TOOL_SPHERE:
      td.radius = d->size;
      s->lowest = d->size;
      break;
    case MICA_TOOL_CAPSULE: {
      td.radius = d->size / 2;
      td.half_length = d->size;
      /* local z onto world x: a quarter turn about y */
      s->orientation[0] = cos(M_PI / 4);
      s->orientation[2] = sin(M_PI / 4);
      s->lowest = d->size / 2;
      break;
    }
    case MICA_TOOL_BOX:
      td.half_extents[0] = td.half_extents[1] = td.half_extents[2] = d->size;
      s->lowest = d->size;
      break;
    default:
      hull_points(d->size, hull);
      td.hull_points = hull;
      td.hull_point_count = 8;
      s->lowest = 0.75 * d->size;
      break;
  }
  memcpy(td.orientation, s->orientation, sizeof td.orientation);
  s->y_start = s->center[1] + s->lowest + d->gap;
  td.position[0] = s->center[0];
  td.position[1] = s->y_start;
  td.position[2] = s->center[2];
  TRY(mica_tool_create(s->world, &td, &s->tool), "mica_tool_create");
  s->load_steps = (int32_t)(d->load_time / d->dt + 0.5);
  if (s->load_steps < 1) s->load_steps = 1;
  s->steps = s->load_steps + (int32_t)(d->hold_time / d->dt + 0.5);
  return MICA_OK;
}

double press_scene_depth(const press_scene* s, int32_t k) {
  const double travel = s->def.gap + s->def.depth;
  const double t = k >= s->load_steps ? 1.0 : (double)k / s->load_steps;
  return t * travel - s->def.gap;
}

mica_status press_scene_step(press_scene* s, int32_t k, double force[3], int32_t* contacts) {
  const double p[3] = {s->center[0], s->center[1] + s->lowest - press_scene_depth(s, k), s->center[2]};
  mica_status st = mica_tool_set_pose(s->world, s->tool, p, s->orientation);
  if (st >= 0) st = mica_step(s->world, s->def.dt);
  if (st < 0) {
    snprintf(s->error, sizeof s->error, "step %d: %s: %s", k, mica_status_string(st), mica_world_last_error(s->world));
    return st;
  }
  const mica_status sf = mica_tool_get_force(s->world, s->tool, force, NULL, contacts);
  return sf < 0 ? sf : st;
}

void press_scene_destroy(press_scene* s) {
  if (s->world) mica_world_destroy(s->world);
  s->world = NULL;
}
