/* SPDX-License-Identifier: Apache-2.0 */
/* capi/status.cpp through the C ABI: status text, stage names, the log callback, and where a
 * failed call's message goes (the world's or the thread's). */
#include "bad_input_util.h"

static void test_status_strings(void** state) {
  (void)state;
#define S(code) {code, #code}
  static const struct {
    mica_status code;
    const char* name;
  } kCodes[] = {
      S(MICA_OK),
      S(MICA_WARN_NOT_CONVERGED),
      S(MICA_WARN_DEVICE),
      S(MICA_WARN_BODIES_OVERLAP),
      S(MICA_WARN_UNBOUND_VERTICES),
      S(MICA_ERR_NULL_ARGUMENT),
      S(MICA_ERR_INVALID_ARGUMENT),
      S(MICA_ERR_OUT_OF_RANGE),
      S(MICA_ERR_STALE_ID),
      S(MICA_ERR_VERSION_MISMATCH),
      S(MICA_ERR_STRUCT_SIZE),
      S(MICA_ERR_BAD_MESH),
      S(MICA_ERR_IO),
      S(MICA_ERR_PARSE),
      S(MICA_ERR_NUMERICAL),
      S(MICA_ERR_WRONG_STATE),
      S(MICA_ERR_UNSUPPORTED),
      S(MICA_ERR_BUFFER_TOO_SMALL),
      S(MICA_ERR_DEVICE),
      S(MICA_ERR_OUT_OF_MEMORY),
      S(MICA_ERR_INTERNAL),
      S(MICA_ERR_DIVERGED),
      S(MICA_ERR_TRUNCATED),
  };
#undef S
  const size_t count = sizeof kCodes / sizeof kCodes[0];
  const mica_status unknown[6] = {5, -99, 100, -1000, INT32_MAX, INT32_MIN};
  for (size_t i = 0; i < count; ++i) {
    const char* text = mica_status_string(kCodes[i].code);
    assert_non_null(text);
    assert_true(strlen(text) > strlen(kCodes[i].name));
    /* names its code: "MICA_ERR_STALE_ID: ..." */
    if (!has_phrase(text, kCodes[i].name)) {
      print_error("mica_status_string(%s) = '%s' does not name the status\n", kCodes[i].name, text);
      fail();
    }
    for (size_t j = 0; j < i; ++j) assert_string_not_equal(text, mica_status_string(kCodes[j].code));
    for (int u = 0; u < 6; ++u) assert_string_not_equal(text, mica_status_string(unknown[u]));
  }
  for (int u = 0; u < 6; ++u) {
    const char* text = mica_status_string(unknown[u]);
    assert_non_null(text);
    assert_true(strlen(text) > 0);
  }
}

static void test_stage_names(void** state) {
  (void)state;
  const int32_t outside[4] = {-1, MICA_STAGE_COUNT, INT32_MIN, INT32_MAX};
  for (int i = 0; i < 4; ++i) {
    assert_non_null(mica_stage_name(outside[i]));
    assert_string_equal(mica_stage_name(outside[i]), "unknown");
  }
  for (int32_t s = 0; s < MICA_STAGE_COUNT; ++s) {
    const char* name = mica_stage_name(s);
    assert_non_null(name);
    assert_true(strlen(name) > 0);
    assert_string_not_equal(name, "unknown");
    for (int32_t t = 0; t < s; ++t) assert_string_not_equal(name, mica_stage_name(t));
  }
  assert_string_equal(mica_stage_name(MICA_STAGE_SOLVE), "solve");
  assert_string_equal(mica_stage_name(MICA_STAGE_ROTATIONS), "rotations");
}

typedef struct {
  int calls;
  int32_t level;
  void* user;
  char message[1024];
} log_record;

static void log_into(int32_t level, const char* message, void* user) {
  log_record* r = user;
  r->calls += 1;
  r->level = level;
  r->user = user;
  snprintf(r->message, sizeof r->message, "%s", message);
}

static void test_log_callback(void** state) {
  (void)state;
  log_record record;
  memset(&record, 0, sizeof record);
  mica_world_def wd = mica_world_def_default();
  wd.log = log_into;
  wd.log_user = &record;
  mica_world* w = NULL;
  REQUIRE_OK(mica_world_create(&wd, &w));
  assert_int_equal(record.calls, 0); /* success is silent at this level */

  EXPECT_STATUS(MICA_ERR_INVALID_ARGUMENT, mica_step(w, -1.0));
  assert_int_equal(record.calls, 1);
  assert_int_equal(record.level, MICA_LOG_ERROR);
  assert_ptr_equal(record.user, &record);
  assert_string_equal(record.message, mica_world_last_error(w));
  assert_true(has_phrase(record.message, "mica_step"));

  EXPECT_STATUS(MICA_ERR_STALE_ID, mica_body_destroy(w, 12345));
  assert_int_equal(record.calls, 2);
  assert_int_equal(record.level, MICA_LOG_ERROR);
  assert_string_equal(record.message, mica_world_last_error(w));
  assert_true(has_phrase(record.message, "0x3039"));

  const mica_body_def bd = mica_body_def_default();
  const int32_t inverted[8] = {0, 1, 2, 3, 2, 1, 3, 4};
  mica_body_id out = 0;
  EXPECT_STATUS(MICA_ERR_BAD_MESH, mica_body_create(w, &bd, kTwoTetNodes, 5, inverted, 2, &out));
  assert_int_equal(record.calls, 3);
  assert_true(has_phrase(record.message, "tet 1"));
  assert_string_equal(record.message, mica_world_last_error(w));

  /* Successful calls do not log errors. */
  REQUIRE_OK_W(w, mica_body_create(w, &bd, kTwoTetNodes, 5, kTwoTets, 2, &out));
  REQUIRE_OK_W(w, mica_step(w, 0.01));
  assert_int_equal(record.calls, 3);
  mica_world_destroy(w);

  /* A world without a log fails the same way, silently. */
  wd.log = NULL;
  wd.log_user = NULL;
  REQUIRE_OK(mica_world_create(&wd, &w));
  EXPECT_STATUS(MICA_ERR_INVALID_ARGUMENT, mica_step(w, NAN));
  assert_true(strlen(mica_world_last_error(w)) > 0);
  mica_world_destroy(w);
}

static void test_error_message_scopes(void** state) {
  fixture* fx = *state;
  EXPECT_FAIL(fx, MICA_ERR_INVALID_ARGUMENT, mica_step(fx->world, -2.0), NULL);
  char world_message[1024];
  snprintf(world_message, sizeof world_message, "%s", mica_world_last_error(fx->world));
  mica_world* w = (mica_world*)fx;
  EXPECT_FAIL_NO_WORLD(fx, MICA_ERR_NULL_ARGUMENT, mica_world_create(NULL, &w), "def");
  assert_string_equal(mica_world_last_error(fx->world), world_message);
  assert_string_not_equal(mica_world_last_error(NULL), world_message);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_status_strings),
      cmocka_unit_test(test_stage_names),
      cmocka_unit_test(test_log_callback),
      cmocka_unit_test_setup_teardown(test_error_message_scopes, setup, teardown),
  };
  return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
