/* SPDX-License-Identifier: Apache-2.0 */
/* Bad input to capi/lpc.cpp through the C ABI: linear projective constraints, their def, their
 * nodes, stale constraint ids, reactions; and grasps driven by a device (mica_device_def.lpc,
 * since 0.6). The checks are in bad_input_util.h. */
#include "bad_input_util.h"

#include <mica/mica_device.h>

static const int32_t kTwoNodes[2] = {1, 2};

/* Adds a constraint that must fail: *out_lpc stays 0. */
static mica_status add_lpc(bad_call* c, const int32_t* nodes, int32_t count, const mica_lpc_def* def) {
  mica_lpc_id out = 0;
  return id_unwritten(c, "out_lpc", &out, mica_add_lpc(c->fx->world, c->fx->body, nodes, count, def, &out));
}

/* Reads a reaction that must fail: the force is not written. */
static mica_status get_reaction(bad_call* c, mica_world* w, mica_lpc_id id) {
  double f[3] = {SENTINEL_D, SENTINEL_D, SENTINEL_D};
  return doubles_unwritten(c, f, 3, mica_lpc_get_reaction(w, id, f));
}

/* ------------------------------------------------------------------------------------------ */
/* NULL pointers                                                                               */

static mica_status add_without_world(bad_call* c) {
  const int32_t nodes[1] = {0};
  const mica_lpc_def ld = mica_lpc_def_default();
  mica_lpc_id out = 0;
  return id_unwritten(c, "out_lpc", &out, mica_add_lpc(NULL, c->fx->body, nodes, 1, &ld, &out));
}
static mica_status remove_without_world(bad_call* c) { return mica_lpc_remove(NULL, c->fx->lpc); }
static mica_status reaction_without_world(bad_call* c) { return get_reaction(c, NULL, c->fx->lpc); }
static mica_status add_with_null(bad_call* c) {
  const int32_t nodes[1] = {0};
  const mica_lpc_def ld = mica_lpc_def_default();
  mica_lpc_id out = 0;
  return id_unwritten(c, "out_lpc", &out,
                      mica_add_lpc(c->fx->world, c->fx->body, NULL_IF(0, nodes), 1, NULL_IF(1, &ld), NULL_IF(2, &out)));
}
static mica_status reaction_into_null(bad_call* c) { return mica_lpc_get_reaction(c->fx->world, c->fx->lpc, NULL); }

static const bad_case kNullCases[] = {
    {"mica_add_lpc: NULL world", add_without_world, MICA_ERR_NULL_ARGUMENT, "world", .no_world = NO_WORLD},
    {"mica_lpc_remove: NULL world", remove_without_world, MICA_ERR_NULL_ARGUMENT, "world", .no_world = NO_WORLD},
    {"mica_lpc_get_reaction: NULL world", reaction_without_world, MICA_ERR_NULL_ARGUMENT, "world",
     .no_world = NO_WORLD},
    {"mica_lpc_def_init: NULL def", def_init_without_def, MICA_ERR_NULL_ARGUMENT, "def", .with.arg = LPC_DEF,
     .no_world = NO_WORLD},
    {"mica_add_lpc: NULL nodes", add_with_null, MICA_ERR_NULL_ARGUMENT, "nodes", .with.arg = 0},
    {"mica_add_lpc: NULL def", add_with_null, MICA_ERR_NULL_ARGUMENT, "def", .with.arg = 1},
    {"mica_add_lpc: NULL out_lpc", add_with_null, MICA_ERR_NULL_ARGUMENT, "out_lpc", .with.arg = 2},
    {"mica_lpc_get_reaction: NULL out_force", reaction_into_null, MICA_ERR_NULL_ARGUMENT, "out_force"},
};

static void test_null_pointers(void** state) { RUN_BAD_CASES((fixture*)*state, kNullCases); }

/* ------------------------------------------------------------------------------------------ */
/* The def: non-finite and degenerate directions and velocities, kinds, struct sizes           */

/* A def of the given kind whose directions are valid for every kind. */
static mica_lpc_def lpc_def(int32_t kind) {
  mica_lpc_def d = mica_lpc_def_default();
  d.kind = kind;
  d.direction[0][0] = 0;
  d.direction[0][2] = 1;
  d.direction[1][0] = 1;
  d.direction[1][1] = 0;
  return d;
}

/* direction[0] (used by every kind here) of the kind .with.arg, its component i % 3 non-finite
 * (the value i / 3). */
