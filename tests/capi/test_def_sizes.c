/* SPDX-License-Identifier: Apache-2.0 */
/* Drop-in upgrades within SONAME 0: every def is accepted from its size in 0.2.0 (the first
 * release) up to the current sizeof, the fields an older caller lacks take their defaults, and
 * only a smaller or a larger (newer header) size is refused. Any 0.x header_version is accepted.
 * tests/abi_fixtures/ runs real programs built against the released headers. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "mica/mica.h"
#include "mica/mica_device.h"

/* The end of the last field each def had in 0.2.0 (its size there: 112, 104, 80, 160, 200 on x86-64). */
#define END_OF(T, field) ((uint32_t)(offsetof(T, field) + sizeof(((T*)0)->field)))
#define FIRST_WORLD END_OF(mica_world_def, body_friction)
#define FIRST_BODY END_OF(mica_body_def, velocity)
#define FIRST_LPC END_OF(mica_lpc_def, velocity)
#define FIRST_TOOL END_OF(mica_tool_def, reserved0)
#define FIRST_DEVICE END_OF(mica_device_def, hand_damping)
/* The 0.5.0 device def ended with hand_damping (lpc came in 0.6). */
#define DEVICE_0_5 END_OF(mica_device_def, hand_damping)
/* The 0.3.0 world def ended with mica_sweep and reserved3 (now threads). */
#define WORLD_0_3 END_OF(mica_world_def, threads)
/* The 0.7.0 body def ended with velocity (cutting_resistance came in 0.8), its tool def with
 * reserved0 (blade and reserved1 came in 0.8): both their 0.2.0 sizes. */
#define BODY_0_7 END_OF(mica_body_def, velocity)
#define TOOL_0_7 END_OF(mica_tool_def, reserved0)

/* A world def with room past its end, so that a larger struct_size is safe to try. */
typedef union {
  mica_world_def d;
  unsigned char bytes[sizeof(mica_world_def) + 16];
} world_buffer;

static void test_first_sizes_are_the_released_ones(void** state) {
  (void)state;
  if (sizeof(void*) != 8) skip();
  assert_int_equal(FIRST_WORLD, 112);
  assert_int_equal(WORLD_0_3, 144);
  assert_int_equal(FIRST_BODY, 104);
  assert_int_equal(FIRST_LPC, 80);
  assert_int_equal(FIRST_TOOL, 160);
  assert_int_equal(FIRST_DEVICE, 200);
  assert_int_equal(DEVICE_0_5, 200);
  assert_int_equal(sizeof(mica_device_def), 208);
  assert_int_equal(BODY_0_7, 104);
  assert_int_equal(TOOL_0_7, 160);
  assert_int_equal(sizeof(mica_body_def), 112);
  assert_int_equal(sizeof(mica_tool_def), 168);
}

/* init at `size` into a buffer of 0xcd: returns the status; *written counts the bytes changed
 * from 0xcd at or beyond `size` (must stay 0). */
typedef mica_status (*init_fn)(void* def, uint32_t size);
static mica_status init_world(void* d, uint32_t size) { return mica_world_def_init(d, size, 200); }
static mica_status init_body(void* d, uint32_t size) { return mica_body_def_init(d, size); }
static mica_status init_lpc(void* d, uint32_t size) { return mica_lpc_def_init(d, size); }
static mica_status init_tool(void* d, uint32_t size) { return mica_tool_def_init(d, size); }
static mica_status init_device(void* d, uint32_t size) { return mica_device_def_init(d, size); }

static const struct {
  const char* name;
  init_fn init;
  uint32_t first, current;
} kDefs[] = {
    {"world", init_world, FIRST_WORLD, (uint32_t)sizeof(mica_world_def)},
    {"body", init_body, FIRST_BODY, (uint32_t)sizeof(mica_body_def)},
    {"lpc", init_lpc, FIRST_LPC, (uint32_t)sizeof(mica_lpc_def)},
    {"tool", init_tool, FIRST_TOOL, (uint32_t)sizeof(mica_tool_def)},
    {"device", init_device, FIRST_DEVICE, (uint32_t)sizeof(mica_device_def)},
};

