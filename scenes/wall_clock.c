/* SPDX-License-Identifier: Apache-2.0 */
#define _POSIX_C_SOURCE 200809L
#include "wall_clock.h"

#include <math.h>
#include <time.h>

double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void sleep_until(double deadline) {
  const double wait = deadline - now_s();
  if (wait <= 0) return;
  struct timespec ts = {(time_t)wait, (long)((wait - floor(wait)) * 1e9)};
  nanosleep(&ts, NULL);
}
