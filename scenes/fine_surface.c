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

/* The points of one triangle (a, b, c) split `m` times along each edge, as (u, v): a + u/m (b - a)
 * + v/m (c - a), u, v >= 0, u + v <= m. Corners are the coarse vertices, edge points are shared
 * with the neighbour across the edge, inner points are the triangle's own. */
typedef struct {
  const fine_surface* coarse;
  const int32_t* corner_edge_start; /* per corner: index of the first of its edge's m - 1 points */
  const int32_t* corner_forward;    /* per corner: 1 if its edge's points run from this corner */
  int32_t m, f, inner;              /* divisions, triangle, index of its first inner point */
} split_triangle;

/* Index of point (s steps from corner k along its edge, 0 < s < m). */
static int32_t edge_point(const split_triangle* t, int k, int32_t s) {
  const int32_t c = 3 * t->f + k;
  return t->corner_edge_start[c] + (t->corner_forward[c] ? s : t->m - s) - 1;
}

static int32_t point(const split_triangle* t, int32_t u, int32_t v) {
  const int32_t* corners = t->coarse->triangles + 3 * (size_t)t->f;
  const int32_t m = t->m;
  if (u == 0 && v == 0) return corners[0];
  if (u == m) return corners[1];
  if (v == m) return corners[2];
  if (v == 0) return edge_point(t, 0, u);
  if (u + v == m) return edge_point(t, 1, v);
  if (u == 0) return edge_point(t, 2, m - v);
  /* inner points row by row: for v = 1..m-2, u = 1..m-1-v */
  int32_t index = t->inner;
  for (int32_t row = 1; row < v; ++row) index += m - 1 - row;
  return index + u - 1;
}

mica_status fine_surface_split(const fine_surface* coarse, int32_t m, fine_surface* out) {
  memset(out, 0, sizeof *out);
  const int32_t t = coarse->triangle_count;
  const double fine_triangles = (double)t * m * m;
  if (m < 1 || fine_triangles > INT32_MAX / 3 || (double)coarse->vertex_count + 3.0 * t * m + fine_triangles > INT32_MAX / 3)
    return MICA_ERR_INVALID_ARGUMENT;
  edge* edges = malloc(sizeof(edge) * 3 * (size_t)t + 1);
  int32_t* start = malloc(sizeof(int32_t) * 3 * (size_t)t + 1);
  int32_t* forward = malloc(sizeof(int32_t) * 3 * (size_t)t + 1);
  /* At most: the coarse vertices, m - 1 per edge (3t edges at most), (m-1)(m-2)/2 per triangle. */
  const size_t most = (size_t)coarse->vertex_count + 3 * (size_t)t * (size_t)m + (size_t)t * (size_t)m * (size_t)m;
  out->xyz = malloc(sizeof(double) * 3 * most);
  out->triangles = malloc(sizeof(int32_t) * 3 * (size_t)t * (size_t)m * (size_t)m + 1);
  if (!edges || !start || !forward || !out->xyz || !out->triangles) {
    free(edges);
    free(start);
    free(forward);
    fine_surface_free(out);
    return MICA_ERR_OUT_OF_MEMORY;
  }
  memcpy(out->xyz, coarse->xyz, sizeof(double) * 3 * (size_t)coarse->vertex_count);
  int32_t n = coarse->vertex_count;
  /* The edges' points, each edge once (sorted, the corners of an edge side by side). */
  for (int32_t c = 0; c < 3 * t; ++c) {
    const int32_t a = coarse->triangles[c], b = coarse->triangles[c % 3 == 2 ? c - 2 : c + 1];
    edges[c].lo = a < b ? a : b;
    edges[c].hi = a < b ? b : a;
    edges[c].corner = c;
    forward[c] = a < b;
  }
  qsort(edges, 3 * (size_t)t, sizeof(edge), edge_order);
  for (int32_t e = 0; e < 3 * t; ++e) {
    if (e == 0 || edge_order(&edges[e], &edges[e - 1]) != 0) {
      const double *lo = coarse->xyz + 3 * (size_t)edges[e].lo, *hi = coarse->xyz + 3 * (size_t)edges[e].hi;
      for (int32_t s = 1; s < m; ++s)
        for (int k = 0; k < 3; ++k) out->xyz[3 * (size_t)(n + s - 1) + k] = lo[k] + (double)s / m * (hi[k] - lo[k]);
      n += m - 1;
    }
    start[edges[e].corner] = n - (m - 1);
  }
  /* Each triangle's inner points and its m^2 triangles, counter-clockwise as the coarse one. */
  int32_t* tri = out->triangles;
  for (int32_t f = 0; f < t; ++f) {
    const split_triangle st = {coarse, start, forward, m, f, n};
    const int32_t* corner = coarse->triangles + 3 * (size_t)f;
    const double *a = coarse->xyz + 3 * (size_t)corner[0], *b = coarse->xyz + 3 * (size_t)corner[1],
                 *c = coarse->xyz + 3 * (size_t)corner[2];
    for (int32_t v = 1; v < m - 1; ++v)
      for (int32_t u = 1; u < m - v; ++u, ++n)
        for (int k = 0; k < 3; ++k)
          out->xyz[3 * (size_t)n + k] = a[k] + (double)u / m * (b[k] - a[k]) + (double)v / m * (c[k] - a[k]);
    for (int32_t v = 0; v < m; ++v)
      for (int32_t u = 0; u + v < m; ++u) {
        *tri++ = point(&st, u, v), *tri++ = point(&st, u + 1, v), *tri++ = point(&st, u, v + 1);
        if (u + v < m - 1) *tri++ = point(&st, u + 1, v), *tri++ = point(&st, u + 1, v + 1), *tri++ = point(&st, u, v + 1);
      }
  }
  free(edges);
  free(start);
  free(forward);
  out->vertex_count = n;
  out->triangle_count = t * m * m;
  return MICA_OK;
}

