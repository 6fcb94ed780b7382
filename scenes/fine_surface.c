/* SPDX-License-Identifier: Apache-2.0 */
#include "fine_surface.h"

#include <stdlib.h>
#include <string.h>

/* An edge (lo < hi) and the triangle corner it starts at (3 * triangle + k: the edge k -> k+1). */
typedef struct {
  int32_t lo, hi, corner;
} edge;

static int edge_order(const void* a, const void* b) {
  const edge *x = a, *y = b;
  if (x->lo != y->lo) return x->lo < y->lo ? -1 : 1;
  return (x->hi > y->hi) - (x->hi < y->hi);
}

/* One level: every triangle into four; the midpoint of an edge is made once. */
static mica_status split(fine_surface* s) {
  const int32_t t = s->triangle_count;
  edge* edges = malloc(sizeof(edge) * 3 * (size_t)t + 1);
  int32_t* mid = malloc(sizeof(int32_t) * 3 * (size_t)t + 1); /* per corner: the midpoint of its edge */
  int32_t* tris = malloc(sizeof(int32_t) * 12 * (size_t)t + 1);
  /* At most one new vertex per edge: 3t / 2 on a closed surface, 3t at most. */
  double* xyz = malloc(sizeof(double) * 3 * ((size_t)s->vertex_count + 3 * (size_t)t));
  if (!edges || !mid || !tris || !xyz) {
    free(edges);
    free(mid);
    free(tris);
    free(xyz);
    return MICA_ERR_OUT_OF_MEMORY;
  }
  for (int32_t c = 0; c < 3 * t; ++c) {
    const int32_t a = s->triangles[c], b = s->triangles[c % 3 == 2 ? c - 2 : c + 1];
    edges[c].lo = a < b ? a : b;
    edges[c].hi = a < b ? b : a;
    edges[c].corner = c;
  }
  qsort(edges, 3 * (size_t)t, sizeof(edge), edge_order);
  memcpy(xyz, s->xyz, sizeof(double) * 3 * (size_t)s->vertex_count);
  int32_t n = s->vertex_count;
  for (int32_t e = 0; e < 3 * t; ++e) {
    if (e == 0 || edge_order(&edges[e], &edges[e - 1]) != 0) {
      for (int k = 0; k < 3; ++k)
        xyz[3 * (size_t)n + k] = 0.5 * (s->xyz[3 * (size_t)edges[e].lo + k] + s->xyz[3 * (size_t)edges[e].hi + k]);
      ++n;
    }
    mid[edges[e].corner] = n - 1;
  }
  for (int32_t f = 0; f < t; ++f) {
    const int32_t* v = s->triangles + 3 * (size_t)f;
    const int32_t* m = mid + 3 * (size_t)f; /* m[0] on v0-v1, m[1] on v1-v2, m[2] on v2-v0 */
    const int32_t four[12] = {v[0], m[0], m[2], m[0], v[1], m[1], m[2], m[1], v[2], m[0], m[1], m[2]};
    memcpy(tris + 12 * (size_t)f, four, sizeof four);
  }
  free(edges);
  free(mid);
  free(s->xyz);
  free(s->triangles);
  s->xyz = xyz;
  s->vertex_count = n;
  s->triangles = tris;
  s->triangle_count = 4 * t;
  return MICA_OK;
}

mica_status fine_surface_of_body(mica_world* world, mica_body_id body, int32_t levels, fine_surface* out) {
  memset(out, 0, sizeof *out);
  int32_t nodes = 0, triangles = 0;
  mica_status status = mica_body_get_counts(world, body, &nodes, NULL, &triangles);
  if (status != MICA_OK) return status;
  if (levels < 0 || levels > 12 || (double)triangles * (1 << (2 * levels)) > INT32_MAX / 12)
    return MICA_ERR_INVALID_ARGUMENT;
  double* rest = malloc(sizeof(double) * 3 * (size_t)nodes);
  int32_t* index = malloc(sizeof(int32_t) * (size_t)nodes); /* body node -> surface vertex, or -1 */
  out->xyz = malloc(sizeof(double) * 3 * (size_t)nodes);
  out->triangles = malloc(sizeof(int32_t) * 3 * (size_t)triangles + 1);
  if (!rest || !index || !out->xyz || !out->triangles) status = MICA_ERR_OUT_OF_MEMORY;
  if (status == MICA_OK) status = mica_body_get_rest_positions(world, body, rest, nodes, NULL);
  if (status == MICA_OK) status = mica_body_get_surface(world, body, out->triangles, triangles, NULL);
  if (status == MICA_OK) {
    for (int32_t i = 0; i < nodes; ++i) index[i] = -1;
    for (int32_t c = 0; c < 3 * triangles; ++c) {
      int32_t* v = &out->triangles[c];
      if (index[*v] < 0) {
        index[*v] = out->vertex_count++;
        memcpy(out->xyz + 3 * (size_t)index[*v], rest + 3 * (size_t)*v, 3 * sizeof(double));
      }
      *v = index[*v];
    }
    out->triangle_count = triangles;
  }
  free(rest);
  free(index);
  for (int32_t level = 0; status == MICA_OK && level < levels; ++level) status = split(out);
  if (status != MICA_OK) fine_surface_free(out);
  return status;
}

void fine_surface_free(fine_surface* s) {
  free(s->xyz);
  free(s->triangles);
  memset(s, 0, sizeof *s);
}
