/* SPDX-License-Identifier: Apache-2.0 */
/* Bad input to capi/body.cpp through the C ABI: the three body creators and their def, meshes
 * and mesh files, node forces, selections, materials per tet, getters and their buffers, stale
 * body ids. The checks
 * are in bad_input_util.h. */
#include "bad_input_util.h"

/* The two-tet mesh as a file, written once. */
static const char* two_tet_file(void) { return write_tmp("two_tets.msh", kTwoTetMsh); }

/* ------------------------------------------------------------------------------------------ */
/* Calls on a body                                                                             */

enum body_call {
  DESTROY,
  GET_COUNTS,
  GET_POSITIONS,
  GET_VELOCITIES,
  GET_REST_POSITIONS,
  GET_SURFACE,
  POSITIONS_VIEW,
  SET_NODE_FORCES,
  SELECT_IN_BOX,
  SELECT_BY_PLANE,
  GET_ENERGY,
  GET_TETS,
  GET_TET_REGIONS,
  SET_MATERIALS,
  GET_NODE_MASSES,
  GET_STRAINS,
  GET_VON_MISES,
  WORLDLESS_BODY_CALLS, /* the calls above are also made without a world */
  SIZE_QUERY = WORLDLESS_BODY_CALLS,
  CLEAR_FORCES,
  ADD_LPC,
  WRITE_VTK,
  BODY_CALLS
};

/* One of the calls that take a body id, which must fail: no output is written, no file made. */
static mica_status call_on_body(bad_call* c, mica_world* w, mica_body_id id, int which) {
  const double v3[3] = {0, 0, 0}, n3[3] = {1, 0, 0};
  const int32_t nodes[1] = {0};
  const double forces[3] = {0, 0, 1};
  const mica_lpc_def ld = mica_lpc_def_default();
  double buf[3 * 64];
  int32_t ibuf[3 * 256];
  for (size_t k = 0; k < COUNT_OF(buf); ++k) buf[k] = SENTINEL_D;
  for (size_t k = 0; k < COUNT_OF(ibuf); ++k) ibuf[k] = SENTINEL_I;
  int32_t count = SENTINEL_I, nn = SENTINEL_I, nt = SENTINEL_I, ntri = SENTINEL_I;
  const double* view = NULL;
  mica_lpc_id out_lpc = 0;
  double e1 = SENTINEL_D, e2 = SENTINEL_D, e3 = SENTINEL_D;
  const char* vtk = tmp_path("stale.vtk");
  unlink(vtk);
  mica_status s = MICA_OK;
  switch (which) {
#define CALL(name, args) c->called = #name, s = name args
    case DESTROY: CALL(mica_body_destroy, (w, id)); break;
    case GET_COUNTS: CALL(mica_body_get_counts, (w, id, &nn, &nt, &ntri)); break;
    case GET_POSITIONS: CALL(mica_body_get_positions, (w, id, buf, 64, &count)); break;
    case GET_VELOCITIES: CALL(mica_body_get_velocities, (w, id, buf, 64, &count)); break;
    case GET_REST_POSITIONS: CALL(mica_body_get_rest_positions, (w, id, buf, 64, &count)); break;
    case GET_SURFACE: CALL(mica_body_get_surface, (w, id, ibuf, 256, &count)); break;
    case POSITIONS_VIEW: CALL(mica_body_positions_view, (w, id, &view, &count)); break;
    case SET_NODE_FORCES: CALL(mica_body_set_node_forces, (w, id, nodes, forces, 1)); break;
    case SELECT_IN_BOX: CALL(mica_body_select_nodes_in_box, (w, id, kLo, kHi, 1, ibuf, 256, &count)); break;
    case SELECT_BY_PLANE: CALL(mica_body_select_nodes_by_plane, (w, id, v3, n3, 0.0, 1, ibuf, 256, &count)); break;
    case GET_ENERGY: CALL(mica_body_get_energy, (w, id, &e1, &e2, &e3)); break;
    case GET_TETS: CALL(mica_body_get_tets, (w, id, ibuf, 192, &count)); break;
    case GET_TET_REGIONS: CALL(mica_body_get_tet_regions, (w, id, ibuf, 256, &count)); break;
    case SET_MATERIALS: CALL(mica_body_set_materials, (w, id, NULL, NULL, NULL, 18)); break;
    case GET_NODE_MASSES: CALL(mica_body_get_node_masses, (w, id, buf, 64, &count)); break;
    case GET_STRAINS: CALL(mica_body_get_strains, (w, id, buf, 32, &count)); break;
    case GET_VON_MISES: CALL(mica_body_get_von_mises, (w, id, buf, 64, &count)); break;
    case SIZE_QUERY: CALL(mica_body_get_positions, (w, id, NULL, 0, &count)); break;
    case CLEAR_FORCES: CALL(mica_body_set_node_forces, (w, id, NULL, NULL, 0)); break;
    case ADD_LPC: CALL(mica_add_lpc, (w, id, nodes, 1, &ld, &out_lpc)); break;
    case WRITE_VTK: CALL(mica_body_write_vtk, (w, id, vtk)); break;
#undef CALL
  }
  if (count != SENTINEL_I || nn != SENTINEL_I || nt != SENTINEL_I || ntri != SENTINEL_I)
    bad_wrong(c, "a count was written");
  if (view) bad_wrong(c, "*out was written");
  if (out_lpc != 0) bad_wrong(c, "*out_lpc was written");
  if (e1 != SENTINEL_D || e2 != SENTINEL_D || e3 != SENTINEL_D) bad_wrong(c, "an energy was written");
  for (size_t k = 0; k < COUNT_OF(ibuf); ++k)
    if (ibuf[k] != SENTINEL_I) bad_wrong(c, "the index buffer was written (item %zu)", k);
  if (access(vtk, F_OK) == 0) bad_wrong(c, "%s was written", vtk);
  return doubles_unwritten(c, buf, COUNT_OF(buf), s);
}

enum creator { CREATE, CREATE_FROM_FILE, CREATE_BOX, CREATORS };

/* A body made by one of the three creators from `bd`, which must fail: *out_body stays 0. */
static mica_status create_body(bad_call* c, mica_world* w, const mica_body_def* bd, int creator) {
  mica_body_id out = 0;
  mica_status s = MICA_OK;
  switch (creator) {
    case CREATE:
      c->called = "mica_body_create";
      s = mica_body_create(w, bd, kTwoTetNodes, 5, kTwoTets, 2, &out);
      break;
    case CREATE_FROM_FILE:
      c->called = "mica_body_create_from_file";
      s = mica_body_create_from_file(w, bd, two_tet_file(), &out);
      break;
    case CREATE_BOX:
      c->called = "mica_body_create_box";
      s = mica_body_create_box(w, bd, kLo, kHi, kCells, 6, &out);
      break;
  }
  return id_unwritten(c, "out_body", &out, s);
}

/* ------------------------------------------------------------------------------------------ */
/* NULL pointers                                                                               */

static mica_status body_without_world(bad_call* c) { return call_on_body(c, NULL, c->fx->body, c->i); }
static mica_status create_without_world(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  return create_body(c, NULL, &bd, c->with.arg);
}