static mica_status add_nonfinite_direction0(bad_call* c) {
  mica_lpc_def d = lpc_def(c->with.arg);
  d.direction[0][c->i % 3] = kNonfinite[c->i / 3];
  return add_lpc(c, kTwoNodes, 2, &d);
}
/* direction[1] of the two-direction kind. */
static mica_status add_nonfinite_direction1(bad_call* c) {
  mica_lpc_def d = lpc_def(MICA_LPC_TWO_DIRS);
  d.direction[1][c->i % 3] = kNonfinite[c->i / 3];
  return add_lpc(c, kTwoNodes, 2, &d);
}
/* The prescribed velocity of the kind .with.arg. */
static mica_status add_nonfinite_velocity(bad_call* c) {
  mica_lpc_def d = mica_lpc_def_default();
  d.kind = c->with.arg;
  d.velocity[c->i % 3] = kNonfinite[c->i / 3];
  return add_lpc(c, kTwoNodes, 2, &d);
}
/* Zero and parallel directions are outside the domain too. */
static mica_status add_zero_direction(bad_call* c) {
  mica_lpc_def d = mica_lpc_def_default();
  d.kind = c->with.arg;
  d.direction[0][0] = d.direction[0][1] = d.direction[0][2] = 0;
  return add_lpc(c, kTwoNodes, 2, &d);
}
static mica_status add_parallel_directions(bad_call* c) {
  mica_lpc_def d = mica_lpc_def_default();
  d.kind = MICA_LPC_TWO_DIRS;
  d.direction[0][0] = 1;
  d.direction[0][1] = 0;
  d.direction[1][0] = -2;
  d.direction[1][1] = 0;
  return add_lpc(c, kTwoNodes, 2, &d);
}
static const int32_t kBadKind[] = {42, -1, 4};
static mica_status add_bad_kind(bad_call* c) {
  mica_lpc_def d = mica_lpc_def_default();
  d.kind = kBadKind[c->i];
  return add_lpc(c, kTwoNodes, 2, &d);
}

static mica_status add_with_bad_size(bad_call* c) {
  any_def d;
  memset(&d, 0, sizeof d);
  d.lpc = mica_lpc_def_default();
  d.lpc.struct_size = bad_struct_size(c->i, sizeof d.lpc);
  return add_lpc(c, kTwoNodes, 2, &d.lpc);
}
static const bad_case kDefCases[] = {
    {"mica_add_lpc: non-finite direction[0], plane", add_nonfinite_direction0, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     .with.arg = MICA_LPC_PLANE},
    {"mica_add_lpc: non-finite direction[0], line", add_nonfinite_direction0, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     .with.arg = MICA_LPC_LINE},
    {"mica_add_lpc: non-finite direction[0], two directions", add_nonfinite_direction0, MICA_ERR_INVALID_ARGUMENT, NULL,
     9, .with.arg = MICA_LPC_TWO_DIRS},
    {"mica_add_lpc: non-finite direction[1], two directions", add_nonfinite_direction1, MICA_ERR_INVALID_ARGUMENT, NULL,
     9},
    {"mica_add_lpc: non-finite velocity, fixed", add_nonfinite_velocity, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     .with.arg = MICA_LPC_FIXED},
    {"mica_add_lpc: non-finite velocity, plane", add_nonfinite_velocity, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     .with.arg = MICA_LPC_PLANE},
    {"mica_add_lpc: non-finite velocity, line", add_nonfinite_velocity, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     .with.arg = MICA_LPC_LINE},
    {"mica_add_lpc: non-finite velocity, two directions", add_nonfinite_velocity, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     .with.arg = MICA_LPC_TWO_DIRS},
    {"mica_add_lpc: zero direction, plane", add_zero_direction, MICA_ERR_INVALID_ARGUMENT, NULL,
     .with.arg = MICA_LPC_PLANE},
    {"mica_add_lpc: zero direction, line", add_zero_direction, MICA_ERR_INVALID_ARGUMENT, NULL,
     .with.arg = MICA_LPC_LINE},
    {"mica_add_lpc: parallel directions", add_parallel_directions, MICA_ERR_INVALID_ARGUMENT, "parallel"},
    {"mica_add_lpc: kind", add_bad_kind, MICA_ERR_INVALID_ARGUMENT, "kind", COUNT_OF(kBadKind)},
    {"mica_add_lpc: struct_size", add_with_bad_size, MICA_ERR_STRUCT_SIZE, "struct_size", 3},
    {"mica_lpc_def_init: struct_size", def_init_with_bad_size, MICA_ERR_STRUCT_SIZE, NULL, 3, .with.arg = LPC_DEF,
     .no_world = NO_WORLD},
};

