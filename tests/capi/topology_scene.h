/* SPDX-License-Identifier: Apache-2.0 */
/* What the topology tests (resection, incision, blades) share: reading a body's mesh, its mass,
 * its positions, its pieces, and saving a world's state. Needs cmocka and capi_ok.h first. */
#ifndef MICA_TESTS_TOPOLOGY_SCENE_H
#define MICA_TESTS_TOPOLOGY_SCENE_H
#include <math.h>
#include <stdlib.h>

#include <mica/mica.h>

typedef struct {
  int32_t nodes, tets;
  double* rest; /* 3 a node */
  int32_t* tet; /* 4 a tet */
} mesh;

static inline mesh get_mesh(mica_world* w, mica_body_id body) {
  mesh m;
  OK(w, mica_body_get_counts(w, body, &m.nodes, &m.tets, NULL));
  m.rest = malloc(sizeof(double) * 3 * (size_t)m.nodes);
  m.tet = malloc(sizeof(int32_t) * 4 * (size_t)m.tets);
  OK(w, mica_body_get_rest_positions(w, body, m.rest, m.nodes, NULL));
  OK(w, mica_body_get_tets(w, body, m.tet, m.tets, NULL));
  return m;
}

static inline void free_mesh(mesh* m) {
  free(m->rest);
  free(m->tet);
}

static inline double rest_centroid_x(const mesh* m, int32_t e) {
  double x = 0;
  for (int a = 0; a < 4; ++a) x += 0.25 * m->rest[3 * m->tet[4 * e + a]];
  return x;
}

/* det[X1-X0, X2-X0, X3-X0] / 6 of points p (3 a node) for tet e: positive for a well-made tet. */
static inline double signed_volume(const double* p, const mesh* m, int32_t e) {
  const double* q[4];
  for (int a = 0; a < 4; ++a) q[a] = p + 3 * m->tet[4 * e + a];
  double d[3][3];
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < 3; ++k) d[a][k] = q[a + 1][k] - q[0][k];
  return (d[0][0] * (d[1][1] * d[2][2] - d[1][2] * d[2][1]) - d[0][1] * (d[1][0] * d[2][2] - d[1][2] * d[2][0]) +
          d[0][2] * (d[1][0] * d[2][1] - d[1][1] * d[2][0])) / 6;
}

static inline double rest_volume(const mesh* m, int32_t e) { return fabs(signed_volume(m->rest, m, e)); }

static inline double total_mass(mica_world* w, mica_body_id body) {
  int32_t n = 0;
  OK(w, mica_body_get_counts(w, body, &n, NULL, NULL));
  double* m = malloc(sizeof(double) * (size_t)n);
  OK(w, mica_body_get_node_masses(w, body, m, n, NULL));
  double sum = 0;
  for (int32_t i = 0; i < n; ++i) sum += m[i];
  free(m);
  return sum;
}

static inline double* get_positions(mica_world* w, mica_body_id body, int32_t* n) {
  OK(w, mica_body_get_counts(w, body, n, NULL, NULL));
  double* x = malloc(sizeof(double) * 3 * (size_t)*n);
  OK(w, mica_body_get_positions(w, body, x, *n, NULL));
  return x;
}

static inline uint8_t* save(mica_world* w, size_t* bytes) {
  OK(w, mica_world_state_size(w, bytes));
  uint8_t* buffer = malloc(*bytes);
  OK(w, mica_world_save_state(w, buffer, *bytes));
  return buffer;
}

static inline int32_t piece_root(int32_t* parent, int32_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

/* The pieces of a mesh (nodes joined by tets): fills piece[i] (0..count-1, in order of first
 * node) and returns the count. */
static inline int32_t find_pieces(const mesh* m, int32_t* piece) {
  int32_t* parent = malloc(sizeof(int32_t) * (size_t)m->nodes);
  for (int32_t i = 0; i < m->nodes; ++i) parent[i] = i;
  for (int32_t e = 0; e < m->tets; ++e)
    for (int a = 1; a < 4; ++a) parent[piece_root(parent, m->tet[4 * e + a])] = piece_root(parent, m->tet[4 * e]);
  int32_t count = 0;
  for (int32_t i = 0; i < m->nodes; ++i) piece[i] = -1;
  for (int32_t i = 0; i < m->nodes; ++i) {
    const int32_t r = piece_root(parent, i);
    if (piece[r] < 0) piece[r] = count++;
    piece[i] = piece[r];
  }
  free(parent);
  return count;
}

/* A changed body against a fresh one: makes, in world b (as world a was made), a body of `bd` from
 * the exported mesh of a's `body`, with its positions and velocities and the nodes of a's `fixed`
 * group fixed (their count in *held), steps both worlds once by `dt` and returns the largest
 * difference of their positions over `scale`: 0 when nothing the world kept of the old topology
 * (factors, warm starts, scratch, colourings) is left. */
static inline double step_against_fresh(mica_world* a, mica_body_id body, mica_lpc_id fixed, mica_world* b,
                                        const mica_body_def* bd, double dt, double scale, int32_t* held) {
  mesh m = get_mesh(a, body);
  mica_body_id fresh = 0;
  OK(b, mica_body_create(b, bd, m.rest, m.nodes, m.tet, m.tets, &fresh));
  int32_t n = 0;
  double* x = get_positions(a, body, &n);
  double* v = malloc(sizeof(double) * 3 * (size_t)n);
  OK(a, mica_body_get_velocities(a, body, v, n, NULL));
  OK(b, mica_body_set_positions(b, fresh, x, n));
  OK(b, mica_body_set_velocities(b, fresh, v, n));
  int32_t nodes[256];
  OK(a, mica_lpc_get_nodes(a, fixed, nodes, 256, held));
  const mica_lpc_def def = mica_lpc_def_default();
  mica_lpc_id again = 0;
  OK(b, mica_add_lpc(b, fresh, nodes, *held, &def, &again));
  OK(a, mica_step(a, dt));
  OK(b, mica_step(b, dt));
  int32_t na = 0, nb = 0;
  double* xa = get_positions(a, body, &na);
  double* xb = get_positions(b, fresh, &nb);
  assert_int_equal(na, nb);
  double worst = 0;
  for (int32_t i = 0; i < 3 * na; ++i) worst = fmax(worst, fabs(xa[i] - xb[i]) / scale);
  free(xa), free(xb), free(x), free(v);
  free_mesh(&m);
  return worst;
}

#endif
