/* SPDX-License-Identifier: Apache-2.0 */
/* The command line of the examples and benchmarks: `--help` (or `-h`) prints the program's usage
 * and exits 0; an option the program does not take (an argument starting with "-" and a letter,
 * so "-1e-3" stays a number), or one that takes a value given none, is refused with a message
 * naming it, exit status 2. Numbers are read whole ("20x" and "abc" are refused, not read as 20
 * and 0) and checked against their range, and the folders a program writes into are made.
 * Header-only, C99 and C++. */
#ifndef MICA_EXAMPLES_CLI_H
#define MICA_EXAMPLES_CLI_H

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Checks argv against `options` (the program's options, NULL-terminated; NULL for none). An option
 * that takes a value is written with it: "--record FILE". Returns -1 to go on, or the exit status
 * the program should return at once (0 after --help, 2 after an unknown option or a missing
 * value). `usage` is the whole help text: what the program does, its arguments and options,
 * their defaults. */
static inline int cli_check(int argc, char** argv, const char* usage, const char* const* options) {
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    if (strcmp(a, "--help") == 0 || strcmp(a, "-h") == 0) {
      fputs(usage, stdout);
      return 0;
    }
  }
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    if (a[0] != '-' || !(isalpha((unsigned char)a[1]) || (a[1] == '-' && a[2] != 0))) continue;
    const char* known = NULL;
    for (const char* const* o = options; o && *o && !known; ++o) {
      const size_t name = strcspn(*o, " ");
      if (strlen(a) == name && strncmp(a, *o, name) == 0) known = *o;
    }
    if (!known) {
      fprintf(stderr, "%s: unknown option %s (--help lists the options)\n\n%s", argv[0], a, usage);
      return 2;
    }
    const char* value = strchr(known, ' ');
    if (value && i + 1 == argc) {
      fprintf(stderr, "%s: %s needs %s (--help lists the options)\n", argv[0], a, value + 1);
      return 2;
    }
    if (value) ++i; /* the value, whatever it looks like */
  }
  return -1;
}

/* Reads `text` as a whole number from `min` to `max` into `*out`. Returns 1, or 0 after printing
 * "<program>: <what> must be a whole number from <min> to <max>, not '<text>'". */
static inline int cli_int(const char* program, const char* what, const char* text, int min, int max, int* out) {
  char* end = NULL;
  errno = 0;
  const long v = strtol(text, &end, 10);
  if (isspace((unsigned char)text[0]) || end == text || *end != 0 || errno == ERANGE || v < min || v > max) {
    fprintf(stderr, "%s: %s must be a whole number from %d to %d, not '%s'\n", program, what, min, max, text);
    return 0;
  }
  *out = (int)v;
  return 1;
}

/* Reads `text` as a whole finite number from `min` to `max` into `*out`. Returns 1, or 0 after
 * printing "<program>: <what> must be a number from <min> to <max>, not '<text>'". */
static inline int cli_double(const char* program, const char* what, const char* text, double min, double max,
                             double* out) {
  char* end = NULL;
  const double v = strtod(text, &end);
  if (isspace((unsigned char)text[0]) || end == text || *end != 0 || !isfinite(v) || v < min || v > max) {
    fprintf(stderr, "%s: %s must be a number from %g to %g, not '%s'\n", program, what, min, max, text);
    return 0;
  }
  *out = v;
  return 1;
}

/* Makes the folder `path` and the folders above it that are missing (mkdir -p). Returns 1, or 0
 * after printing "<program>: cannot make the folder '<path>': <why>". */
static inline int cli_make_folder(const char* program, const char* path) {
  char partial[4096];
  const size_t n = strlen(path);
  if (n == 0 || n >= sizeof partial) {
    fprintf(stderr, "%s: cannot make the folder '%s': %s\n", program, path, n ? "the name is too long" : "no name");
    return 0;
  }
  int error = 0;
  for (size_t k = 1; k <= n && !error; ++k) {
    if (k < n && path[k] != '/') continue;
    memcpy(partial, path, k);
    partial[k] = 0;
    if (mkdir(partial, 0777) != 0 && errno != EEXIST) error = errno;
  }
  struct stat st;
  if (!error && (stat(path, &st) != 0 || !S_ISDIR(st.st_mode))) error = ENOTDIR; /* a file is in the way */
  if (error) {
    fprintf(stderr, "%s: cannot make the folder '%s': %s\n", program, path, strerror(error));
    return 0;
  }
  return 1;
}

/* Makes the folder a file is to be written into (the part of `file` before its last '/', if any). */
static inline int cli_make_parent(const char* program, const char* file) {
  char parent[4096];
  const char* slash = strrchr(file, '/');
  if (!slash || slash == file) return 1; /* the working folder, or the root */
  const size_t n = (size_t)(slash - file);
  if (n >= sizeof parent) return cli_make_folder(program, file); /* reports the long name */
  memcpy(parent, file, n);
  parent[n] = 0;
  return cli_make_folder(program, parent);
}

#endif
