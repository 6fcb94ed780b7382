/* SPDX-License-Identifier: Apache-2.0 */
/* Nodes on one side of a plane, and holding them: see node_selection.h. */
#include "node_selection.h"

#include <stdlib.h>

int32_t* scene_select_plane(mica_world* world, mica_body_id body, const double point[3], const double normal[3],
                            double tol, int32_t* count) {
  *count = 0;
  mica_body_select_nodes_by_plane(world, body, point, normal, tol, 1, NULL, 0, count);
  int32_t* nodes = malloc(sizeof(int32_t) * (size_t)(*count > 0 ? *count : 1));
  if (!nodes) {
    *count = 0;
    return NULL;
  }
  if (*count > 0 && mica_body_select_nodes_by_plane(world, body, point, normal, tol, 1, nodes, *count, count) < 0)
    *count = 0;
  return nodes;
}

mica_status scene_fix_plane(mica_world* world, mica_body_id body, const double point[3], const double normal[3],
                            double tol, int32_t* count, mica_lpc_id* out) {
  int32_t n = 0;
  int32_t* nodes = scene_select_plane(world, body, point, normal, tol, &n);
  if (count) *count = n;
  if (!nodes) return MICA_ERR_OUT_OF_MEMORY;
  const mica_lpc_def fixed = mica_lpc_def_default(); /* MICA_LPC_FIXED */
  const mica_status status = n > 0 ? mica_add_lpc(world, body, nodes, n, &fixed, out) : MICA_ERR_INVALID_ARGUMENT;
  free(nodes);
  return status;
}