static mica_status create_with_null(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out,
                      mica_body_create(c->fx->world, NULL_IF(0, &bd), NULL_IF(1, kTwoTetNodes), 5, NULL_IF(2, kTwoTets),
                                       2, NULL_IF(3, &out)));
}
static mica_status create_from_file_with_null(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  mica_body_id out = 0;
  return id_unwritten(
      c, "out_body", &out,
      mica_body_create_from_file(c->fx->world, &bd, NULL_IF(0, tmp_path("valid_for_null.msh")), NULL_IF(1, &out)));
}
static mica_status create_box_with_null(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out,
                      mica_body_create_box(c->fx->world, NULL_IF(0, &bd), NULL_IF(1, kLo), NULL_IF(2, kHi),
                                           NULL_IF(3, kCells), 6, NULL_IF(4, &out)));
}
static mica_status set_node_forces_with_null(bad_call* c) {
  const int32_t nodes[1] = {0};
  const double forces[3] = {0, 0, 1};
  return mica_body_set_node_forces(c->fx->world, c->fx->body, NULL_IF(0, nodes), NULL_IF(1, forces), 1);
}
static mica_status select_in_box_with_null(bad_call* c) {
  int32_t ibuf[256], count = 0;
  const int size_query = c->with.arg == 2; /* neither a buffer nor a count: nowhere to answer */
  return mica_body_select_nodes_in_box(c->fx->world, c->fx->body, NULL_IF(0, kLo), NULL_IF(1, kHi), 1,
                                       size_query ? NULL : ibuf, size_query ? 0 : 256, NULL_IF(2, &count));
}
static mica_status select_by_plane_with_null(bad_call* c) {
  const double v3[3] = {0, 0, 0}, n3[3] = {1, 0, 0};
  int32_t ibuf[256], count = 0;
  const int size_query = c->with.arg == 2;
  return mica_body_select_nodes_by_plane(c->fx->world, c->fx->body, NULL_IF(0, v3), NULL_IF(1, n3), 0.0, 1,
                                         size_query ? NULL : ibuf, size_query ? 0 : 256, NULL_IF(2, &count));
}
/* A size query with neither a buffer nor a count has nowhere to answer. */
static mica_status nowhere_to_answer(bad_call* c) {
  mica_world* w = c->fx->world;
  const mica_body_id b = c->fx->body;
  switch (c->with.arg) {
    case GET_POSITIONS: return mica_body_get_positions(w, b, NULL, 0, NULL);
    case GET_VELOCITIES: return mica_body_get_velocities(w, b, NULL, 0, NULL);
    case GET_REST_POSITIONS: return mica_body_get_rest_positions(w, b, NULL, 0, NULL);
    case GET_SURFACE: return mica_body_get_surface(w, b, NULL, 0, NULL);
    case GET_TETS: return mica_body_get_tets(w, b, NULL, 0, NULL);
    case GET_TET_REGIONS: return mica_body_get_tet_regions(w, b, NULL, 0, NULL);
    case GET_NODE_MASSES: return mica_body_get_node_masses(w, b, NULL, 0, NULL);
    case GET_STRAINS: return mica_body_get_strains(w, b, NULL, 0, NULL);
    case GET_VON_MISES: return mica_body_get_von_mises(w, b, NULL, 0, NULL);
    default: {
      int32_t count = 0;
      return mica_body_positions_view(w, b, NULL, &count);
    }
  }
}

static const bad_case kNullCases[] = {
    {"NULL world", body_without_world, MICA_ERR_NULL_ARGUMENT, "world", WORLDLESS_BODY_CALLS, .no_world = NO_WORLD},
    {"NULL world", create_without_world, MICA_ERR_NULL_ARGUMENT, "world", .with.arg = CREATE, .no_world = NO_WORLD},
    {"NULL world", create_without_world, MICA_ERR_NULL_ARGUMENT, "world", .with.arg = CREATE_FROM_FILE,
     .no_world = NO_WORLD},
    {"NULL world", create_without_world, MICA_ERR_NULL_ARGUMENT, "world", .with.arg = CREATE_BOX, .no_world = NO_WORLD},
    {"mica_body_def_init: NULL def", def_init_without_def, MICA_ERR_NULL_ARGUMENT, "def", .with.arg = BODY_DEF,
     .no_world = NO_WORLD},
    {"mica_body_create: NULL def", create_with_null, MICA_ERR_NULL_ARGUMENT, "def", .with.arg = 0},
    {"mica_body_create: NULL nodes", create_with_null, MICA_ERR_NULL_ARGUMENT, "nodes", .with.arg = 1},
    {"mica_body_create: NULL tets", create_with_null, MICA_ERR_NULL_ARGUMENT, "tets", .with.arg = 2},
    {"mica_body_create: NULL out_body", create_with_null, MICA_ERR_NULL_ARGUMENT, "out_body", .with.arg = 3},
    {"mica_body_create_from_file: NULL path", create_from_file_with_null, MICA_ERR_NULL_ARGUMENT, "path",
     .with.arg = 0},
    {"mica_body_create_from_file: NULL out_body", create_from_file_with_null, MICA_ERR_NULL_ARGUMENT, "out_body",
     .with.arg = 1},
    {"mica_body_create_box: NULL def", create_box_with_null, MICA_ERR_NULL_ARGUMENT, "def", .with.arg = 0},
    {"mica_body_create_box: NULL lo", create_box_with_null, MICA_ERR_NULL_ARGUMENT, "lo", .with.arg = 1},
    {"mica_body_create_box: NULL hi", create_box_with_null, MICA_ERR_NULL_ARGUMENT, "hi", .with.arg = 2},
    {"mica_body_create_box: NULL cells", create_box_with_null, MICA_ERR_NULL_ARGUMENT, "cells", .with.arg = 3},
    {"mica_body_create_box: NULL out_body", create_box_with_null, MICA_ERR_NULL_ARGUMENT, "out_body", .with.arg = 4},
    {"mica_body_get_positions: nowhere to answer", nowhere_to_answer, MICA_ERR_NULL_ARGUMENT, "out_count",
     .with.arg = GET_POSITIONS},
    {"mica_body_get_velocities: nowhere to answer", nowhere_to_answer, MICA_ERR_NULL_ARGUMENT, "out_count",
     .with.arg = GET_VELOCITIES},
    {"mica_body_get_rest_positions: nowhere to answer", nowhere_to_answer, MICA_ERR_NULL_ARGUMENT, "out_count",
     .with.arg = GET_REST_POSITIONS},
    {"mica_body_get_surface: nowhere to answer", nowhere_to_answer, MICA_ERR_NULL_ARGUMENT, "out_count",
     .with.arg = GET_SURFACE},
    {"mica_body_get_tets: nowhere to answer", nowhere_to_answer, MICA_ERR_NULL_ARGUMENT, "out_count",
     .with.arg = GET_TETS},
    {"mica_body_get_tet_regions: nowhere to answer", nowhere_to_answer, MICA_ERR_NULL_ARGUMENT, "out_count",
     .with.arg = GET_TET_REGIONS},
    {"mica_body_get_node_masses: nowhere to answer", nowhere_to_answer, MICA_ERR_NULL_ARGUMENT, "out_count",
     .with.arg = GET_NODE_MASSES},
    {"mica_body_get_strains: nowhere to answer", nowhere_to_answer, MICA_ERR_NULL_ARGUMENT, "out_count",
     .with.arg = GET_STRAINS},
    {"mica_body_get_von_mises: nowhere to answer", nowhere_to_answer, MICA_ERR_NULL_ARGUMENT, "out_count",
     .with.arg = GET_VON_MISES},
    {"mica_body_positions_view: NULL out", nowhere_to_answer, MICA_ERR_NULL_ARGUMENT, "out",
     .with.arg = POSITIONS_VIEW},
    {"mica_body_set_node_forces: NULL nodes", set_node_forces_with_null, MICA_ERR_NULL_ARGUMENT, "nodes",
     .with.arg = 0},
    {"mica_body_set_node_forces: NULL forces", set_node_forces_with_null, MICA_ERR_NULL_ARGUMENT, "forces",
     .with.arg = 1},
    {"mica_body_select_nodes_in_box: NULL lo", select_in_box_with_null, MICA_ERR_NULL_ARGUMENT, "lo", .with.arg = 0},
    {"mica_body_select_nodes_in_box: NULL hi", select_in_box_with_null, MICA_ERR_NULL_ARGUMENT, "hi", .with.arg = 1},
    {"mica_body_select_nodes_in_box: nowhere to answer", select_in_box_with_null, MICA_ERR_NULL_ARGUMENT, "out_count",
     .with.arg = 2},
    {"mica_body_select_nodes_by_plane: NULL point", select_by_plane_with_null, MICA_ERR_NULL_ARGUMENT, "point",
     .with.arg = 0},
    {"mica_body_select_nodes_by_plane: NULL normal", select_by_plane_with_null, MICA_ERR_NULL_ARGUMENT, "normal",
     .with.arg = 1},
    {"mica_body_select_nodes_by_plane: nowhere to answer", select_by_plane_with_null, MICA_ERR_NULL_ARGUMENT,
     "out_count", .with.arg = 2},
};

