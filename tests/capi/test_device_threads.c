/* SPDX-License-Identifier: Apache-2.0 */
/* The functions mica_device.h calls safe on other threads, run there while the world's thread
 * creates, steps and destroys: mica_device_get_stats (any thread) and mica_device_get_info (any
 * thread but the servo thread) on two reader threads, mica_device_poll on a servo thread, while
 * the world's thread creates and destroys devices (0.4: creating one moved the device table
 * under the readers, a heap-use-after-free under ASan in 5 runs of 5). And the functions
 * documented "any thread", on four threads at once. Labelled `threads`: CI runs it under
 * ThreadSanitizer. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <pthread.h>
#include <stdatomic.h>
#include <string.h>

#include <mica/mica.h>
#include <mica/mica_device.h>

typedef struct shared {
  mica_world* world;
  mica_device_id fixed;         /* lives throughout */
  _Atomic uint64_t newest;      /* the device created last (may be destroyed by now) */
  atomic_int done;
  atomic_long reads, bad;
} shared;

static void* reader(void* arg) {
  shared* s = arg;
  long reads = 0, bad = 0;
  while (!atomic_load(&s->done)) {
    mica_device_stats st;
    memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    if (mica_device_get_stats(s->world, s->fixed, &st) != MICA_OK) bad++;
    mica_device_info info;
    memset(&info, 0, sizeof info);
    info.struct_size = sizeof info;
    if (mica_device_get_info(s->world, s->fixed, &info) != MICA_OK || strcmp(info.name, "null") != 0) bad++;
    /* The newest may be gone: OK or a stale id, nothing else. */
    const mica_status n = mica_device_get_stats(s->world, atomic_load(&s->newest), &st);
    if (n != MICA_OK && n != MICA_ERR_STALE_ID) bad++;
    reads++;
  }
  atomic_fetch_add(&s->reads, reads);
  atomic_fetch_add(&s->bad, bad);
  return NULL;
}

static void* servo(void* arg) {
  shared* s = arg;
  long bad = 0;
  while (!atomic_load(&s->done)) {
    double f[3];
    if (mica_device_poll(s->world, s->fixed, NULL, f) != MICA_OK) bad++;
    const mica_status n = mica_device_poll(s->world, atomic_load(&s->newest), NULL, f);
    if (n != MICA_OK && n != MICA_ERR_STALE_ID) bad++;
  }
  atomic_fetch_add(&s->bad, bad);
  return NULL;
}

static void test_readers_while_devices_come_and_go(void** state) {
  (void)state;
  shared s;
  memset(&s, 0, sizeof s);
  mica_world_def wd = mica_world_def_default();
  assert_int_equal(mica_world_create(&wd, &s.world), MICA_OK);
  const mica_body_def bd = mica_body_def_default();
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.1, 0.1};
  const int32_t cells[3] = {2, 2, 2};
  mica_body_id body;
  assert_int_equal(mica_body_create_box(s.world, &bd, lo, hi, cells, 5, &body), MICA_OK);
  mica_device_def dd = mica_device_def_default(); /* null devices */
  assert_int_equal(mica_device_create(s.world, &dd, &s.fixed), MICA_OK);
  atomic_store(&s.newest, s.fixed);
  pthread_t r1, r2, sv;
  assert_int_equal(pthread_create(&r1, NULL, reader, &s), 0);
  assert_int_equal(pthread_create(&r2, NULL, reader, &s), 0);
  assert_int_equal(pthread_create(&sv, NULL, servo, &s), 0);
  mica_device_id made[300];
  int count = 0;
  for (int k = 0; k < 300; ++k) {
    assert_int_equal(mica_device_create(s.world, &dd, &made[count]), MICA_OK);
    atomic_store(&s.newest, made[count]);
    count++;
    if (k % 3 == 2) { /* destroy one made earlier (not the newest: readers use it) */
      assert_int_equal(mica_device_destroy(s.world, made[count - 2]), MICA_OK);
      made[count - 2] = made[count - 1];
      count--;
    }
    if (k % 50 == 0) assert_true(mica_step(s.world, 0.01) >= 0);
  }
  for (int k = 0; k < count; ++k) {
    atomic_store(&s.newest, made[k]);
    assert_int_equal(mica_device_destroy(s.world, made[k]), MICA_OK);
  }
  atomic_store(&s.done, 1);
  pthread_join(r1, NULL);
  pthread_join(r2, NULL);
  pthread_join(sv, NULL);
  print_message("%ld reads beside 300 creations and as many destructions\n", atomic_load(&s.reads));
  assert_int_equal(atomic_load(&s.bad), 0);
  assert_true(atomic_load(&s.reads) > 0);
  assert_int_equal(mica_device_destroy(s.world, s.fixed), MICA_OK);
  mica_world_destroy(s.world);
}

/* The functions documented "any thread", on four threads at once: version, status and stage
 * names, the def initialisers, world creation (good and bad) and the per-thread message. */
static void* any_thread(void* arg) {
  long* bad = arg;
  for (int k = 0; k < 40; ++k) {
    if (mica_version() != MICA_VERSION_NUMBER) ++*bad;
    if (!mica_status_string(-(k % 20))[0] || !mica_stage_name(k % 12)[0]) ++*bad;
    mica_body_def bd;
    mica_tool_def td;
    mica_lpc_def ld;
    mica_device_def dd;
    if (mica_body_def_init(&bd, sizeof bd) != MICA_OK || mica_tool_def_init(&td, sizeof td) != MICA_OK ||
        mica_lpc_def_init(&ld, sizeof ld) != MICA_OK || mica_device_def_init(&dd, sizeof dd) != MICA_OK)
      ++*bad;
    mica_world_def wd = mica_world_def_default();
    if (k % 2) wd.tolerance = -1; /* refused: the message is this thread's */
    mica_world* w = NULL;
    const mica_status st = mica_world_create(&wd, &w);
    if (k % 2) {
      if (st != MICA_ERR_INVALID_ARGUMENT || w || !strstr(mica_world_last_error(NULL), "tolerance")) ++*bad;
    } else {
      if (st != MICA_OK || !w) ++*bad;
      mica_world_destroy(w);
    }
  }
  return NULL;
}

static void test_any_thread_functions(void** state) {
  (void)state;
  pthread_t t[4];
  long bad[4] = {0, 0, 0, 0};
  for (int i = 0; i < 4; ++i) assert_int_equal(pthread_create(&t[i], NULL, any_thread, &bad[i]), 0);
  for (int i = 0; i < 4; ++i) pthread_join(t[i], NULL);
  for (int i = 0; i < 4; ++i) assert_int_equal(bad[i], 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_readers_while_devices_come_and_go),
      cmocka_unit_test(test_any_thread_functions),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
