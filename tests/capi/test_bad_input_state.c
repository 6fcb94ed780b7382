/* SPDX-License-Identifier: Apache-2.0 */
/* Bad input to capi/state.cpp and the node setters of capi/body.cpp through the C ABI: setting
 * positions and velocities, saving and restoring a state, reading contacts. The checks (status,
 * message, log, the world bit-identical afterwards) are in bad_input_util.h. */
#include "bad_input_util.h"

/* 3 * n values: the fixture body's current positions, with `bad` at value `at` (at < 0: none). */
static double* node_values(fixture* fx, int at, double bad) {
  double* v = malloc(sizeof(double) * 3 * (size_t)(fx->node_count + 1));
  mica_body_get_positions(fx->world, fx->body, v, fx->node_count, NULL);
  if (at >= 0) v[at] = bad;
  return v;
}

static void test_set_positions_and_velocities(void** state) {
  fixture* fx = *state;
  const int32_t n = fx->node_count;
  double* ok = node_values(fx, -1, 0);
  typedef mica_status (*setter)(mica_world*, mica_body_id, const double*, int32_t);
  const setter setters[2] = {mica_body_set_positions, mica_body_set_velocities};
  const char* what[2] = {"positions", "velocities"};
  for (int s = 0; s < 2; ++s) {
    const setter set = setters[s];
    EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, set(NULL, fx->body, ok, n), "world");
    EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, set(fx->world, fx->body, NULL, n), "xyz");
    EXPECT_FAIL(fx, MICA_ERR_STALE_ID, set(fx->world, fx->dead_body, ok, n), NULL);
    EXPECT_FAIL(fx, MICA_ERR_STALE_ID, set(fx->world, MICA_NULL_ID, ok, n), NULL);
    EXPECT_FAIL(fx, MICA_ERR_STALE_ID, set(fx->world, fx->lpc, ok, n), NULL);
    const int32_t counts[5] = {n - 1, n + 1, 0, -1, INT32_MAX};
    for (int c = 0; c < 5; ++c)
      EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, set(fx->world, fx->body, ok, counts[c]), "node_count");
    const int at[3] = {0, 3 * (n / 2) + 1, 3 * n - 1};
    for (int k = 0; k < 3; ++k)
      for (int b = 0; b < 3; ++b) {
        double* bad = node_values(fx, at[k], kNonfinite[b]);
        char node[32];
        snprintf(node, sizeof node, "node %d", at[k] / 3);
        EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, set(fx->world, fx->body, bad, n), what[s], node, "not finite");
        free(bad);
      }
  }
  /* A static body has no velocities. */
  mica_body_def sd = mica_body_def_default();
  sd.is_static = 1;
  sd.translation[1] = -1;
  mica_body_id wall;
  REQUIRE_OK_W(fx->world, mica_body_create_box(fx->world, &sd, kLo, kHi, kCells, 6, &wall));
  double* wall_v = calloc(3 * (size_t)n, sizeof(double));
  EXPECT_FAIL(fx, MICA_ERR_WRONG_STATE, mica_body_set_velocities(fx->world, wall, wall_v, n), "static");
  free(wall_v);
  REQUIRE_OK_W(fx->world, mica_body_destroy(fx->world, wall));
  free(ok);
}

static void test_save_and_restore(void** state) {
  fixture* fx = *state;
  size_t bytes = 0;
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_world_state_size(NULL, &bytes), "world");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_world_state_size(fx->world, NULL), "out_bytes");
  REQUIRE_OK_W(fx->world, mica_world_state_size(fx->world, &bytes));
  unsigned char* saved = malloc(bytes);
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_world_save_state(NULL, saved, bytes), "world");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_world_save_state(fx->world, NULL, bytes), "buffer");
  EXPECT_FAIL(fx, MICA_ERR_BUFFER_TOO_SMALL, mica_world_save_state(fx->world, saved, bytes - 1), "bytes");
  EXPECT_FAIL(fx, MICA_ERR_BUFFER_TOO_SMALL, mica_world_save_state(fx->world, saved, 0), "bytes");
  REQUIRE_OK_W(fx->world, mica_world_save_state(fx->world, saved, bytes));
  /* Step on, so that a restore that did anything would show. */
  REQUIRE_OK_W(fx->world, mica_step(fx->world, 0.01));

  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_world_restore_state(NULL, saved, bytes), "world");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_world_restore_state(fx->world, NULL, bytes), "buffer");
  const size_t lengths[4] = {0, 8, bytes / 2, bytes - 1};
  for (int k = 0; k < 4; ++k)
    EXPECT_FAIL(fx, MICA_ERR_PARSE, mica_world_restore_state(fx->world, saved, lengths[k]), "truncated");
  unsigned char* longer = calloc(bytes + 8, 1);
  memcpy(longer, saved, bytes);
  EXPECT_FAIL(fx, MICA_ERR_PARSE, mica_world_restore_state(fx->world, longer, bytes + 8), "bytes");
  free(longer);
  unsigned char* bad = malloc(bytes);
  memcpy(bad, saved, bytes);
  bad[0] = 'X';
  EXPECT_FAIL(fx, MICA_ERR_PARSE, mica_world_restore_state(fx->world, bad, bytes), "MICASTAT");
  memcpy(bad, saved, bytes);
  bad[bytes - 3] ^= 1;
  EXPECT_FAIL(fx, MICA_ERR_PARSE, mica_world_restore_state(fx->world, bad, bytes), "checksum");
  free(bad);

  /* A state of another world: its body has other counts; another with an extra tool. */
  fixture* other = new_fixture(MICA_SOLVER_DIRECT, MICA_SWEEP_FACTORED);
  assert_non_null(other);
  REQUIRE_OK_W(fx->world, mica_world_state_size(fx->world, &bytes));
  const mica_tool_def td = mica_tool_def_default();
  mica_tool_id tool;
  REQUIRE_OK_W(other->world, mica_tool_create(other->world, &td, &tool));
  size_t other_bytes = 0;
  REQUIRE_OK_W(other->world, mica_world_state_size(other->world, &other_bytes));
  unsigned char* foreign = malloc(other_bytes);
  REQUIRE_OK_W(other->world, mica_world_save_state(other->world, foreign, other_bytes));
  EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_restore_state(fx->world, foreign, other_bytes), "shape",
              "tool");
  free(foreign);
  mica_world_destroy(other->world);
  free(other);
  free(saved);
}

static void test_get_contacts(void** state) {
  fixture* fx = *state;
  mica_contact out[4];
  memset(out, 0, sizeof out);
  out[0].struct_size = sizeof out[0];
  int32_t count = SENTINEL_I;
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_world_get_contacts(NULL, out, 4, &count), "world");
  EXPECT_FAIL(fx, MICA_ERR_NULL_ARGUMENT, mica_world_get_contacts(fx->world, NULL, 0, NULL), "out_count");
  EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_world_get_contacts(fx->world, out, -1, &count), "capacity");
  const uint32_t sizes[3] = {0, (uint32_t)sizeof out[0] - 8, (uint32_t)sizeof out[0] + 8};
  for (int k = 0; k < 3; ++k) {
    out[0].struct_size = sizes[k];
    EXPECT_FAIL(fx, MICA_ERR_STRUCT_SIZE, mica_world_get_contacts(fx->world, out, 4, &count), "struct_size");
  }
  assert_int_equal(count, SENTINEL_I);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_set_positions_and_velocities, setup, teardown),
      cmocka_unit_test_setup_teardown(test_save_and_restore, setup, teardown),
      cmocka_unit_test_setup_teardown(test_get_contacts, setup, teardown),
  };
  return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