static void test_null_pointers(void** state) { RUN_BAD_CASES((fixture*)*state, kNullCases); }

/* Optional outputs really are optional. */
static void test_optional_outputs_may_be_null(void** state) {
  fixture* fx = *state;
  EXPECT_STATUS(MICA_OK, mica_body_get_counts(fx->world, fx->body, NULL, NULL, NULL));
  EXPECT_STATUS(MICA_OK, mica_body_get_energy(fx->world, fx->body, NULL, NULL, NULL));
  const double* view = NULL;
  EXPECT_STATUS(MICA_OK, mica_body_positions_view(fx->world, fx->body, &view, NULL));
  assert_non_null(view);
  EXPECT_STATUS(MICA_OK, mica_body_set_node_forces(fx->world, fx->body, NULL, NULL, 0));
  double* x = calloc(3 * (size_t)fx->node_count, sizeof(double));
  EXPECT_STATUS(MICA_OK, mica_body_get_positions(fx->world, fx->body, x, fx->node_count, NULL));
  assert_memory_equal(x, view, 3 * (size_t)fx->node_count * sizeof(double));
  free(x);
}

/* ------------------------------------------------------------------------------------------ */
/* The body def                                                                                */

/* Non-finite: the variant's value i / 3 through the creator i % 3. */
static void youngs_nonfinite(mica_body_def* d, int i) { d->youngs_modulus = kNonfinite[i]; }
static void poisson_nonfinite(mica_body_def* d, int i) { d->poisson_ratio = kNonfinite[i]; }
static void density_nonfinite(mica_body_def* d, int i) { d->density = kNonfinite[i]; }
static void alpha_nonfinite(mica_body_def* d, int i) { d->rayleigh_alpha = kNonfinite[i]; }
static void beta_nonfinite(mica_body_def* d, int i) { d->rayleigh_beta = kNonfinite[i]; }
static void translation0_nonfinite(mica_body_def* d, int i) { d->translation[0] = kNonfinite[i]; }
static void translation2_nonfinite(mica_body_def* d, int i) { d->translation[2] = kNonfinite[i]; }
static void velocity1_nonfinite(mica_body_def* d, int i) { d->velocity[1] = kNonfinite[i]; }
static void velocity2_nonfinite(mica_body_def* d, int i) { d->velocity[2] = kNonfinite[i]; }

static mica_status create_any_spoiled(bad_call* c) {
  mica_body_def bd = mica_body_def_default();
  c->with.body_def(&bd, c->i / CREATORS);
  return create_body(c, c->fx->world, &bd, c->i % CREATORS);
}

/* Finite values outside the domain, and bad enums, through mica_body_create_box. */
static const double kBadYoungs[] = {0.0, -1e4};
static void youngs_outside(mica_body_def* d, int i) { d->youngs_modulus = kBadYoungs[i]; }
static const double kBadPoisson[] = {0.5, 0.7, -0.1};
static void poisson_outside(mica_body_def* d, int i) { d->poisson_ratio = kBadPoisson[i]; }
/* Finite, positive, but beyond what the step's matrix can hold in double precision. */
static const double kHugeYoungs[] = {1e300, 1e200};
static void youngs_huge(mica_body_def* d, int i) { d->youngs_modulus = kHugeYoungs[i]; }
static const double kTinyDensity[] = {1e-300, 1e-200};
static void density_tiny(mica_body_def* d, int i) { d->density = kTinyDensity[i]; }
static const double kBadDensity[] = {0.0, -1};
static void density_outside(mica_body_def* d, int i) { d->density = kBadDensity[i]; }
static void alpha_negative(mica_body_def* d, int i) {
  (void)i;
  d->rayleigh_alpha = -1e-3;
}
static void beta_negative(mica_body_def* d, int i) {
  (void)i;
  d->rayleigh_beta = -1e-3;
}
static const int32_t kBadModel[] = {7, -1, 3}; /* 2 is MICA_MODEL_NEO_HOOKEAN since 0.8 */
static void model(mica_body_def* d, int i) { d->model = kBadModel[i]; }
static const int32_t kBadMass[] = {-1, 2, 100};
static void mass(mica_body_def* d, int i) { d->mass = kBadMass[i]; }
static const int32_t kBadStatic[] = {2, -1, INT32_MAX};
static void is_static(mica_body_def* d, int i) { d->is_static = kBadStatic[i]; }

static mica_status create_box_spoiled(bad_call* c) {
  mica_body_def bd = mica_body_def_default();
  c->with.body_def(&bd, c->i);
  return create_body(c, c->fx->world, &bd, CREATE_BOX);
}

/* A bad model through mica_body_create_box (even variants) and mica_body_create (odd). */
static mica_status create_box_or_mesh_spoiled(bad_call* c) {
  mica_body_def bd = mica_body_def_default();
  c->with.body_def(&bd, c->i / 2);
  return create_body(c, c->fx->world, &bd, c->i % 2 ? CREATE : CREATE_BOX);
}

/* A struct_size that is not the def's (i / 3) through creator i % 3. */
static mica_status create_with_bad_size(bad_call* c) {
  any_def d;
  memset(&d, 0, sizeof d);
  d.body = mica_body_def_default();
  d.body.struct_size = bad_struct_size(c->i / CREATORS, sizeof d.body);
  return create_body(c, c->fx->world, &d.body, c->i % CREATORS);
}

static const bad_case kDefCases[] = {
    {"body def: non-finite youngs_modulus", create_any_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     {.body_def = youngs_nonfinite}},
    {"body def: non-finite poisson_ratio", create_any_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     {.body_def = poisson_nonfinite}},
    {"body def: non-finite density", create_any_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     {.body_def = density_nonfinite}},
    {"body def: non-finite rayleigh_alpha", create_any_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     {.body_def = alpha_nonfinite}},
    {"body def: non-finite rayleigh_beta", create_any_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     {.body_def = beta_nonfinite}},
    {"body def: non-finite translation[0]", create_any_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     {.body_def = translation0_nonfinite}},
    {"body def: non-finite translation[2]", create_any_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     {.body_def = translation2_nonfinite}},
    {"body def: non-finite velocity[1]", create_any_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     {.body_def = velocity1_nonfinite}},
    {"body def: non-finite velocity[2]", create_any_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     {.body_def = velocity2_nonfinite}},
    {"body def: youngs_modulus <= 0", create_box_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, COUNT_OF(kBadYoungs),
     {.body_def = youngs_outside}},
    {"body def: poisson_ratio outside [0, 0.5)", create_box_spoiled, MICA_ERR_INVALID_ARGUMENT, "got",
     COUNT_OF(kBadPoisson), {.body_def = poisson_outside}},
    {"body def: youngs_modulus beyond double precision", create_box_spoiled, MICA_ERR_INVALID_ARGUMENT,
     "stiffness", COUNT_OF(kHugeYoungs), {.body_def = youngs_huge}},
    {"body def: density beyond double precision", create_box_spoiled, MICA_ERR_INVALID_ARGUMENT, "mass",
     COUNT_OF(kTinyDensity), {.body_def = density_tiny}},
    {"body def: density <= 0", create_box_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, COUNT_OF(kBadDensity),
     {.body_def = density_outside}},
    {"body def: rayleigh_alpha < 0", create_box_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 1,
     {.body_def = alpha_negative}},
    {"body def: rayleigh_beta < 0", create_box_spoiled, MICA_ERR_INVALID_ARGUMENT, NULL, 1,
     {.body_def = beta_negative}},
    {"body def: model", create_box_or_mesh_spoiled, MICA_ERR_INVALID_ARGUMENT, "model", 2 * COUNT_OF(kBadModel),
     {.body_def = model}},
    {"body def: mass", create_box_spoiled, MICA_ERR_INVALID_ARGUMENT, "mass", COUNT_OF(kBadMass), {.body_def = mass}},
    {"body def: is_static", create_box_spoiled, MICA_ERR_INVALID_ARGUMENT, "is_static", COUNT_OF(kBadStatic),
     {.body_def = is_static}},
    {"body def: struct_size", create_with_bad_size, MICA_ERR_STRUCT_SIZE, "struct_size", 3 * CREATORS},
    {"mica_body_def_init: struct_size", def_init_with_bad_size, MICA_ERR_STRUCT_SIZE, NULL, 3, .with.arg = BODY_DEF,
     .no_world = NO_WORLD},
};

