/* SPDX-License-Identifier: Apache-2.0 */
/* The functions mica_device.h calls safe on other threads, run there while the world's thread
 * creates, steps and destroys: mica_device_get_stats (any thread) and mica_device_get_info (any
 * thread but the servo thread) on two reader threads, mica_device_poll on a servo thread, while
 * the world's thread creates and destroys devices (0.4: creating one moved the device table
 * under the readers, a heap-use-after-free under ASan in 5 runs of 5). And the functions
 * documented "any thread", on four threads at once. And two devices in one world, one driving a
 * tool and one a grasp, each on its own servo thread (mica_device_start) while the world steps
 * and a third thread reads both. Labelled `threads`: CI runs it under
 * ThreadSanitizer. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <string.h>
#include <time.h>

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

/* Two servo threads: a stylus presses the sphere into the block over a node, another lifts a grasp. */
static void press(double t, double p[3], void* user) {
  (void)user;
  p[0] = 0.075;
  p[1] = 0.1 + 0.015 - 0.005 * (t < 0.3 ? t / 0.3 : 1); /* the 1.5 cm sphere 5 mm into the top face */
  p[2] = 0.05;
}
static void lift(double t, double p[3], void* user) {
  (void)user;
  p[0] = 0.025;
  p[1] = 0.1 + 0.005 * (t < 0.3 ? t / 0.3 : 1);
  p[2] = 0.05;
}

typedef struct two {
  mica_world* world;
  mica_device_id device[2];
  atomic_int done;
  atomic_long reads, bad;
} two;

static void* read_both(void* arg) {
  two* s = arg;
  long reads = 0, bad = 0;
  while (!atomic_load(&s->done)) {
    for (int d = 0; d < 2; ++d) {
      mica_device_stats st;
      memset(&st, 0, sizeof st);
      st.struct_size = sizeof st;
      if (mica_device_get_stats(s->world, s->device[d], &st) != MICA_OK || st.failures != 0) bad++;
      for (int k = 0; k < 3; ++k)
        if (!(fabs(st.last_force[k]) <= 3.3)) bad++; /* finite, within the Touch's clamp */
    }
    reads++;
  }
  atomic_fetch_add(&s->reads, reads);
  atomic_fetch_add(&s->bad, bad);
  return NULL;
}

static void test_two_devices_two_servo_threads(void** state) {
  (void)state;
  two s;
  memset(&s, 0, sizeof s);
  mica_world_def wd = mica_world_def_default();
  assert_int_equal(mica_world_create(&wd, &s.world), MICA_OK);
  mica_body_def bd = mica_body_def_default();
  bd.rayleigh_alpha = 2;
  const double lo[3] = {0, 0, 0}, hi[3] = {0.1, 0.1, 0.1};
  const int32_t cells[3] = {4, 4, 4};
  mica_body_id body;
  assert_int_equal(mica_body_create_box(s.world, &bd, lo, hi, cells, 5, &body), MICA_OK);
  int32_t base[64], n = 0;
  const double up[3] = {0, 1, 0};
  assert_int_equal(mica_body_select_nodes_by_plane(s.world, body, lo, up, 1e-9, 1, base, 64, &n), MICA_OK);
  const mica_lpc_def fixed = mica_lpc_def_default();
  mica_lpc_id fix, grasp;
  assert_int_equal(mica_add_lpc(s.world, body, base, n, &fixed, &fix), MICA_OK);
  const double at[3] = {0.025, 0.1, 0.05};
  assert_int_equal(mica_lpc_grab(s.world, body, at, 1e-3, MICA_NULL_ID, &grasp), MICA_OK);
  mica_tool_def td = mica_tool_def_default();
  td.radius = 0.015;
  press(0, td.position, NULL);
  mica_tool_id tool;
  assert_int_equal(mica_tool_create(s.world, &td, &tool), MICA_OK);
  mica_device_def dd = mica_device_def_default();
  dd.backend = MICA_DEVICE_SIMULATED;
  dd.trajectory = press;
  dd.tool = tool;
  assert_int_equal(mica_device_create(s.world, &dd, &s.device[0]), MICA_OK);
  dd.trajectory = lift;
  dd.tool = MICA_NULL_ID;
  dd.lpc = grasp;
  assert_int_equal(mica_device_create(s.world, &dd, &s.device[1]), MICA_OK);
  for (int d = 0; d < 2; ++d) assert_int_equal(mica_device_start(s.world, s.device[d]), MICA_OK);
  pthread_t r;
  assert_int_equal(pthread_create(&r, NULL, read_both, &s), 0);
  long polls_before[2] = {0, 0};
  for (int k = 0; k < 60; ++k) {
    assert_true(mica_step(s.world, 0.01) >= 0);
    const struct timespec ts = {0, 5000000};
    nanosleep(&ts, NULL);
    if (k == 9)
      for (int d = 0; d < 2; ++d) {
        mica_device_stats st = {.struct_size = sizeof st};
        assert_int_equal(mica_device_get_stats(s.world, s.device[d], &st), MICA_OK);
        polls_before[d] = (long)st.polls;
      }
  }
  atomic_store(&s.done, 1);
  pthread_join(r, NULL);
  for (int d = 0; d < 2; ++d) assert_int_equal(mica_device_stop(s.world, s.device[d]), MICA_OK);
  mica_device_stats st[2] = {{.struct_size = sizeof st[0]}, {.struct_size = sizeof st[1]}};
  for (int d = 0; d < 2; ++d) assert_int_equal(mica_device_get_stats(s.world, s.device[d], &st[d]), MICA_OK);
  double tool_force[3], reaction[3];
  assert_int_equal(mica_tool_get_force(s.world, tool, tool_force, NULL, NULL), MICA_OK);
  assert_int_equal(mica_lpc_get_reaction(s.world, grasp, reaction), MICA_OK);
  print_message("polls %lld and %lld (%lld and %lld during the last 50 steps), %ld reads; last forces y %.3f and %.3f "
                "N (tool %.3f N, grasp %.3f N)\n",
                (long long)st[0].polls, (long long)st[1].polls, (long long)(st[0].polls - polls_before[0]),
                (long long)(st[1].polls - polls_before[1]), atomic_load(&s.reads), st[0].last_force[1],
                st[1].last_force[1], tool_force[1], reaction[1]);
  assert_int_equal(atomic_load(&s.bad), 0);
  for (int d = 0; d < 2; ++d) {
    assert_int_equal(st[d].failures, 0);
    assert_true(st[d].polls - polls_before[d] > 0); /* each servo loop ran on while the other did */
  }
  /* Each rendered its own model: the sphere pushed up, the grasp pulled down. */
  assert_true(tool_force[1] > 0 && reaction[1] < 0);
  assert_true(st[0].last_force[1] > 0 && st[1].last_force[1] < 0);
  assert_int_equal(mica_device_destroy(s.world, s.device[0]), MICA_OK);
  assert_int_equal(mica_device_destroy(s.world, s.device[1]), MICA_OK);
  mica_world_destroy(s.world);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_readers_while_devices_come_and_go),
      cmocka_unit_test(test_any_thread_functions),
      cmocka_unit_test(test_two_devices_two_servo_threads),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
