/* SPDX-License-Identifier: Apache-2.0 */
/* Bad input to capi/tool.cpp through the C ABI: tool creation and its def, poses, forces, stale
 * tool ids. The checks are in bad_input_util.h. */
#include "bad_input_util.h"

/* In the fixture world: a live tool and a destroyed one (made by setup_tools). */
static mica_tool_id g_tool, g_dead_tool;

static const double kP[3] = {0, 0, 0}, kQ[4] = {1, 0, 0, 0};

/* Creates a tool that must fail: *out_tool stays 0. */
static mica_status create_tool(bad_call* c, mica_world* w, const mica_tool_def* def) {
  mica_tool_id out = 0;
  return id_unwritten(c, "out_tool", &out, mica_tool_create(w, def, &out));
}

/* Reads a force that must fail: nothing is written. */
static mica_status get_force(bad_call* c, mica_world* w, mica_tool_id id) {
  double out[6] = {SENTINEL_D, SENTINEL_D, SENTINEL_D, SENTINEL_D, SENTINEL_D, SENTINEL_D}; /* force, torque */
  int32_t contacts = SENTINEL_I;
  const mica_status s = mica_tool_get_force(w, id, out, out + 3, &contacts);
  if (contacts != SENTINEL_I) bad_wrong(c, "*out_contacts was written");
  return doubles_unwritten(c, out, 6, s);
}

/* ------------------------------------------------------------------------------------------ */
/* NULL pointers                                                                               */

static mica_status create_without_world(bad_call* c) {
  const mica_tool_def good = mica_tool_def_default();
  return create_tool(c, NULL, &good);
}
static mica_status destroy_without_world(bad_call* c) {
  (void)c;
  return mica_tool_destroy(NULL, g_tool);
}
static mica_status pose_without_world(bad_call* c) {
  (void)c;
  return mica_tool_set_pose(NULL, g_tool, kP, kQ);
}
static mica_status force_without_world(bad_call* c) { return get_force(c, NULL, g_tool); }
static mica_status create_with_null(bad_call* c) {
  const mica_tool_def good = mica_tool_def_default();
  mica_tool_id out = 0;
  return id_unwritten(c, "out_tool", &out, mica_tool_create(c->fx->world, NULL_IF(0, &good), NULL_IF(1, &out)));
}
static mica_status pose_with_null(bad_call* c) {
  return mica_tool_set_pose(c->fx->world, g_tool, NULL_IF(0, kP), NULL_IF(1, kQ));
}

static const bad_case kNullCases[] = {
    {"mica_tool_create: NULL world", create_without_world, MICA_ERR_NULL_ARGUMENT, "world", .no_world = NO_WORLD},
    {"mica_tool_destroy: NULL world", destroy_without_world, MICA_ERR_NULL_ARGUMENT, "world", .no_world = NO_WORLD},
    {"mica_tool_set_pose: NULL world", pose_without_world, MICA_ERR_NULL_ARGUMENT, "world", .no_world = NO_WORLD},
    {"mica_tool_get_force: NULL world", force_without_world, MICA_ERR_NULL_ARGUMENT, "world", .no_world = NO_WORLD},
    {"mica_tool_def_init: NULL def", def_init_without_def, MICA_ERR_NULL_ARGUMENT, "def", .with.arg = TOOL_DEF,
     .no_world = NO_WORLD},
    {"mica_tool_create: NULL def", create_with_null, MICA_ERR_NULL_ARGUMENT, "def", .with.arg = 0},
    {"mica_tool_create: NULL out_tool", create_with_null, MICA_ERR_NULL_ARGUMENT, "out_tool", .with.arg = 1},
    {"mica_tool_set_pose: NULL position", pose_with_null, MICA_ERR_NULL_ARGUMENT, "position", .with.arg = 0},
    {"mica_tool_set_pose: NULL orientation", pose_with_null, MICA_ERR_NULL_ARGUMENT, "orientation", .with.arg = 1},
};

/* ------------------------------------------------------------------------------------------ */
/* The def                                                                                     */

