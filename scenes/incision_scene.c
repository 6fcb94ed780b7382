/* SPDX-License-Identifier: Apache-2.0 */
/* An incision: see incision_scene.h. */
#include "incision_scene.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define ENTRY_ABOVE 0.001   /* m: the tip starts this far above and behind the start point */
#define HOOK_SIDE 0.005     /* m: the hook grabs this far to the +z side of the line */
#define HOOK_RADIUS 0.004   /* m */
#define HOOK_TRAVEL 0.008   /* m */
#define HOOK_SPEED 0.01     /* m/s */
#define FORCEPS_SIDE 0.012  /* m: the forceps rests this far to the -z side */
#define FORCEPS_RADIUS 0.004

static const double kNoTurn[4] = {1, 0, 0, 0};

incision_scene_def incision_scene_def_default(void) {
  incision_scene_def d;
  memset(&d, 0, sizeof d);
  d.cells = 12;
  d.mesh = "data/nidus/nidus.msh";
  d.length = 0.03;
  d.depth = 0.008;
  d.speed = 0.01;
  d.dt = 0.01;
  d.cutting_resistance = 40;
  d.blade = 1;
  d.hook = 1;
  return d;
}

static mica_status fail(incision_scene* s, mica_status status, const char* fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(s->error, sizeof s->error, fmt, ap);
  va_end(ap);
  return status;
}

/* The blade's frame: its edge (local z) leaning 45 degrees forward in the x-y plane, its cutting
 * direction (local x) forward and down, local y = z x x = -z (world). */
static const double kEdge[3] = {0.70710678118654752, 0.70710678118654752, 0};
static const double kCuts[3] = {0.70710678118654752, -0.70710678118654752, 0};
static const double kBladeTurn[4] = {0.65328148243818826, -0.65328148243818826, 0.27059805007309849, -0.27059805007309849};

#define HALF_EDGE 0.015 /* m */
#define BLADE_RADIUS 0.00025

/* The blade's origin for a tip at `tip` (the tip is the edge's lower end). */
static void blade_origin(const double tip[3], double out[3]) {
  for (int c = 0; c < 3; ++c) out[c] = tip[c] + HALF_EDGE * kEdge[c];
}

static void tip_at_step(const incision_scene* s, int32_t k, double tip[3]) {
  const double step = s->def.speed * s->def.dt;
  if (k <= s->entry_steps) {  /* in, along the cutting direction */
    const double travel = (ENTRY_ABOVE + s->def.depth) * sqrt(2.0) * (double)k / (double)s->entry_steps;
    for (int c = 0; c < 3; ++c) tip[c] = s->start[c] - ENTRY_ABOVE * sqrt(2.0) * kCuts[c] + travel * kCuts[c];
    return;
  }
  const int32_t along = k - s->entry_steps < s->cut_steps ? k - s->entry_steps : s->cut_steps;
  for (int c = 0; c < 3; ++c) tip[c] = s->start[c] + s->def.depth * sqrt(2.0) * kCuts[c];
  tip[0] += step * (double)along;
}

