/* SPDX-License-Identifier: Apache-2.0 */
/* Helpers shared by the accuracy-against-time study programs (bench/study/). Header-only:
 * each program is one translation unit against the public API (mica.h, mica_device.h).
 *
 * Progress: each program writes "progress <done> <total>" lines to stderr; scripts/study.sh
 * turns them into one bar. Everything else a program has to say goes to stdout or its CSVs.
 */
#ifndef MICA_STUDY_COMMON_H
#define MICA_STUDY_COMMON_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <mica/mica.h>

static inline double study_now_ms(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

/* The calling thread's CPU time: what a step cost when other processes share the core (the
 * wall clock counts their time too). */
static inline double study_cpu_ms(void) {
  struct timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

static inline int study_cmp_double(const void* a, const void* b) {
  const double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

/* The q-quantile (0..1) of n values, sorted in place (nearest rank). NAN for n = 0. */
static inline double study_quantile(double* v, int n, double q) {
  if (n <= 0) return NAN;
  qsort(v, (size_t)n, sizeof v[0], study_cmp_double);
  int k = (int)ceil(q * n) - 1;
  if (k < 0) k = 0;
  if (k >= n) k = n - 1;
  return v[k];
}

static inline void study_progress(double done, double total) {
  fprintf(stderr, "progress %.6g %.6g\n", done, total);
  fflush(stderr);
}

/* The distinct nodes of a body's surface triangles; malloc'ed, count in *n. */
static inline int32_t* study_surface_nodes(mica_world* w, mica_body_id body, int32_t* n) {
  int32_t nodes = 0, tris = 0;
  mica_body_get_counts(w, body, &nodes, NULL, &tris);
  int32_t* tri = malloc(sizeof(int32_t) * 3 * (size_t)(tris > 0 ? tris : 1));
  char* on = calloc((size_t)(nodes > 0 ? nodes : 1), 1);
  mica_body_get_surface(w, body, tri, tris, NULL);
  for (int32_t k = 0; k < 3 * tris; ++k) on[tri[k]] = 1;
  int32_t* list = malloc(sizeof(int32_t) * (size_t)(nodes > 0 ? nodes : 1));
  *n = 0;
  for (int32_t i = 0; i < nodes; ++i)
    if (on[i]) list[(*n)++] = i;
  free(tri);
  free(on);
  return list;
}

/* Resident set size of this process (kB), from /proc/self/status; -1 if unreadable. */
static inline long study_vmrss_kb(void) {
  FILE* f = fopen("/proc/self/status", "r");
  if (!f) return -1;
  char line[256];
  long kb = -1;
  while (fgets(line, sizeof line, f))
    if (strncmp(line, "VmRSS:", 6) == 0) {
      kb = strtol(line + 6, NULL, 10);
      break;
    }
  fclose(f);
  return kb;
}

/* "AMD EPYC ..., 2 CPUs, load 1.23" into buf: the machine line every CSV header carries. */
static inline void study_machine(char* buf, size_t size) {
  char model[160] = "unknown CPU";
  FILE* f = fopen("/proc/cpuinfo", "r");
  int cpus = 0;
  if (f) {
    char line[256];
    while (fgets(line, sizeof line, f)) {
      if (strncmp(line, "model name", 10) == 0) {
        ++cpus;
        const char* c = strchr(line, ':');
        if (c && cpus == 1) {
          snprintf(model, sizeof model, "%s", c + 2);
          model[strcspn(model, "\n")] = 0;
        }
      }
    }
    fclose(f);
  }
  double load = -1;
  f = fopen("/proc/loadavg", "r");
  if (f) {
    if (fscanf(f, "%lf", &load) != 1) load = -1;
    fclose(f);
  }
  snprintf(buf, size, "%s, %d CPUs, load average %.2f", model, cpus, load);
}

#endif /* MICA_STUDY_COMMON_H */