static void test_bad_body_def(void** state) { RUN_BAD_CASES((fixture*)*state, kDefCases); }

/* ------------------------------------------------------------------------------------------ */
/* Meshes given as arrays, boxes                                                               */

/* A non-finite coordinate of node 0, 1, 2 or 4 (coordinates 0, 4, 8, 12); the value i % 3. */
static mica_status create_nonfinite_node(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  const int coordinate = 4 * (c->i / 3);
  double nodes[15];
  memcpy(nodes, kTwoTetNodes, sizeof nodes);
  nodes[coordinate] = kNonfinite[c->i % 3];
  bad_needle(c, 0, "node %d", coordinate / 3);
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out, mica_body_create(c->fx->world, &bd, nodes, 5, kTwoTets, 2, &out));
}

/* A node index out of range at a corner of tet 0 or tet 1 (.with.arg): the index i / 4, the
 * corner i % 4. */
static const int32_t kBadTetNode[] = {-1, 5, INT32_MAX};
static mica_status create_out_of_range_tet(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  int32_t tets[8];
  memcpy(tets, kTwoTets, sizeof tets);
  tets[4 * c->with.arg + c->i % 4] = kBadTetNode[c->i / 4];
  bad_needle(c, 0, "%d", kBadTetNode[c->i / 4]);
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out, mica_body_create(c->fx->world, &bd, kTwoTetNodes, 5, tets, 2, &out));
}

static const int32_t kBadNodeCount[] = {-1, INT32_MIN, 0, 3, INT32_MAX};
static mica_status create_bad_node_count(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out,
                      mica_body_create(c->fx->world, &bd, kTwoTetNodes, kBadNodeCount[c->i], kTwoTets, 2, &out));
}
static const int32_t kBadTetCount[] = {-1, INT32_MIN, 0};
static mica_status create_bad_tet_count(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out,
                      mica_body_create(c->fx->world, &bd, kTwoTetNodes, 5, kTwoTets, kBadTetCount[c->i], &out));
}

/* Degenerate meshes. */
static const int32_t kInverted1[8] = {0, 1, 2, 3, 2, 1, 3, 4}; /* two nodes of tet 1 swapped */
static const int32_t kInverted0[8] = {0, 1, 3, 2, 1, 2, 3, 4};
static const double kFlatNodes[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 0};
static const int32_t kFlatTets[8] = {0, 1, 2, 3, 0, 1, 4, 2}; /* tet 1: four nodes on z = 0 */
static const double kFlat4[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
static const double kSame4[12] = {1, 2, 3, 1, 2, 3, 1, 2, 3, 1, 2, 3};
static const int32_t kOneTet[4] = {0, 1, 2, 3};
static const double kSixNodes[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1, 5, 5, 5};
static const int32_t kRepeated[8] = {0, 1, 2, 3, 1, 2, 2, 4};
static const int32_t kAllSame[8] = {0, 1, 2, 3, 4, 4, 4, 4};
static const mesh_arrays kInvertedTet1 = {kTwoTetNodes, 5, kInverted1, 2};
static const mesh_arrays kInvertedTet0 = {kTwoTetNodes, 5, kInverted0, 2};
static const mesh_arrays kFlatTet1 = {kFlatNodes, 5, kFlatTets, 2};
static const mesh_arrays kFlatTet = {kFlat4, 4, kOneTet, 1};
static const mesh_arrays kPointTet = {kSame4, 4, kOneTet, 1};
static const mesh_arrays kUnusedNode5 = {kSixNodes, 6, kTwoTets, 2};
static const mesh_arrays kUnusedNode4 = {kTwoTetNodes, 5, kTwoTets, 1}; /* only tet 0 given */
static const mesh_arrays kRepeatedNode = {kTwoTetNodes, 5, kRepeated, 2};
static const mesh_arrays kOneNodeTet = {kTwoTetNodes, 5, kAllSame, 2};

static mica_status create_mesh(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  const mesh_arrays* m = c->with.mesh;
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out,
                      mica_body_create(c->fx->world, &bd, m->nodes, m->node_count, m->tets, m->tet_count, &out));
}

/* A non-finite corner coordinate k = i / 3 of lo or hi (.with.arg 0 or 1), the value i % 3. */
static mica_status create_box_nonfinite_corner(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  double corner[2][3] = {{0, 0, 0}, {1, 1, 1}};
  corner[c->with.arg][c->i / 3] = kNonfinite[c->i % 3];
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out,
                      mica_body_create_box(c->fx->world, &bd, corner[0], corner[1], kCells, 6 - c->with.arg, &out));
}
/* A box with hi[k] = .with.arg (0: empty, -1: inverted) for k = i. */
static mica_status create_flat_box(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  const double lo[3] = {0, 0, 0};
  double hi[3] = {1, 1, 1};
  hi[c->i] = c->with.arg;
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out, mica_body_create_box(c->fx->world, &bd, lo, hi, kCells, 6, &out));
}
static const int32_t kBadCells[4][3] = {{0, 1, 1}, {1, -1, 1}, {1, 1, INT32_MIN}, {-5, -5, -5}};
/* Cell counts whose node or tet count overflows 64-bit products must be refused as invalid,
 * not turned into a failed allocation. */
static const int32_t kHugeCells[4][3] = {{100000, 100000, 100000},
                                         {2097152, 2097152, 2097152},
                                         {INT32_MAX, INT32_MAX, 1},
                                         {INT32_MAX, INT32_MAX, INT32_MAX}};
static const int32_t kBadTetsPerCell[] = {4, 0, -5, 7, 12};
static mica_status create_box_bad_cells(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out, mica_body_create_box(c->fx->world, &bd, kLo, kHi, kBadCells[c->i], 6, &out));
}
/* The huge cell counts i / 2 with 6 and 5 tets per cell. */
static mica_status create_huge_box(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out,
                      mica_body_create_box(c->fx->world, &bd, kLo, kHi, kHugeCells[c->i / 2], 6 - c->i % 2, &out));
}
static mica_status create_box_bad_tets_per_cell(bad_call* c) {
  const mica_body_def bd = mica_body_def_default();
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out,
                      mica_body_create_box(c->fx->world, &bd, kLo, kHi, kCells, kBadTetsPerCell[c->i], &out));
}