/* Non-finite values (the value i) and values outside the domain, each with its shape. */
static void radius_nonfinite(mica_tool_def* d, int i) {
  d->shape = MICA_TOOL_SPHERE;
  d->radius = kNonfinite[i];
}
static void normal_nonfinite(mica_tool_def* d, int i) {
  d->shape = MICA_TOOL_PLANE;
  d->normal[1] = kNonfinite[i];
}
static void sphere_position_nonfinite(mica_tool_def* d, int i) {
  d->shape = MICA_TOOL_SPHERE;
  d->position[2] = kNonfinite[i];
}
static void plane_position_nonfinite(mica_tool_def* d, int i) {
  d->shape = MICA_TOOL_PLANE;
  d->position[2] = kNonfinite[i];
}
static void sphere_orientation_w_nonfinite(mica_tool_def* d, int i) {
  d->shape = MICA_TOOL_SPHERE;
  d->orientation[0] = kNonfinite[i];
}
static void plane_orientation_z_nonfinite(mica_tool_def* d, int i) {
  d->shape = MICA_TOOL_PLANE;
  d->orientation[3] = kNonfinite[i];
}
static void margin_nonfinite(mica_tool_def* d, int i) {
  d->shape = MICA_TOOL_SPHERE;
  d->margin = kNonfinite[i];
}
static const double kBadRadius[] = {0.0, -0.01};
static void radius_outside(mica_tool_def* d, int i) { d->radius = kBadRadius[i]; }
static void margin_negative(mica_tool_def* d, int i) {
  (void)i;
  d->margin = -1e-3;
}
static void plane_normal_zero(mica_tool_def* d, int i) {
  (void)i;
  d->shape = MICA_TOOL_PLANE;
  d->normal[0] = d->normal[1] = d->normal[2] = 0;
}
static const int32_t kBadShape[] = {5, -1, 42};
static void shape(mica_tool_def* d, int i) { d->shape = kBadShape[i]; }

static mica_status create_spoiled(bad_call* c) {
  mica_tool_def d = mica_tool_def_default();
  c->with.tool_def(&d, c->i);
  return create_tool(c, c->fx->world, &d);
}

static mica_status create_with_bad_size(bad_call* c) {
  any_def d;
  memset(&d, 0, sizeof d);
  d.tool = mica_tool_def_default();
  d.tool.struct_size = bad_struct_size(c->i, sizeof d.tool);
  return create_tool(c, c->fx->world, &d.tool);
}
static const bad_case kDefCases[] = {
    {"mica_tool_create: non-finite radius", create_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 3,
     {.tool_def = radius_nonfinite}},
    {"mica_tool_create: non-finite normal", create_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 3,
     {.tool_def = normal_nonfinite}},
    {"mica_tool_create: non-finite position, sphere", create_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 3,
     {.tool_def = sphere_position_nonfinite}},
    {"mica_tool_create: non-finite position, plane", create_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 3,
     {.tool_def = plane_position_nonfinite}},
    {"mica_tool_create: non-finite orientation, sphere", create_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 3,
     {.tool_def = sphere_orientation_w_nonfinite}},
    {"mica_tool_create: non-finite orientation, plane", create_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 3,
     {.tool_def = plane_orientation_z_nonfinite}},
    {"mica_tool_create: non-finite margin", create_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 3,
     {.tool_def = margin_nonfinite}},
    {"mica_tool_create: radius <= 0", create_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, COUNT_OF(kBadRadius),
     {.tool_def = radius_outside}},
    {"mica_tool_create: margin < 0", create_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 1, {.tool_def = margin_negative}},
    {"mica_tool_create: zero plane normal", create_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 1,
     {.tool_def = plane_normal_zero}},
    {"mica_tool_create: shape", create_spoiled, MICA_ERR_INVALID_ARGUMENT, "shape", COUNT_OF(kBadShape),
     {.tool_def = shape}},
    {"mica_tool_create: struct_size", create_with_bad_size, MICA_ERR_STRUCT_SIZE, "struct_size", 3},
    {"mica_tool_def_init: struct_size", def_init_with_bad_size, MICA_ERR_STRUCT_SIZE, NULL, 3, .with.arg = TOOL_DEF,
     .no_world = NO_WORLD},
};

/* ------------------------------------------------------------------------------------------ */
/* Poses and ids                                                                               */

/* Position component i % 3 non-finite (the value i / 3). */
static mica_status pose_nonfinite_position(bad_call* c) {
  double p[3] = {0, 0, 0};
  p[c->i % 3] = kNonfinite[c->i / 3];
  return mica_tool_set_pose(c->fx->world, g_tool, p, kQ);
}
/* Orientation component i % 4 non-finite (the value i / 4). */
static mica_status pose_nonfinite_orientation(bad_call* c) {
  double q[4] = {1, 0, 0, 0};
  q[c->i % 4] = kNonfinite[c->i / 4];
  return mica_tool_set_pose(c->fx->world, g_tool, kP, q);
}
static mica_status pose_zero_orientation(bad_call* c) {
  const double zero_q[4] = {0, 0, 0, 0};
  return mica_tool_set_pose(c->fx->world, g_tool, kP, zero_q);
}

/* Ids that name no live tool: destroyed, a body's, a constraint's, null, made up (tool kind,
 * generation 1, slot 99), all ones. The message names the id. */
