/* SPDX-License-Identifier: Apache-2.0 */
/* The wall clock of the real-time programs (examples_c/haptic_loop.c, two_hands.c,
 * bench/bench_servo.c, tests/capi/test_recording.c): seconds on the monotonic clock, and a sleep
 * until such a time, so that a loop keeps a period (deadline += period; sleep_until(deadline)). */
#ifndef MICA_SCENES_WALL_CLOCK_H
#define MICA_SCENES_WALL_CLOCK_H

#ifdef __cplusplus
extern "C" {
#endif

/* Seconds on CLOCK_MONOTONIC. */
double now_s(void);

/* Sleeps until now_s() reaches `deadline` (returns at once if it has). */
void sleep_until(double deadline);

#ifdef __cplusplus
}
#endif

#endif /* MICA_SCENES_WALL_CLOCK_H */
