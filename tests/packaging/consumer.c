/* SPDX-License-Identifier: Apache-2.0 */
/* A program built against the *installed* libmica (pkg-config or find_package(mica)):
 * a box fixed on its x = 0 face sags under gravity. Exits non-zero with a message on failure. */
#include <mica/mica.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

static int failures = 0;

#define CHECK(cond, ...)                                      \
  do {                                                        \
    if (!(cond)) {                                            \
      fprintf(stderr, "consumer: %s:%d: ", __FILE__, __LINE__); \
      fprintf(stderr, __VA_ARGS__);                           \
      fprintf(stderr, "\n");                                  \
      failures++;                                             \
    }                                                         \
  } while (0)

/* A failed call makes the rest meaningless: report it and stop. */
#define CALL(world, expr)                                                                 \
  do {                                                                                    \
    mica_status status_ = (expr);                                                         \
    if (status_ < 0) {                                                                    \
      fprintf(stderr, "consumer: %s:%d: %s -> %s (%s)\n", __FILE__, __LINE__, #expr,      \
              mica_status_string(status_), mica_world_last_error(world));                 \
      exit(1);                                                                            \
    }                                                                                     \
  } while (0)

int main(void) {
  const double lo[3] = {0.0, 0.0, 0.0};
  const double hi[3] = {0.2, 0.05, 0.05};
  const int32_t cells[3] = {4, 1, 1};
  const double plane_point[3] = {0.0, 0.0, 0.0};
  const double plane_normal[3] = {1.0, 0.0, 0.0};
  const double dt = 0.01;
  const int steps = 10;
  /* Free fall over the run (implicit Euler: g dt^2 n(n+1)/2 = 0.054 m) bounds any motion. */
  const double max_motion = 0.1;

  CHECK(mica_version() == MICA_VERSION_NUMBER, "mica_version() = %d, header says %d",
        (int)mica_version(), MICA_VERSION_NUMBER);

  mica_world_def world_def = mica_world_def_default();
  mica_world* world = NULL;
  CALL(NULL, mica_world_create(&world_def, &world));
  CHECK(world != NULL, "mica_world_create returned no world");
  if (!world) return 1;

  mica_body_def body_def = mica_body_def_default();
  mica_body_id body = MICA_NULL_ID;
  CALL(world, mica_body_create_box(world, &body_def, lo, hi, cells, 6, &body));
  CHECK(body != MICA_NULL_ID, "mica_body_create_box returned the null id");

  int32_t node_count = 0;
  CALL(world, mica_body_get_counts(world, body, &node_count, NULL, NULL));
  CHECK(node_count == 5 * 2 * 2, "box has %d nodes, expected 20", (int)node_count);

  /* Fix the x = 0 face: query the count, then fill the buffer. */
  int32_t fixed_count = 0;
  CALL(world, mica_body_select_nodes_by_plane(world, body, plane_point, plane_normal, 1e-9, 1,
                                              NULL, 0, &fixed_count));
  CHECK(fixed_count == 4, "x = 0 face has %d nodes, expected 4", (int)fixed_count);
  int32_t* fixed = malloc(sizeof *fixed * (size_t)(fixed_count > 0 ? fixed_count : 1));
  CALL(world, mica_body_select_nodes_by_plane(world, body, plane_point, plane_normal, 1e-9, 1,
                                              fixed, fixed_count, &fixed_count));
  mica_lpc_def lpc_def = mica_lpc_def_default();
  mica_lpc_id lpc = MICA_NULL_ID;
  CALL(world, mica_add_lpc(world, body, fixed, fixed_count, &lpc_def, &lpc));
  CHECK(lpc != MICA_NULL_ID, "mica_add_lpc returned the null id");

  double* rest = malloc(sizeof *rest * 3 * (size_t)node_count);
  double* pos = malloc(sizeof *pos * 3 * (size_t)node_count);
  int32_t count = 0;
  CALL(world, mica_body_get_rest_positions(world, body, rest, node_count, &count));

  for (int i = 0; i < steps; ++i) CALL(world, mica_step(world, dt));

  CALL(world, mica_body_get_positions(world, body, pos, node_count, &count));
  CHECK(count == node_count, "got %d positions, expected %d", (int)count, (int)node_count);

  double mean_dy = 0.0;
  for (int32_t n = 0; n < count; ++n) {
    for (int k = 0; k < 3; ++k) {
      double d = pos[3 * n + k] - rest[3 * n + k];
      CHECK(isfinite(pos[3 * n + k]), "node %d coordinate %d is not finite", (int)n, k);
      CHECK(fabs(d) <= max_motion, "node %d moved %g m along axis %d (more than free fall)",
            (int)n, d, k);
    }
    mean_dy += (pos[3 * n + 1] - rest[3 * n + 1]) / count;
  }
  CHECK(mean_dy < -1e-6, "the body did not sag under gravity (mean dy = %g m)", mean_dy);

  for (int32_t i = 0; i < fixed_count; ++i) {
    const int32_t n = fixed[i];
    for (int k = 0; k < 3; ++k)
      CHECK(fabs(pos[3 * n + k] - rest[3 * n + k]) < 1e-9, "fixed node %d moved", (int)n);
  }

  free(pos);
  free(rest);
  free(fixed);
  mica_world_destroy(world);

  if (failures) {
    fprintf(stderr, "consumer: %d check(s) failed\n", failures);
    return 1;
  }
  printf("consumer: libmica %d OK, mean sag %.4g m after %d steps\n", (int)mica_version(),
         -mean_dy, steps);
  return 0;
}