static void test_init_accepts_every_released_size(void** state) {
  (void)state;
  unsigned char buffer[512];
  for (size_t k = 0; k < sizeof kDefs / sizeof kDefs[0]; ++k) {
    assert_true(kDefs[k].current + 16 <= sizeof buffer);
    /* Accepted: first .. current, 8 bytes apart (every def is 8-byte aligned). */
    for (uint32_t size = kDefs[k].first; size <= kDefs[k].current; size += 8) {
      memset(buffer, 0xcd, sizeof buffer);
      if (kDefs[k].init(buffer, size) != MICA_OK) fail_msg("%s def of %u bytes refused: %s", kDefs[k].name, size,
                                                            mica_world_last_error(NULL));
      uint32_t recorded;
      memcpy(&recorded, buffer, sizeof recorded);
      assert_int_equal(recorded, size);
      for (size_t i = size; i < sizeof buffer; ++i) assert_int_equal(buffer[i], 0xcd);
    }
    /* Refused, nothing written: below the first release, above this library. */
    const uint32_t refused[3] = {0, kDefs[k].first - 8, kDefs[k].current + 8};
    for (int r = 0; r < 3; ++r) {
      memset(buffer, 0xcd, sizeof buffer);
      assert_int_equal(kDefs[k].init(buffer, refused[r]), MICA_ERR_STRUCT_SIZE);
      for (size_t i = 0; i < sizeof buffer; ++i) assert_int_equal(buffer[i], 0xcd);
    }
    /* A newer header's def says so. */
    assert_non_null(strstr(mica_world_last_error(NULL), "newer libmica header"));
  }
}

/* A world def from a 0.2 caller: only its 112 bytes are read; what lies beyond (here bytes no
 * valid field could hold) is never looked at. */
static void test_world_from_an_older_header(void** state) {
  (void)state;
  world_buffer w;
  memset(&w, 0xcd, sizeof w);
  assert_int_equal(mica_world_def_init(&w.d, FIRST_WORLD, 200), MICA_OK);
  mica_world* world = NULL;
  assert_int_equal(mica_world_create(&w.d, &world), MICA_OK);
  assert_non_null(world);
  mica_world_destroy(world);

  /* The same bytes as a 0.4 def: warm_start 0xcdcdcdcd is refused. */
  w.d.struct_size = sizeof w.d;
  world = NULL;
  assert_int_equal(mica_world_create(&w.d, &world), MICA_ERR_INVALID_ARGUMENT);
  assert_null(world);
}

/* A stiff cantilever (E = 1e7 Pa, 10 x 2 x 2 cells, x = 0 clamped) sagging for three 10 ms
 * steps in a world made from `def`: the last step's statistics and the positions. */
typedef struct {
  mica_world_stats stats;
  double x[3 * 11 * 3 * 3];
} sag_result;

static void sag(const mica_world_def* def, sag_result* r) {
  memset(r, 0, sizeof *r);
  mica_world* world = NULL;
  assert_int_equal(mica_world_create(def, &world), MICA_OK);
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = 1e7;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.02, 0.02}, point[3] = {0, 0, 0}, normal[3] = {1, 0, 0};
  const int32_t cells[3] = {10, 2, 2};
  mica_body_id body;
  assert_int_equal(mica_body_create_box(world, &bd, lo, hi, cells, 5, &body), MICA_OK);
  int32_t clamped[9], count = 0;
  assert_int_equal(mica_body_select_nodes_by_plane(world, body, point, normal, 1e-9, 1, clamped, 9, &count), MICA_OK);
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id lpc;
  assert_int_equal(mica_add_lpc(world, body, clamped, count, &fixed, &lpc), MICA_OK);
  for (int k = 0; k < 3; ++k) assert_true(mica_step(world, 0.01) >= 0);
  r->stats.struct_size = sizeof r->stats;
  assert_int_equal(mica_world_get_stats(world, &r->stats), MICA_OK);
  int32_t n = 0;
  assert_int_equal(mica_body_get_positions(world, body, r->x, 11 * 3 * 3, &n), MICA_OK);
  assert_int_equal(n, 11 * 3 * 3);
  mica_world_destroy(world);
}

