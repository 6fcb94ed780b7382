/* SPDX-License-Identifier: Apache-2.0 */
/* A box body fixed at its base, a grasp dragging one face, and a sphere over it: see box_scene.h. */
#include "box_scene.h"

#include <stdlib.h>
#include <string.h>

#include "node_selection.h"

box_scene_def box_scene_def_default(void) {
  box_scene_def d;
  memset(&d, 0, sizeof d);
  d.body = mica_body_def_default();
  d.hi[0] = d.hi[1] = d.hi[2] = 0.1;
  d.cells[0] = d.cells[1] = d.cells[2] = 8;
  d.tets_per_cell = 6;
  d.tool_radius = 0.02;
  d.tool_margin = mica_tool_def_default().margin;
  return d;
}

box_scene_def box_scene_block_def(void) {
  box_scene_def d = box_scene_def_default();
  d.lo[0] = d.lo[2] = -0.05;
  d.lo[1] = -0.1;
  d.hi[0] = d.hi[2] = 0.05;
  d.hi[1] = 0;
  d.tool_position[1] = 0.05;
  return d;
}

/* The nodes of the face x = hi[0], moved at `velocity`. */
static mica_status add_drag(mica_world* world, const box_scene_def* d, box_scene* s) {
  const double face[3] = {d->hi[0], 0, 0}, inward[3] = {-1, 0, 0};
  int32_t n = 0;
  int32_t* nodes = scene_select_plane(world, s->body, face, inward, 1e-9, &n);
  if (!nodes) return MICA_ERR_OUT_OF_MEMORY;
  mica_lpc_def pull = mica_lpc_def_default();
  memcpy(pull.velocity, d->drag_velocity, sizeof pull.velocity);
  const mica_status status = mica_add_lpc(world, s->body, nodes, n, &pull, &s->drag);
  free(nodes);
  return status;
}

mica_status box_scene_create(mica_world* world, const box_scene_def* def, box_scene* s) {
  memset(s, 0, sizeof *s);
  mica_status st = mica_body_create_box(world, &def->body, def->lo, def->hi, def->cells, def->tets_per_cell, &s->body);
  if (st < 0) return st;
  st = mica_body_get_counts(world, s->body, &s->nodes, &s->tets, NULL);
  if (st < 0) return st;
  const double base[3] = {0, def->lo[1], 0}, up[3] = {0, 1, 0};
  st = scene_fix_plane(world, s->body, base, up, 1e-9, NULL, &s->base);
  if (st < 0) return st;
  const double* v = def->drag_velocity;
  if (v[0] != 0 || v[1] != 0 || v[2] != 0) {
    st = add_drag(world, def, s);
    if (st < 0) return st;
  }
  if (def->tool_radius > 0) {
    mica_tool_def td = mica_tool_def_default();
    td.radius = def->tool_radius;
    td.margin = def->tool_margin;
    memcpy(td.position, def->tool_position, sizeof td.position);
    st = mica_tool_create(world, &td, &s->tool);
  }
  return st;
}
