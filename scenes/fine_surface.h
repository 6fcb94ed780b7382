/* SPDX-License-Identifier: Apache-2.0 */
/* A fine render mesh over a body: its rest surface with each edge cut into `divisions` equal parts
 * and each triangle into divisions^2 (the points of an edge shared by its two triangles), as a
 * vertex array and triangles - the mesh that examples_c/render_mesh.c, bench/bench_embedding.c and
 * the tests embed in the body (mica_embedding_create). Plain C99 against the public API only
 * (mica.h). */
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

/* The rest surface of `body` (only its surface nodes, renumbered), each triangle split into
 * divisions^2 (divisions >= 1; 1 keeps it): about divisions^2 times the vertices. Returns a getter's
 * status, MICA_ERR_INVALID_ARGUMENT (divisions < 1 or too many for int32_t counts) or
 * MICA_ERR_OUT_OF_MEMORY; on failure *out is empty. */
mica_status fine_surface_of_body(mica_world* world, mica_body_id body, int32_t divisions, fine_surface* out);

/* `coarse` with each triangle split into m^2 (m >= 1), into *out (its own arrays). Returns
 * MICA_ERR_INVALID_ARGUMENT or MICA_ERR_OUT_OF_MEMORY with *out empty on failure. */
mica_status fine_surface_split(const fine_surface* coarse, int32_t m, fine_surface* out);

/* Frees the arrays and empties *s. */
void fine_surface_free(fine_surface* s);

#ifdef __cplusplus
}
#endif

#endif /* MICA_SCENES_FINE_SURFACE_H */
