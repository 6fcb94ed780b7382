/* SPDX-License-Identifier: Apache-2.0 */
/* The command line of the examples and benchmarks: `--help` (or `-h`) prints the program's usage
 * and exits 0; an option the program does not take (an argument starting with "-" and a letter,
 * so "-1e-3" stays a number) is refused with a message naming it and the usage, exit status 2.
 * Header-only, C99 and C++. */
#ifndef MICA_EXAMPLES_CLI_H
#define MICA_EXAMPLES_CLI_H

#include <ctype.h>
#include <stdio.h>
#include <string.h>

/* Checks argv against `options` (the program's options, NULL-terminated; NULL for none). Returns
 * -1 to go on, or the exit status the program should return at once (0 after --help, 2 after an
 * unknown option). `usage` is the whole help text: what the program does, its arguments and
 * options, their defaults. */
static int cli_check(int argc, char** argv, const char* usage, const char* const* options) {
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
    int known = 0;
    for (const char* const* o = options; o && *o && !known; ++o) known = strcmp(a, *o) == 0;
    if (!known) {
      fprintf(stderr, "%s: unknown option %s (--help lists the options)\n\n%s", argv[0], a, usage);
      return 2;
    }
  }
  return -1;
}

#endif