static const bad_case kMeshCases[] = {
    {"mica_body_create: non-finite node coordinate", create_nonfinite_node, MICA_ERR_INVALID_ARGUMENT, NULL, 12},
    {"mica_body_create: node index out of range in tet 1", create_out_of_range_tet, MICA_ERR_OUT_OF_RANGE, "tet 1",
     4 * COUNT_OF(kBadTetNode), .with.arg = 1},
    {"mica_body_create: node index out of range in tet 0", create_out_of_range_tet, MICA_ERR_OUT_OF_RANGE, "tet 0",
     4 * COUNT_OF(kBadTetNode), .with.arg = 0},
    {"mica_body_create: node_count", create_bad_node_count, MICA_ERR_INVALID_ARGUMENT, "node_count",
     COUNT_OF(kBadNodeCount)},
    {"mica_body_create: tet_count", create_bad_tet_count, MICA_ERR_INVALID_ARGUMENT, "tet_count",
     COUNT_OF(kBadTetCount)},
    {"mica_body_create: tet 1 inverted", create_mesh, MICA_ERR_BAD_MESH, "tet 1", .with.mesh = &kInvertedTet1},
    {"mica_body_create: tet 0 inverted", create_mesh, MICA_ERR_BAD_MESH, "tet 0", .with.mesh = &kInvertedTet0},
    {"mica_body_create: tet 1 flat", create_mesh, MICA_ERR_BAD_MESH, "tet 1", .with.mesh = &kFlatTet1},
    {"mica_body_create: a single flat tet", create_mesh, MICA_ERR_BAD_MESH, "tet 0", .with.mesh = &kFlatTet},
    {"mica_body_create: a tet whose nodes coincide", create_mesh, MICA_ERR_BAD_MESH, "tet 0", .with.mesh = &kPointTet},
    {"mica_body_create: node 5 in no tet", create_mesh, MICA_ERR_BAD_MESH, "node 5", .with.mesh = &kUnusedNode5},
    {"mica_body_create: node 4 in no tet", create_mesh, MICA_ERR_BAD_MESH, "node 4", .with.mesh = &kUnusedNode4},
    {"mica_body_create: a node repeated in tet 1", create_mesh, MICA_ERR_BAD_MESH, "tet 1",
     .with.mesh = &kRepeatedNode},
    {"mica_body_create: tet 1 all one node", create_mesh, MICA_ERR_BAD_MESH, "tet 1", .with.mesh = &kOneNodeTet},
    {"mica_body_create_box: non-finite lo", create_box_nonfinite_corner, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     .with.arg = 0},
    {"mica_body_create_box: non-finite hi", create_box_nonfinite_corner, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     .with.arg = 1},
    {"mica_body_create_box: empty", create_flat_box, MICA_ERR_INVALID_ARGUMENT, NULL, 3, .with.arg = 0},
    {"mica_body_create_box: inverted", create_flat_box, MICA_ERR_INVALID_ARGUMENT, NULL, 3, .with.arg = -1},
    {"mica_body_create_box: cells", create_box_bad_cells, MICA_ERR_INVALID_ARGUMENT, "cells", COUNT_OF(kBadCells)},
    {"mica_body_create_box: huge cells", create_huge_box, MICA_ERR_INVALID_ARGUMENT, NULL, 2 * COUNT_OF(kHugeCells)},
    {"mica_body_create_box: tets_per_cell", create_box_bad_tets_per_cell, MICA_ERR_INVALID_ARGUMENT, "tets_per_cell",
     COUNT_OF(kBadTetsPerCell)},
};

static void test_bad_meshes(void** state) {
  fixture* fx = *state;
  /* The valid mesh is accepted (control), in a world of its own. */
  {
    const mica_body_def bd = mica_body_def_default();
    mica_body_id out = 0;
    mica_world_def wd = mica_world_def_default();
    mica_world* other = NULL;
    REQUIRE_OK(mica_world_create(&wd, &other));
    REQUIRE_OK_W(other, mica_body_create(other, &bd, kTwoTetNodes, 5, kTwoTets, 2, &out));
    mica_world_destroy(other);
  }
  RUN_BAD_CASES(fx, kMeshCases);
}

/* ------------------------------------------------------------------------------------------ */
/* Mesh files                                                                                  */

static mica_status create_from(bad_call* c, const char* path) {
  const mica_body_def bd = mica_body_def_default();
  mica_body_id out = 0;
  return id_unwritten(c, "out_body", &out, mica_body_create_from_file(c->fx->world, &bd, path, &out));
}
/* g_dir/<name>, which the message must name. */
static mica_status create_from_named(bad_call* c, const char* name) {
  bad_needle(c, 0, "%s/%s", g_dir, name);
  return create_from(c, c->needle[0]);
}
static mica_status create_from_missing_dir(bad_call* c) { return create_from_named(c, "no-such-dir/missing.msh"); }
static mica_status create_from_missing_node(bad_call* c) { return create_from_named(c, "missing.node"); }
static mica_status create_from_directory(bad_call* c) { return create_from_named(c, "directory.msh"); }
static mica_status create_from_stl(bad_call* c) {
  write_tmp("mesh.stl", "solid x\nendsolid x\n");
  return create_from_named(c, "mesh.stl");
}
static mica_status create_from_missing_obj(bad_call* c) { return create_from(c, "/nonexistent/mesh.obj"); }
static mica_status create_from_empty_path(bad_call* c) { return create_from(c, ""); }

/* Malformed Gmsh files: a parse error with the line number. */
static const struct {
  const char* name;
  const char* body;
  int with_head;
} kMalformed[] = {
    /* $Nodes promises 5 nodes and the file ends after 2 */
    {"truncated_nodes.msh", "$Nodes\n5\n1 0 0 0\n2 1 0 0\n", 1},
    /* the same, cut in the middle of a line */
    {"truncated_line.msh", "$Nodes\n5\n1 0 0 0\n2 1 0", 1},
    /* a coordinate that is not a number */
    {"bad_coordinate.msh", "$Nodes\n1\n1 0 abc 0\n$EndNodes\n", 1},
    /* a non-finite coordinate */
    {"nan_coordinate.msh", "$Nodes\n1\n1 0 nan 0\n$EndNodes\n", 1},
    /* a node count that the file cannot hold */
    {"lying_count.msh", "$Nodes\n999999999999\n1 0 0 0\n$EndNodes\n", 1},
    {"negative_count.msh", "$Nodes\n-3\n$EndNodes\n", 1},
    /* an element naming a node that $Nodes did not list */
    {"unknown_node.msh",
     "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 0 1 2 3 99\n$EndElements\n", 1},
    /* a tet with three nodes */
    {"short_tet.msh",
     "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n$EndNodes\n$Elements\n1\n1 4 0 1 2 3\n$EndElements\n", 1},
    /* a missing $EndNodes */
    {"no_end.msh", "$Nodes\n1\n1 0 0 0\n$Elements\n", 1},
    /* not a Gmsh file at all, an empty file, binary garbage */
    {"not_gmsh.msh", "hello world\n", 0},
    {"empty.msh", "", 0},
    {"garbage.msh", "\x01\x02\x03\xff\xfe\n\n\x7f", 0},
};
static mica_status create_from_malformed(bad_call* c) {
  char text[1024];
  snprintf(text, sizeof text, "%s%s", kMalformed[c->i].with_head ? "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n" : "",
           kMalformed[c->i].body);
  if (!write_tmp(kMalformed[c->i].name, text)) bad_wrong(c, "cannot write %s", kMalformed[c->i].name);
  return create_from_named(c, kMalformed[c->i].name);
}
/* A malformed TetGen pair. */
static mica_status create_from_bad_tetgen(bad_call* c) {
  write_tmp("bad_pair.ele", "1 4 0\n0 0 1 2 3\n");
  return create_from(c, write_tmp("bad_pair.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 one 0\n3 0 0 1\n"));
}