static void test_bad_lpc_def(void** state) { RUN_BAD_CASES((fixture*)*state, kDefCases); }

/* ------------------------------------------------------------------------------------------ */
/* Nodes and counts                                                                            */

/* A node index out of range (the index i) at position .with.arg of three, which the message names. */
static mica_status add_on_bad_node(bad_call* c) {
  const mica_lpc_def d = mica_lpc_def_default();
  const int32_t bad[3] = {-1, c->fx->node_count, INT32_MAX};
  int32_t nodes[3] = {0, 1, 2};
  nodes[c->with.arg] = bad[c->i];
  bad_needle(c, 0, "%d", bad[c->i]);
  return add_lpc(c, nodes, 3, &d);
}
static const int32_t kBadCount[] = {-1, INT32_MIN, 0};
static mica_status add_bad_count(bad_call* c) {
  const int32_t nodes[1] = {0};
  const mica_lpc_def ld = mica_lpc_def_default();
  return add_lpc(c, nodes, kBadCount[c->i], &ld);
}

static const bad_case kNodeCases[] = {
    {"mica_add_lpc: node out of range at position 0", add_on_bad_node, MICA_ERR_OUT_OF_RANGE, "position 0", 3,
     .with.arg = 0},
    {"mica_add_lpc: node out of range at position 2", add_on_bad_node, MICA_ERR_OUT_OF_RANGE, "position 2", 3,
     .with.arg = 2},
    {"mica_add_lpc: count", add_bad_count, MICA_ERR_INVALID_ARGUMENT, "count", COUNT_OF(kBadCount)},
};

static void test_bad_nodes(void** state) { RUN_BAD_CASES((fixture*)*state, kNodeCases); }

/* ------------------------------------------------------------------------------------------ */
/* Stale ids                                                                                   */

/* Ids that name no live constraint: removed, a body's, a destroyed body's, null, made up
 * (constraint kind, generation 1, slot 99), all ones. The message names the id. */
static mica_lpc_id stale_lpc(bad_call* c) {
  const mica_lpc_id bad[6] = {c->fx->dead_lpc, c->fx->body,         c->fx->dead_body,
                              MICA_NULL_ID,    0x0200000100000063u, UINT64_MAX};
  hex_id(bad[c->i], c->needle[0], sizeof c->needle[0]);
  return bad[c->i];
}
static mica_status remove_stale(bad_call* c) { return mica_lpc_remove(c->fx->world, stale_lpc(c)); }
static mica_status reaction_of_stale(bad_call* c) { return get_reaction(c, c->fx->world, stale_lpc(c)); }

static const bad_case kStaleCases[] = {
    {"mica_lpc_remove: stale id", remove_stale, MICA_ERR_STALE_ID, NULL, 6},
    {"mica_lpc_get_reaction: stale id", reaction_of_stale, MICA_ERR_STALE_ID, NULL, 6},
};

static void test_stale_lpc_ids(void** state) {
  fixture* fx = *state;
  RUN_BAD_CASES(fx, kStaleCases);
  /* The live constraint answers with finite numbers. */
  double f[3] = {SENTINEL_D, SENTINEL_D, SENTINEL_D};
  EXPECT_STATUS(MICA_OK, mica_lpc_get_reaction(fx->world, fx->lpc, f));
  assert_true(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2]));
  /* The live constraint is still there: removing it works once, then it is stale. */
  EXPECT_STATUS(MICA_OK, mica_lpc_remove(fx->world, fx->lpc));
  char hex[32];
  EXPECT_FAIL(fx, MICA_ERR_STALE_ID, mica_lpc_remove(fx->world, fx->lpc), hex_id(fx->lpc, hex, sizeof hex));
}

/* ------------------------------------------------------------------------------------------ */
/* A device driving a grasp (mica_device_def.lpc)                                              */

/* Made by setup_driven in the fixture world: a grab a (null) device drives, a tool and a grab
 * following it (forceps). */
static mica_lpc_id g_grab, g_forceps;
static mica_tool_id g_tool;
static mica_device_id g_device;