static mica_tool_id stale_tool(bad_call* c) {
  const mica_tool_id bad[6] = {g_dead_tool, c->fx->body, c->fx->lpc, MICA_NULL_ID, 0x0300000100000063u, UINT64_MAX};
  hex_id(bad[c->i], c->needle[0], sizeof c->needle[0]);
  return bad[c->i];
}
static mica_status destroy_stale(bad_call* c) { return mica_tool_destroy(c->fx->world, stale_tool(c)); }
static mica_status pose_stale(bad_call* c) { return mica_tool_set_pose(c->fx->world, stale_tool(c), kP, kQ); }
static mica_status force_of_stale(bad_call* c) { return get_force(c, c->fx->world, stale_tool(c)); }

/* A tool id where a body or a constraint id is expected. */
static mica_status tool_as_body(bad_call* c) {
  int32_t n = SENTINEL_I;
  const mica_status s = mica_body_get_counts(c->fx->world, g_tool, &n, NULL, NULL);
  if (n != SENTINEL_I) bad_wrong(c, "*out_nodes was written");
  return s;
}
static mica_status tool_as_lpc(bad_call* c) { return mica_lpc_remove(c->fx->world, g_tool); }

static const bad_case kPoseAndIdCases[] = {
    {"mica_tool_set_pose: non-finite position", pose_nonfinite_position, MICA_ERR_INVALID_ARGUMENT, NULL, 9},
    {"mica_tool_set_pose: non-finite orientation", pose_nonfinite_orientation, MICA_ERR_INVALID_ARGUMENT, NULL, 12},
    {"mica_tool_set_pose: zero orientation", pose_zero_orientation, MICA_ERR_INVALID_ARGUMENT, NULL},
    {"mica_tool_destroy: stale id", destroy_stale, MICA_ERR_STALE_ID, NULL, 6},
    {"mica_tool_set_pose: stale id", pose_stale, MICA_ERR_STALE_ID, NULL, 6},
    {"mica_tool_get_force: stale id", force_of_stale, MICA_ERR_STALE_ID, NULL, 6},
    {"mica_body_get_counts: a tool id", tool_as_body, MICA_ERR_STALE_ID, NULL},
    {"mica_lpc_remove: a tool id", tool_as_lpc, MICA_ERR_STALE_ID, NULL},
};

/* The fixture with a live tool and a destroyed one. */
static int setup_tools(void** state) {
  if (setup(state) != 0) return -1;
  fixture* fx = *state;
  const mica_tool_def good = mica_tool_def_default();
  g_tool = g_dead_tool = 0;
  if (mica_tool_create(fx->world, &good, &g_tool) != MICA_OK) return -1;
  if (mica_tool_create(fx->world, &good, &g_dead_tool) != MICA_OK) return -1;
  return mica_tool_destroy(fx->world, g_dead_tool) == MICA_OK ? 0 : -1;
}

/* The live tool removed, so that the teardown's step, which a tool in a DIRECT world would turn
 * into MICA_ERR_UNSUPPORTED, still tests the world. */
static int teardown_tools(void** state) {
  fixture* fx = *state;
  const mica_status s = mica_tool_destroy(fx->world, g_tool);
  return teardown(state) == 0 && s == MICA_OK ? 0 : -1;
}

static void test_null_pointers(void** state) { RUN_BAD_CASES((fixture*)*state, kNullCases); }
static void test_bad_tool_def(void** state) { RUN_BAD_CASES((fixture*)*state, kDefCases); }

static void test_bad_poses_and_ids(void** state) {
  fixture* fx = *state;
  RUN_BAD_CASES(fx, kPoseAndIdCases);
  /* The live tool still works, all outputs optional. */
  EXPECT_STATUS(MICA_OK, mica_tool_get_force(fx->world, g_tool, NULL, NULL, NULL));
}

/* A zero quaternion is no rotation: refused at creation as mica_tool_set_pose refuses it. (A
 * wrongly created tool is removed, for the teardown's step.) */
static void test_zero_orientation_at_creation(void** state) {
  fixture* fx = *state;
  mica_tool_def d = mica_tool_def_default();
  d.orientation[0] = d.orientation[1] = d.orientation[2] = d.orientation[3] = 0;
  mica_tool_id out = 0;
  const mica_status zero_status = mica_tool_create(fx->world, &d, &out);
  if (zero_status == MICA_OK) mica_tool_destroy(fx->world, out);
  fx->log_calls = 0;
  EXPECT_STATUS(MICA_ERR_INVALID_ARGUMENT, zero_status);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_null_pointers, setup_tools, teardown_tools),
      cmocka_unit_test_setup_teardown(test_bad_tool_def, setup_tools, teardown_tools),
      cmocka_unit_test_setup_teardown(test_bad_poses_and_ids, setup_tools, teardown_tools),
      cmocka_unit_test_setup_teardown(test_zero_orientation_at_creation, setup_tools, teardown_tools),
  };
  return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