static const bad_case kFileCases[] = {
    {"mica_body_create_from_file: a missing directory", create_from_missing_dir, MICA_ERR_IO, NULL},
    {"mica_body_create_from_file: a missing file", create_from_missing_node, MICA_ERR_IO, NULL},
    {"mica_body_create_from_file: a directory named like a mesh", create_from_directory, MICA_ERR_IO, NULL},
    /* Unknown extensions, whether or not the file exists. */
    {"mica_body_create_from_file: .stl", create_from_stl, MICA_ERR_UNSUPPORTED, NULL},
    {"mica_body_create_from_file: .obj, missing", create_from_missing_obj, MICA_ERR_UNSUPPORTED,
     "/nonexistent/mesh.obj"},
    {"mica_body_create_from_file: empty path", create_from_empty_path, MICA_ERR_UNSUPPORTED, NULL},
    {"mica_body_create_from_file: malformed Gmsh", create_from_malformed, MICA_ERR_PARSE, "line", COUNT_OF(kMalformed)},
    {"mica_body_create_from_file: malformed TetGen", create_from_bad_tetgen, MICA_ERR_PARSE, "line"},
};

static void test_mesh_files(void** state) {
  fixture* fx = *state;
  assert_int_equal(mkdir(tmp_path("directory.msh"), 0700), 0);
  RUN_BAD_CASES(fx, kFileCases);

  /* Control: a valid file (the two-tet mesh) loads, in another world. */
  const mica_body_def bd = mica_body_def_default();
  mica_body_id out = 0;
  mica_world_def wd = mica_world_def_default();
  mica_world* other = NULL;
  REQUIRE_OK(mica_world_create(&wd, &other));
  REQUIRE_OK_W(other, mica_body_create_from_file(other, &bd, two_tet_file(), &out));
  int32_t n = 0, t = 0;
  REQUIRE_OK_W(other, mica_body_get_counts(other, out, &n, &t, NULL));
  assert_int_equal(n, 5);
  assert_int_equal(t, 2);
  mica_world_destroy(other);
}

/* ------------------------------------------------------------------------------------------ */
/* Node forces and selections                                                                  */

