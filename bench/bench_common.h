/* SPDX-License-Identifier: Apache-2.0 */
/* What every benchmark prints beside its figures: a monotonic clock, the thread's CPU time, a sort order for medians,
 * and the machine it ran on (CPU, the CPUs it may use, the load). Header-only (static inline: a
 * benchmark takes what it needs); Linux. */
#pragma once
/* Needs _GNU_SOURCE (CPU_COUNT), defined by the including file before any header. */
#include <sched.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

static inline double now_ms(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

/* The calling thread's CPU time: what a step cost when the wall clock is polluted by other load
 * (it leaves out time the thread waited, e.g. for a background factorization). */
static inline double thread_cpu_ms(void) {
  struct timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

static inline int cmp(const void* a, const void* b) {
  const double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

static inline void machine(char* buf, size_t size) {
  char model[160] = "unknown CPU";
  FILE* f = fopen("/proc/cpuinfo", "r");
  if (f) {
    char line[256];
    while (fgets(line, sizeof line, f))
      if (strncmp(line, "model name", 10) == 0) {
        const char* c = strchr(line, ':');
        if (c) snprintf(model, sizeof model, "%s", c + 2);
        model[strcspn(model, "\n")] = 0;
        break;
      }
    fclose(f);
  }
  double load = -1;
  f = fopen("/proc/loadavg", "r");
  if (f) {
    if (fscanf(f, "%lf", &load) != 1) load = -1;
    fclose(f);
  }
  cpu_set_t set;
  CPU_ZERO(&set);
  const int cpus = sched_getaffinity(0, sizeof set, &set) == 0 ? CPU_COUNT(&set) : -1;
  snprintf(buf, size, "%s; this process may run on %d CPU(s); load average %.2f", model, cpus, load);
}
