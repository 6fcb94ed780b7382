/* SPDX-License-Identifier: Apache-2.0 */
/* A fine render mesh over a body: its rest surface with each triangle split into four (at the edge
 * midpoints, shared by the two triangles of an edge) `levels` times, as a vertex array and
 * triangles - the mesh that examples_c/render_mesh.c, bench/bench_embedding.c and the tests embed
 * in the body (mica_embedding_create). Plain C99 against the public API only (mica.h). */
#ifndef MICA_SCENES_FINE_SURFACE_H
#define MICA_SCENES_FINE_SURFACE_H

#include <stdint.h>

#include <mica/mica.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct fine_surface {
  double* xyz;            /* 3 * vertex_count, m (malloc'ed) */
  int32_t vertex_count;
  int32_t triangle_count;
  int32_t* triangles;     /* 3 * triangle_count vertex indices, counter-clockwise seen from outside (malloc'ed) */
} fine_surface;

/* The rest surface of `body` (only its surface nodes, renumbered), split `levels` (>= 0) times: each
 * level multiplies the triangles by 4 and the vertices by about 4. Returns a getter's status,
 * MICA_ERR_INVALID_ARGUMENT (levels < 0 or too many for int32_t counts) or MICA_ERR_OUT_OF_MEMORY;
 * on failure *out is empty. */
mica_status fine_surface_of_body(mica_world* world, mica_body_id body, int32_t levels, fine_surface* out);

/* Frees the arrays and empties *s. */
void fine_surface_free(fine_surface* s);

#ifdef __cplusplus
}
#endif

#endif /* MICA_SCENES_FINE_SURFACE_H */