mica_status fine_surface_of_body(mica_world* world, mica_body_id body, int32_t divisions, fine_surface* out) {
  memset(out, 0, sizeof *out);
  int32_t nodes = 0, triangles = 0;
  mica_status status = mica_body_get_counts(world, body, &nodes, NULL, &triangles);
  if (status != MICA_OK) return status;
  if (divisions < 1) return MICA_ERR_INVALID_ARGUMENT;
  fine_surface coarse = {NULL, 0, 0, NULL};
  double* rest = malloc(sizeof(double) * 3 * (size_t)nodes);
  int32_t* index = malloc(sizeof(int32_t) * (size_t)nodes); /* body node -> surface vertex, or -1 */
  coarse.xyz = malloc(sizeof(double) * 3 * (size_t)nodes);
  coarse.triangles = malloc(sizeof(int32_t) * 3 * (size_t)triangles + 1);
  if (!rest || !index || !coarse.xyz || !coarse.triangles) status = MICA_ERR_OUT_OF_MEMORY;
  if (status == MICA_OK) status = mica_body_get_rest_positions(world, body, rest, nodes, NULL);
  if (status == MICA_OK) status = mica_body_get_surface(world, body, coarse.triangles, triangles, NULL);
  if (status == MICA_OK) {
    for (int32_t i = 0; i < nodes; ++i) index[i] = -1;
    for (int32_t c = 0; c < 3 * triangles; ++c) {
      int32_t* v = &coarse.triangles[c];
      if (index[*v] < 0) {
        index[*v] = coarse.vertex_count++;
        memcpy(coarse.xyz + 3 * (size_t)index[*v], rest + 3 * (size_t)*v, 3 * sizeof(double));
      }
      *v = index[*v];
    }
    coarse.triangle_count = triangles;
    status = fine_surface_split(&coarse, divisions, out);
  }
  free(rest);
  free(index);
  fine_surface_free(&coarse);
  return status;
}

void fine_surface_free(fine_surface* s) {
  free(s->xyz);
  free(s->triangles);
  memset(s, 0, sizeof *s);
}