/* A 0.2 caller's def gets this library's defaults: its init fills the solver (MICA since 0.5), and
 * the field its header lacks (mica_sweep, since 0.3) is the default, the factored sweep. The world
 * steps exactly like one made with MICA and the factored sweep set explicitly, and not like the
 * Gauss-Seidel sweep (the 0.4 default), which stops at the 200-iteration cap on this stiff beam. */
static void test_older_header_gets_the_library_defaults(void** state) {
  (void)state;
  world_buffer old;
  memset(&old, 0xcd, sizeof old);
  assert_int_equal(mica_world_def_init(&old.d, FIRST_WORLD, 200), MICA_OK);
  assert_int_equal(old.d.solver, MICA_SOLVER_MICA);
  mica_world_def factored = mica_world_def_default(), gauss_seidel = factored;
  factored.solver = gauss_seidel.solver = MICA_SOLVER_MICA;
  factored.mica_sweep = MICA_SWEEP_FACTORED;
  gauss_seidel.mica_sweep = MICA_SWEEP_GAUSS_SEIDEL;
  static sag_result a, b, c;
  sag(&old.d, &a);
  sag(&factored, &b);
  sag(&gauss_seidel, &c);
  print_message("0.2 def: %d iterations (converged %d); factored: %d (%d); Gauss-Seidel: %d (%d)\n",
                a.stats.solver_iterations, a.stats.converged, b.stats.solver_iterations, b.stats.converged,
                c.stats.solver_iterations, c.stats.converged);
  assert_int_equal(a.stats.solver_iterations, b.stats.solver_iterations);
  assert_int_equal(a.stats.converged, 1);
  assert_memory_equal(a.x, b.x, sizeof a.x);
  assert_int_equal(c.stats.converged, 0);
  assert_true(c.stats.solver_iterations != a.stats.solver_iterations);
}

/* A device def from a 0.5 caller: only its 200 bytes are read, so what lies where 0.6 has `lpc`
 * (here an id no world ever made) is not looked at and the device drives nothing; the same bytes
 * read as a 0.6 def name a stale grasp. */
static void test_device_from_0_5_header(void** state) {
  (void)state;
  union {
    mica_device_def d;
    unsigned char bytes[sizeof(mica_device_def) + 16];
  } dev;
  memset(&dev, 0xcd, sizeof dev);
  assert_int_equal(mica_device_def_init(&dev.d, DEVICE_0_5), MICA_OK);
  mica_world_def wd = mica_world_def_default();
  mica_world* world = NULL;
  assert_int_equal(mica_world_create(&wd, &world), MICA_OK);
  mica_device_id device = MICA_NULL_ID;
  assert_int_equal(mica_device_create(world, &dev.d, &device), MICA_OK);
  assert_int_equal(mica_device_destroy(world, device), MICA_OK);
  dev.d.struct_size = sizeof dev.d;
  assert_int_equal(mica_device_create(world, &dev.d, &device), MICA_ERR_STALE_ID);
  mica_world_destroy(world);
}

/* Body and tool defs from a 0.7 caller: only their 104 and 160 bytes are read, so what lies where
 * 0.8 has cutting_resistance (bytes 0xcd: a negative double) and blade (0xcdcdcdcd, neither 0 nor
 * 1) is not looked at; the same bytes read as 0.8 defs are refused. */