mica_status incision_scene_create(const incision_scene_def* def, incision_scene* s) {
  memset(s, 0, sizeof *s);
  s->def = *def;
  if (!(def->length > 0 && def->depth > 0 && def->speed > 0 && def->dt > 0))
    return fail(s, MICA_ERR_INVALID_ARGUMENT, "length, depth, speed and dt must be > 0");
  press_scene_def pd = def->cells > 0 ? press_scene_def_default() : press_scene_nidus_touch_def(def->mesh, 1, 1);
  pd.cells = def->cells;
  pd.mesh = def->mesh;
  pd.dt = def->dt;
  pd.solver = MICA_SOLVER_MICA;
  pd.sweep = MICA_SWEEP_FACTORED;
  pd.tolerance = 1e-6;
  pd.max_iterations = 2000;
  pd.size = FORCEPS_RADIUS;
  pd.refactor_interval = def->refactor_interval;
  mica_status st = press_scene_create(&pd, &s->press);
  if (st < 0) return fail(s, st, "%s", s->press.error);
  s->entry_steps = (int32_t)ceil((ENTRY_ABOVE + def->depth) * sqrt(2.0) / (def->speed * def->dt));
  s->cut_steps = (int32_t)ceil(def->length / (def->speed * def->dt));
  s->steps = s->entry_steps + s->cut_steps + s->cut_steps / 10;
  mica_world* w = s->press.world;
  memcpy(s->start, s->press.center, sizeof s->start);
  s->start[0] -= def->length / 2;

  mica_tool_def td = mica_tool_def_default();
  td.shape = MICA_TOOL_CAPSULE;
  td.radius = BLADE_RADIUS;
  td.half_length = HALF_EDGE;
  td.margin = 0.0005;
  td.blade = def->blade;
  memcpy(td.orientation, kBladeTurn, sizeof kBladeTurn);
  tip_at_step(s, 0, s->tip);
  blade_origin(s->tip, td.position);
  st = mica_tool_create(w, &td, &s->blade);
  if (st < 0) goto failed;
  if (def->cutting_resistance != 200) {
    double* r = malloc(sizeof(double) * (size_t)s->press.tets);
    if (!r) {
      st = MICA_ERR_OUT_OF_MEMORY;
      goto failed;
    }
    for (int32_t e = 0; e < s->press.tets; ++e) r[e] = def->cutting_resistance;
    st = mica_body_set_cutting_resistance(w, s->press.body, r, s->press.tets);
    free(r);
    if (st < 0) goto failed;
  }

  /* The forceps tip beside the line, or out of the way. */
  double forceps[3] = {s->press.center[0], s->press.center[1] + FORCEPS_RADIUS - 0.001, s->press.center[2] - FORCEPS_SIDE};
  if (!def->forceps) forceps[1] += 10;
  st = mica_tool_teleport(w, s->press.tool, forceps, kNoTurn);
  if (st < 0) goto failed;

  s->hook = MICA_NULL_ID;
  if (def->hook) {
    s->hook_at[0] = s->press.center[0];
    s->hook_at[1] = s->press.center[1];
    s->hook_at[2] = s->press.center[2] + HOOK_SIDE;
    st = mica_lpc_grab(w, s->press.body, s->hook_at, HOOK_RADIUS, MICA_NULL_ID, &s->hook);
    if (st < 0) goto failed;
  }
  return MICA_OK;

failed:
  fail(s, st, "%s", mica_world_last_error(w));
  press_scene_destroy(&s->press);
  return st;
}

mica_status incision_scene_step(incision_scene* s, int32_t k) {
  mica_world* w = s->press.world;
  double origin[3];
  tip_at_step(s, k, s->tip);
  blade_origin(s->tip, origin);
  mica_status st = mica_tool_set_pose(w, s->blade, origin, kBladeTurn);
  if (st >= 0 && s->hook != MICA_NULL_ID && s->tip[0] > s->press.center[0] &&
      s->hook_at[2] < s->press.center[2] + HOOK_SIDE + HOOK_TRAVEL) {
    s->hook_at[2] += HOOK_SPEED * s->def.dt;
    st = mica_lpc_set_handle_pose(w, s->hook, s->hook_at, kNoTurn);
  }
  if (st >= 0) st = mica_step(w, s->def.dt);
  if (st < 0) return fail(s, st, "%s", mica_world_last_error(w));
  return st;
}

mica_status incision_scene_blade_force(const incision_scene* s, double force[3], double* along) {
  const mica_status st = mica_tool_get_force(s->press.world, s->blade, force, NULL, NULL);
  if (along) *along = -(force[0] * kCuts[0] + force[1] * kCuts[1] + force[2] * kCuts[2]);
  return st;
}

void incision_scene_destroy(incision_scene* s) { press_scene_destroy(&s->press); }