static mica_status create_device(bad_call* c, const mica_device_def* d) {
  mica_device_id out = 0;
  return id_unwritten(c, "out_device", &out, mica_device_create(c->fx->world, d, &out));
}
static mica_status device_with_tool_and_lpc(bad_call* c) {
  mica_device_def d = mica_device_def_default();
  d.lpc = g_grab;
  d.tool = g_tool;
  return create_device(c, &d);
}
/* Ids that name no live constraint (MICA_NULL_ID is "no grasp", not stale). */
static mica_status device_with_stale_lpc(bad_call* c) {
  const mica_lpc_id bad[5] = {c->fx->dead_lpc, c->fx->body, c->fx->dead_body, 0x0200000100000063u, UINT64_MAX};
  hex_id(bad[c->i], c->needle[0], sizeof c->needle[0]);
  mica_device_def d = mica_device_def_default();
  d.lpc = bad[c->i];
  return create_device(c, &d);
}
static mica_status device_on_lpc_without_handle(bad_call* c) {
  mica_device_def d = mica_device_def_default();
  d.lpc = c->fx->lpc;
  return create_device(c, &d);
}
static mica_status device_on_forceps(bad_call* c) {
  mica_device_def d = mica_device_def_default();
  d.lpc = g_forceps;
  return create_device(c, &d);
}
static mica_status remove_driven_grab(bad_call* c) { return mica_lpc_remove(c->fx->world, g_grab); }
static mica_status destroy_body_of_driven_grab(bad_call* c) { return mica_body_destroy(c->fx->world, c->fx->body); }
static mica_status move_driven_handle(bad_call* c) {
  const double p[3] = {0.3, 0.1, 0.1}, q[4] = {1, 0, 0, 0};
  return mica_lpc_set_handle_pose(c->fx->world, g_grab, p, q);
}

static const bad_case kDrivenCases[] = {
    {"mica_device_create: both tool and lpc", device_with_tool_and_lpc, MICA_ERR_INVALID_ARGUMENT, "not both"},
    {"mica_device_create: stale lpc", device_with_stale_lpc, MICA_ERR_STALE_ID, NULL, 5},
    {"mica_device_create: lpc without a handle", device_on_lpc_without_handle, MICA_ERR_INVALID_ARGUMENT, "no handle"},
    {"mica_device_create: lpc whose handle follows a tool", device_on_forceps, MICA_ERR_INVALID_ARGUMENT,
     "follows a tool"},
    {"mica_lpc_remove: a device drives it", remove_driven_grab, MICA_ERR_WRONG_STATE, "destroy the device first"},
    {"mica_body_destroy: a device drives a grasp on it", destroy_body_of_driven_grab, MICA_ERR_WRONG_STATE,
     "destroy the device first"},
    {"mica_lpc_set_handle_pose: a device moves it", move_driven_handle, MICA_ERR_WRONG_STATE, "move the device"},
};

static int setup_driven(void** state) {
  if (setup(state) != 0) return -1;
  fixture* fx = *state;
  const mica_tool_def td = mica_tool_def_default();
  if (mica_tool_create(fx->world, &td, &g_tool) != MICA_OK) return -1;
  if (mica_lpc_grab(fx->world, fx->body, kHi, 1e-3, MICA_NULL_ID, &g_grab) != MICA_OK) return -1;
  if (mica_lpc_grab(fx->world, fx->body, kHi, 1e-3, g_tool, &g_forceps) != MICA_OK) return -1;
  mica_device_def dd = mica_device_def_default();
  dd.lpc = g_grab;
  return mica_device_create(fx->world, &dd, &g_device) == MICA_OK ? 0 : -1;
}

/* Once the device is gone the grasp goes as any other (and the tool, which a DIRECT world would
 * refuse to step with). */
static int teardown_driven(void** state) {
  fixture* fx = *state;
  const int bad = mica_device_destroy(fx->world, g_device) != MICA_OK || mica_lpc_remove(fx->world, g_grab) != MICA_OK ||
                  mica_lpc_remove(fx->world, g_forceps) != MICA_OK || mica_tool_destroy(fx->world, g_tool) != MICA_OK;
  return teardown(state) == 0 && !bad ? 0 : -1;
}

static void test_driven_grasps(void** state) { RUN_BAD_CASES((fixture*)*state, kDrivenCases); }

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_null_pointers, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_lpc_def, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_nodes, setup, teardown),
      cmocka_unit_test_setup_teardown(test_stale_lpc_ids, setup, teardown),
      cmocka_unit_test_setup_teardown(test_driven_grasps, setup_driven, teardown_driven),
  };
  return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