static void test_body_and_tool_from_0_7_header(void** state) {
  (void)state;
  union {
    mica_body_def d;
    unsigned char bytes[sizeof(mica_body_def) + 16];
  } body;
  union {
    mica_tool_def d;
    unsigned char bytes[sizeof(mica_tool_def) + 16];
  } tool;
  memset(&body, 0xcd, sizeof body);
  memset(&tool, 0xcd, sizeof tool);
  assert_int_equal(mica_body_def_init(&body.d, BODY_0_7), MICA_OK);
  assert_int_equal(mica_tool_def_init(&tool.d, TOOL_0_7), MICA_OK);
  tool.d.shape = MICA_TOOL_SPHERE;
  mica_world_def wd = mica_world_def_default();
  mica_world* world = NULL;
  assert_int_equal(mica_world_create(&wd, &world), MICA_OK);
  const double lo[3] = {0, 0, 0}, hi[3] = {0.04, 0.02, 0.02};
  const int32_t cells[3] = {4, 2, 2};
  mica_body_id b = MICA_NULL_ID;
  assert_int_equal(mica_body_create_box(world, &body.d, lo, hi, cells, 5, &b), MICA_OK);
  mica_tool_id t = MICA_NULL_ID;
  assert_int_equal(mica_tool_create(world, &tool.d, &t), MICA_OK);
  body.d.struct_size = sizeof body.d;
  tool.d.struct_size = sizeof tool.d;
  assert_int_equal(mica_body_create_box(world, &body.d, lo, hi, cells, 5, &b), MICA_ERR_INVALID_ARGUMENT);
  assert_non_null(strstr(mica_world_last_error(world), "cutting_resistance"));
  assert_int_equal(mica_tool_create(world, &tool.d, &t), MICA_ERR_INVALID_ARGUMENT);
  assert_non_null(strstr(mica_world_last_error(world), "blade"));
  mica_world_destroy(world);
}

/* 0.3's reserved3 became threads in 0.4: a 0.3 def's value there is not a thread count. */
static void test_world_0_3_reserved_slot(void** state) {
  (void)state;
  mica_world_def d = mica_world_def_default();
  d.threads = 5000; /* outside [0, 1024]: refused when read as threads */
  d.header_version = 300;
  mica_world* world = NULL;
  assert_int_equal(mica_world_create(&d, &world), MICA_ERR_INVALID_ARGUMENT);
  assert_null(world);
  d.struct_size = WORLD_0_3;
  assert_int_equal(mica_world_create(&d, &world), MICA_OK);
  assert_non_null(world);
  mica_world_destroy(world);
}

static void test_header_versions(void** state) {
  (void)state;
  const uint32_t accepted[4] = {0, 200, 300, MICA_VERSION_NUMBER};
  for (int k = 0; k < 4; ++k) {
    mica_world_def d = mica_world_def_default();
    d.header_version = accepted[k];
    mica_world* world = NULL;
    assert_int_equal(mica_world_create(&d, &world), MICA_OK);
    mica_world_destroy(world);
  }
  mica_world_def d = mica_world_def_default();
  d.header_version = 10203;
  mica_world* world = NULL;
  assert_int_equal(mica_world_create(&d, &world), MICA_ERR_VERSION_MISMATCH);
  assert_null(world);
  assert_non_null(strstr(mica_world_last_error(NULL), "1.2.3"));
}

/* The current header's *_default() keeps struct_size even when init refuses. Simulated here
 * by what the inline function does: set the size, then call init with a size the library
 * refuses; the create call then names that size instead of a stale or zero one. */
static void test_create_names_a_refused_size(void** state) {
  (void)state;
  world_buffer w;
  memset(&w, 0, sizeof w);
  const uint32_t newer = (uint32_t)sizeof(mica_world_def) + 8;
  w.d.struct_size = newer;
  w.d.header_version = MICA_VERSION_NUMBER;
  assert_int_equal(mica_world_def_init(&w.d, newer, MICA_VERSION_NUMBER), MICA_ERR_STRUCT_SIZE);
  mica_world* world = NULL;
  assert_int_equal(mica_world_create(&w.d, &world), MICA_ERR_STRUCT_SIZE);
  char expected[64];
  snprintf(expected, sizeof expected, "def->struct_size is %u", (unsigned)newer);
  assert_non_null(strstr(mica_world_last_error(NULL), expected));
  assert_non_null(strstr(mica_world_last_error(NULL), "newer libmica header"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_first_sizes_are_the_released_ones),
      cmocka_unit_test(test_init_accepts_every_released_size),
      cmocka_unit_test(test_world_from_an_older_header),
      cmocka_unit_test(test_world_0_3_reserved_slot),
      cmocka_unit_test(test_device_from_0_5_header),
      cmocka_unit_test(test_body_and_tool_from_0_7_header),
      cmocka_unit_test(test_older_header_gets_the_library_defaults),
      cmocka_unit_test(test_header_versions),
      cmocka_unit_test(test_create_names_a_refused_size),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