/* Node forces on nodes 3 and 4 with force component i % 6 non-finite (the value i / 6). */
static mica_status set_nonfinite_force(bad_call* c) {
  const int32_t nodes[2] = {3, 4};
  double f[6] = {0.1, 0.2, 0.3, -0.1, -0.2, -0.3};
  f[c->i % 6] = kNonfinite[c->i / 6];
  return mica_body_set_node_forces(c->fx->world, c->fx->body, nodes, f, 2);
}
/* A node index out of range at position .with.arg of three (the index i). */
static int32_t bad_node(const fixture* fx, int i) {
  const int32_t bad[3] = {-1, fx->node_count, INT32_MAX};
  return bad[i];
}
static mica_status set_force_on_bad_node(bad_call* c) {
  const double f[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
  int32_t nodes[3] = {0, 1, 2};
  nodes[c->with.arg] = bad_node(c->fx, c->i);
  bad_needle(c, 0, "%d", nodes[c->with.arg]);
  return mica_body_set_node_forces(c->fx->world, c->fx->body, nodes, f, 3);
}
static const int32_t kBadCount[] = {-1, INT32_MIN};
static mica_status set_forces_bad_count(bad_call* c) {
  const int32_t nodes[1] = {0};
  const double forces[3] = {0, 0, 1};
  return mica_body_set_node_forces(c->fx->world, c->fx->body, nodes, forces, kBadCount[c->i]);
}

/* Selections: nothing may be answered. */
static mica_status select_in_box(bad_call* c, const double* lo, const double* hi, int32_t use_rest) {
  int32_t ibuf[256], count = -7;
  const mica_status s = mica_body_select_nodes_in_box(c->fx->world, c->fx->body, lo, hi, use_rest, ibuf, 256, &count);
  if (count != -7) bad_wrong(c, "*out_count is %d", count);
  return s;
}
static mica_status select_by_plane(bad_call* c, const double* point, const double* normal, double tolerance,
                                   int32_t use_rest) {
  int32_t ibuf[256], count = -7;
  const mica_status s = mica_body_select_nodes_by_plane(c->fx->world, c->fx->body, point, normal, tolerance, use_rest,
                                                        ibuf, 256, &count);
  if (count != -7) bad_wrong(c, "*out_count is %d", count);
  return s;
}
/* lo (.with.arg 0, use_rest 1) or hi (1, use_rest 0) with coordinate i / 3 non-finite (value i % 3). */
static mica_status select_in_nonfinite_box(bad_call* c) {
  double corner[2][3] = {{-1, -1, -1}, {1, 1, 1}};
  corner[c->with.arg][c->i / 3] = kNonfinite[c->i % 3];
  return select_in_box(c, corner[0], corner[1], 1 - c->with.arg);
}
/* The point (.with.arg 0) or the normal (1) with coordinate i / 3 non-finite (value i % 3). */
static mica_status select_by_nonfinite_plane(bad_call* c) {
  double plane[2][3] = {{0, 0, 0}, {1, 0, 0}};
  plane[c->with.arg][c->i / 3] = kNonfinite[c->i % 3];
  return select_by_plane(c, plane[0], plane[1], 0.0, 1);
}
static mica_status select_with_nonfinite_tolerance(bad_call* c) {
  const double point[3] = {0, 0, 0}, normal[3] = {1, 0, 0};
  return select_by_plane(c, point, normal, kNonfinite[c->i], 1);
}
static mica_status select_by_zero_normal(bad_call* c) {
  const double zero[3] = {0, 0, 0};
  return select_by_plane(c, zero, zero, 0.0, 1);
}
static const int32_t kBadRest[] = {2, -1, INT32_MAX};
static mica_status select_in_box_bad_rest(bad_call* c) { return select_in_box(c, kLo, kHi, kBadRest[c->i]); }
static mica_status select_by_plane_bad_rest(bad_call* c) {
  const double zero[3] = {0, 0, 0}, n3[3] = {1, 0, 0};
  return select_by_plane(c, zero, n3, 0.0, kBadRest[c->i]);
}

/* mica_body_set_materials: one property of one tet (.with.arg: E 0, nu 1, rho 2) out of its
 * domain, the others the fixture's defaults; the message names the tet. */
static const double kBadMaterial[3][4] = {{0, -1e4, NAN, INFINITY}, {0.5, -0.1, NAN, INFINITY}, {0, -1, NAN, INFINITY}};
static const int32_t kBadMaterialTet[3] = {5, 17, 0};
static mica_status set_bad_material(bad_call* c) {
  double values[3][18];
  const double defaults[3] = {1e4, 0.3, 1000};
  for (int p = 0; p < 3; ++p)
    for (int e = 0; e < 18; ++e) values[p][e] = defaults[p];
  const int32_t tet = kBadMaterialTet[c->with.arg];
  values[c->with.arg][tet] = kBadMaterial[c->with.arg][c->i];
  bad_needle(c, 0, "tet %d", tet);
  return mica_body_set_materials(c->fx->world, c->fx->body, values[0], values[1], values[2], 18);
}
static const int32_t kBadTetCountForMaterials[] = {17, 19, 0, -1, INT32_MIN, INT32_MAX};
static mica_status set_materials_bad_count(bad_call* c) {
  double E[18];
  for (int e = 0; e < 18; ++e) E[e] = 2e4;
  return mica_body_set_materials(c->fx->world, c->fx->body, E, NULL, NULL, kBadTetCountForMaterials[c->i]);
}

static const bad_case kForceAndSelectionCases[] = {
    {"mica_body_set_materials: youngs_modulus of tet 5", set_bad_material, MICA_ERR_INVALID_ARGUMENT, "Young's", 4,
     .with.arg = 0},
    {"mica_body_set_materials: poisson_ratio of tet 17", set_bad_material, MICA_ERR_INVALID_ARGUMENT, "Poisson", 4,
     .with.arg = 1},
    {"mica_body_set_materials: density of tet 0", set_bad_material, MICA_ERR_INVALID_ARGUMENT, "density", 4,
     .with.arg = 2},
    {"mica_body_set_materials: tet_count", set_materials_bad_count, MICA_ERR_INVALID_ARGUMENT, "tet_count",
     COUNT_OF(kBadTetCountForMaterials)},
    {"mica_body_set_node_forces: non-finite", set_nonfinite_force, MICA_ERR_INVALID_ARGUMENT, NULL, 18},
    {"mica_body_set_node_forces: node out of range at position 0", set_force_on_bad_node, MICA_ERR_OUT_OF_RANGE,
     "position 0", 3, .with.arg = 0},
    {"mica_body_set_node_forces: node out of range at position 2", set_force_on_bad_node, MICA_ERR_OUT_OF_RANGE,
     "position 2", 3, .with.arg = 2},
    {"mica_body_set_node_forces: count", set_forces_bad_count, MICA_ERR_INVALID_ARGUMENT, "count", COUNT_OF(kBadCount)},
    {"mica_body_select_nodes_in_box: non-finite lo", select_in_nonfinite_box, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     .with.arg = 0},
    {"mica_body_select_nodes_in_box: non-finite hi", select_in_nonfinite_box, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     .with.arg = 1},
    {"mica_body_select_nodes_in_box: use_rest", select_in_box_bad_rest, MICA_ERR_INVALID_ARGUMENT, "use_rest",
     COUNT_OF(kBadRest)},
    {"mica_body_select_nodes_by_plane: non-finite point", select_by_nonfinite_plane, MICA_ERR_INVALID_ARGUMENT, NULL, 9,
     .with.arg = 0},
    {"mica_body_select_nodes_by_plane: non-finite normal", select_by_nonfinite_plane, MICA_ERR_INVALID_ARGUMENT, NULL,
     9, .with.arg = 1},
    {"mica_body_select_nodes_by_plane: non-finite tolerance", select_with_nonfinite_tolerance,
     MICA_ERR_INVALID_ARGUMENT, NULL, 3},
    {"mica_body_select_nodes_by_plane: zero normal", select_by_zero_normal, MICA_ERR_INVALID_ARGUMENT, NULL},
    {"mica_body_select_nodes_by_plane: use_rest", select_by_plane_bad_rest, MICA_ERR_INVALID_ARGUMENT, "use_rest",
     COUNT_OF(kBadRest)},
};

static void test_bad_forces_and_selections(void** state) { RUN_BAD_CASES((fixture*)*state, kForceAndSelectionCases); }

/* ------------------------------------------------------------------------------------------ */
/* Buffers: too small, negative capacities                                                     */

/* Capacity i: 0 or the needed count - 1 (too small), or -1 or INT32_MIN (negative: a value
 * outside its domain, MICA_ERR_INVALID_ARGUMENT, "a value is outside its domain (NaN, negative,
 * bad enum)"). When too small, the message names the needed count and *out_count is set to it;
 * either way the buffer is left alone. */
static int32_t capacity(int too_small, int i, int32_t needed) {
  if (too_small) return i == 0 ? 0 : needed - 1;
  return i == 0 ? -1 : INT32_MIN;
}

/* A node getter (the row's) with capacity(too_small, i); without out_count when !with_count. */
static mica_status node_getter_short(bad_call* c, int too_small, int i, int with_count) {
  int32_t n = -1; /* nodes, or tets for the per-tet getters: the size query says */
  const mica_status query = c->with.nodes(c->fx->world, c->fx->body, NULL, 0, &n);
  if (query != MICA_OK || n <= 0) return bad_wrong(c, "the size query gave %d, %d", query, n), query;
  double* buf = malloc(sizeof(double) * 6 * (size_t)n);
  for (int32_t k = 0; k < 6 * n; ++k) buf[k] = SENTINEL_D;
  int32_t out_count = SENTINEL_I;
  if (too_small && with_count) bad_needle(c, 0, "%d", n);
  const mica_status s = doubles_unwritten(
      c, buf, 6 * (size_t)n,
      c->with.nodes(c->fx->world, c->fx->body, buf, capacity(too_small, i, n), with_count ? &out_count : NULL));
  if (too_small && with_count && out_count != n)
    bad_wrong(c, "*out_count is %d, want the needed count %d", out_count, n);
  free(buf);
  return s;
}
static mica_status nodes_too_small(bad_call* c) { return node_getter_short(c, 1, c->i, 1); }
static mica_status nodes_negative(bad_call* c) { return node_getter_short(c, 0, c->i, 1); }
/* Without out_count the call still refuses and leaves the buffer alone (capacity: needed - 1). */
static mica_status nodes_too_small_no_count(bad_call* c) { return node_getter_short(c, 1, 1, 0); }

static mica_status index_getter_short(bad_call* c, int too_small) {
  const index_list* list = c->with.indices;
  int32_t needed = -1;
  const mica_status query = list->get(c->fx, NULL, 0, &needed);
  if (query != MICA_OK || needed <= 0) return bad_wrong(c, "the size query gave %d, %d", query, needed), query;
  int32_t* buf = malloc(sizeof(int32_t) * (size_t)(list->width * needed));
  for (int32_t k = 0; k < list->width * needed; ++k) buf[k] = SENTINEL_I;
  int32_t out_count = SENTINEL_I;
  if (too_small) bad_needle(c, 0, "%d", needed);
  const mica_status s = list->get(c->fx, buf, capacity(too_small, c->i, needed), &out_count);
  for (int32_t k = 0; k < list->width * needed; ++k)
    if (buf[k] != SENTINEL_I) {
      bad_wrong(c, "the buffer was written (item %d) although the call failed", k / list->width);
      break;
    }
  if (too_small && out_count != needed) bad_wrong(c, "*out_count is %d, want the needed count %d", out_count, needed);
  free(buf);
  return s;
}
static mica_status indices_too_small(bad_call* c) { return index_getter_short(c, 1); }
static mica_status indices_negative(bad_call* c) { return index_getter_short(c, 0); }

static mica_status get_surface(fixture* fx, int32_t* out, int32_t capacity, int32_t* out_count) {
  return mica_body_get_surface(fx->world, fx->body, out, capacity, out_count);
}
static mica_status get_in_box(fixture* fx, int32_t* out, int32_t capacity, int32_t* out_count) {
  const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
  return mica_body_select_nodes_in_box(fx->world, fx->body, lo, hi, 1, out, capacity, out_count);
}
static mica_status get_by_plane(fixture* fx, int32_t* out, int32_t capacity, int32_t* out_count) {
  const double p[3] = {0.15, 0, 0}, n[3] = {1, 0, 0};
  return mica_body_select_nodes_by_plane(fx->world, fx->body, p, n, 1e-9, 0, out, capacity, out_count);
}
static mica_status get_tets(fixture* fx, int32_t* out, int32_t capacity, int32_t* out_count) {
  return mica_body_get_tets(fx->world, fx->body, out, capacity, out_count);
}
static mica_status get_tet_regions(fixture* fx, int32_t* out, int32_t capacity, int32_t* out_count) {
  return mica_body_get_tet_regions(fx->world, fx->body, out, capacity, out_count);
}
static const index_list kSurface = {"mica_body_get_surface", get_surface, 3};
static const index_list kTets = {"mica_body_get_tets", get_tets, 4};
static const index_list kTetRegions = {"mica_body_get_tet_regions", get_tet_regions, 1};
static const index_list kInBox = {"mica_body_select_nodes_in_box", get_in_box, 1};
static const index_list kByPlane = {"mica_body_select_nodes_by_plane", get_by_plane, 1};

static const bad_case kBufferCases[] = {
    {"mica_body_get_tets: capacity too small", indices_too_small, MICA_ERR_BUFFER_TOO_SMALL, NULL, 2,
     {.indices = &kTets}},
    {"mica_body_get_tet_regions: capacity too small", indices_too_small, MICA_ERR_BUFFER_TOO_SMALL, NULL, 2,
     {.indices = &kTetRegions}},
    {"mica_body_get_tets: negative capacity", indices_negative, MICA_ERR_INVALID_ARGUMENT, NULL, 2, {.indices = &kTets}},
    {"mica_body_get_tet_regions: negative capacity", indices_negative, MICA_ERR_INVALID_ARGUMENT, NULL, 2,
     {.indices = &kTetRegions}},
    {"mica_body_get_node_masses: capacity too small", nodes_too_small, MICA_ERR_BUFFER_TOO_SMALL, NULL, 2,
     {.nodes = mica_body_get_node_masses}},
    {"mica_body_get_strains: capacity too small", nodes_too_small, MICA_ERR_BUFFER_TOO_SMALL, NULL, 2,
     {.nodes = mica_body_get_strains}},
    {"mica_body_get_von_mises: capacity too small", nodes_too_small, MICA_ERR_BUFFER_TOO_SMALL, NULL, 2,
     {.nodes = mica_body_get_von_mises}},
    {"mica_body_get_strains: capacity too small, no out_count", nodes_too_small_no_count, MICA_ERR_BUFFER_TOO_SMALL,
     NULL, 1, {.nodes = mica_body_get_strains}},
    {"mica_body_get_node_masses: negative capacity", nodes_negative, MICA_ERR_INVALID_ARGUMENT, NULL, 2,
     {.nodes = mica_body_get_node_masses}},
    {"mica_body_get_strains: negative capacity", nodes_negative, MICA_ERR_INVALID_ARGUMENT, NULL, 2,
     {.nodes = mica_body_get_strains}},
    {"mica_body_get_von_mises: negative capacity", nodes_negative, MICA_ERR_INVALID_ARGUMENT, NULL, 2,
     {.nodes = mica_body_get_von_mises}},
    {"mica_body_get_positions: capacity too small", nodes_too_small, MICA_ERR_BUFFER_TOO_SMALL, NULL, 2,
     {.nodes = mica_body_get_positions}},
    {"mica_body_get_velocities: capacity too small", nodes_too_small, MICA_ERR_BUFFER_TOO_SMALL, NULL, 2,
     {.nodes = mica_body_get_velocities}},
    {"mica_body_get_rest_positions: capacity too small", nodes_too_small, MICA_ERR_BUFFER_TOO_SMALL, NULL, 2,
     {.nodes = mica_body_get_rest_positions}},
    {"mica_body_get_surface: capacity too small", indices_too_small, MICA_ERR_BUFFER_TOO_SMALL, NULL, 2,
     {.indices = &kSurface}},
    {"mica_body_select_nodes_in_box: capacity too small", indices_too_small, MICA_ERR_BUFFER_TOO_SMALL, NULL, 2,
     {.indices = &kInBox}},
    {"mica_body_select_nodes_by_plane: capacity too small", indices_too_small, MICA_ERR_BUFFER_TOO_SMALL, NULL, 2,
     {.indices = &kByPlane}},
    {"mica_body_get_positions: capacity too small, no out_count", nodes_too_small_no_count, MICA_ERR_BUFFER_TOO_SMALL,
     NULL, 1, {.nodes = mica_body_get_positions}},
    {"mica_body_get_positions: negative capacity", nodes_negative, MICA_ERR_INVALID_ARGUMENT, NULL, 2,
     {.nodes = mica_body_get_positions}},
    {"mica_body_get_velocities: negative capacity", nodes_negative, MICA_ERR_INVALID_ARGUMENT, NULL, 2,
     {.nodes = mica_body_get_velocities}},
    {"mica_body_get_rest_positions: negative capacity", nodes_negative, MICA_ERR_INVALID_ARGUMENT, NULL, 2,
     {.nodes = mica_body_get_rest_positions}},
    {"mica_body_get_surface: negative capacity", indices_negative, MICA_ERR_INVALID_ARGUMENT, NULL, 2,
     {.indices = &kSurface}},
    {"mica_body_select_nodes_in_box: negative capacity", indices_negative, MICA_ERR_INVALID_ARGUMENT, NULL, 2,
     {.indices = &kInBox}},
    {"mica_body_select_nodes_by_plane: negative capacity", indices_negative, MICA_ERR_INVALID_ARGUMENT, NULL, 2,
     {.indices = &kByPlane}},
};

static void test_buffers(void** state) {
  fixture* fx = *state;
  int32_t in_box = 0, on_plane = 0;
  EXPECT_STATUS(MICA_OK, get_in_box(fx, NULL, 0, &in_box));
  EXPECT_STATUS(MICA_OK, get_by_plane(fx, NULL, 0, &on_plane));
  assert_int_equal(in_box, fx->node_count);
  assert_int_equal(on_plane, 8); /* x <= 0.15: the faces x = 0 and x = 0.1 */
  RUN_BAD_CASES(fx, kBufferCases);
}

/* ------------------------------------------------------------------------------------------ */
/* Stale ids                                                                                   */

static uint64_t destroyed(const fixture* fx) { return fx->dead_body; }
static uint64_t an_lpc(const fixture* fx) { return fx->lpc; }
static uint64_t null_id(const fixture* fx) { return (void)fx, MICA_NULL_ID; }
static uint64_t made_up(const fixture* fx) { return (void)fx, 0x0100000100000063u; } /* body, generation 1, slot 99 */
static uint64_t wrong_generation(const fixture* fx) { return (fx->body & ~(0xffffffull << 32)) | (0x000abcull << 32); }
static uint64_t unknown_kind(const fixture* fx) { return fx->body ^ (0xffull << 56); }
static uint64_t all_ones(const fixture* fx) { return (void)fx, UINT64_MAX; }

/* Every call that takes a body id (c->i), with the row's stale id, which the message names. */
static mica_status call_on_stale_body(bad_call* c) {
  const mica_body_id id = c->with.id(c->fx);
  hex_id(id, c->needle[0], sizeof c->needle[0]);
  return call_on_body(c, c->fx->world, id, c->i);
}

static const bad_case kStaleCases[] = {
    {"stale body id: destroyed", call_on_stale_body, MICA_ERR_STALE_ID, NULL, BODY_CALLS, {.id = destroyed}},
    {"stale body id: an lpc id", call_on_stale_body, MICA_ERR_STALE_ID, NULL, BODY_CALLS, {.id = an_lpc}},
    {"stale body id: MICA_NULL_ID", call_on_stale_body, MICA_ERR_STALE_ID, NULL, BODY_CALLS, {.id = null_id}},
    {"stale body id: made up", call_on_stale_body, MICA_ERR_STALE_ID, NULL, BODY_CALLS, {.id = made_up}},
    {"stale body id: live slot, wrong generation", call_on_stale_body, MICA_ERR_STALE_ID, NULL, BODY_CALLS,
     {.id = wrong_generation}},
    {"stale body id: live slot, unknown kind", call_on_stale_body, MICA_ERR_STALE_ID, NULL, BODY_CALLS,
     {.id = unknown_kind}},
    {"stale body id: UINT64_MAX", call_on_stale_body, MICA_ERR_STALE_ID, NULL, BODY_CALLS, {.id = all_ones}},
};

static void test_stale_body_ids(void** state) { RUN_BAD_CASES((fixture*)*state, kStaleCases); }

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test_setup_teardown(test_null_pointers, setup, teardown),
      cmocka_unit_test_setup_teardown(test_optional_outputs_may_be_null, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_body_def, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_meshes, setup, teardown),
      cmocka_unit_test_setup_teardown(test_mesh_files, setup, teardown),
      cmocka_unit_test_setup_teardown(test_bad_forces_and_selections, setup, teardown),
      cmocka_unit_test_setup_teardown(test_buffers, setup, teardown),
      cmocka_unit_test_setup_teardown(test_stale_body_ids, setup, teardown),
  };
  return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
