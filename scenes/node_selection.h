/* SPDX-License-Identifier: Apache-2.0 */
/* Nodes on one side of a plane, and holding them: what every scene does to fix a base or clamp a
 * face (scenes/box_scene.c, scenes/press_scene.c, the examples and the study). Plain C99 against
 * the public API only (mica.h). */
#ifndef MICA_SCENES_NODE_SELECTION_H
#define MICA_SCENES_NODE_SELECTION_H

#include <stdint.h>

#include <mica/mica.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The nodes of `body` whose rest position p has (p - point) . normal <= tol
 * (mica_body_select_nodes_by_plane), in a malloc'ed array the caller frees (room for one node at
 * least), their count in *count (0 when the selection fails). NULL when out of memory. */
int32_t* scene_select_plane(mica_world* world, mica_body_id body, const double point[3], const double normal[3],
                            double tol, int32_t* count);

/* Fixes (MICA_LPC_FIXED) the nodes scene_select_plane selects; their count into *count (may be
 * NULL). Returns mica_add_lpc's status, MICA_ERR_INVALID_ARGUMENT when no node is selected, or
 * MICA_ERR_OUT_OF_MEMORY. */
mica_status scene_fix_plane(mica_world* world, mica_body_id body, const double point[3], const double normal[3],
                            double tol, int32_t* count, mica_lpc_id* out);

#ifdef __cplusplus
}
#endif

#endif /* MICA_SCENES_NODE_SELECTION_H */
