/* SPDX-License-Identifier: Apache-2.0 */
/* Replays a recording (mica_world_record_start) into a fresh world, checks every step against the
 * recording, and writes what a session scorer or a bug hunter reads:
 *   replay_steps.csv   step, status, solver iterations and residual, contacts, ms
 *   replay_forces.csv  step, kind (tool or lpc), id, force (N): each tool's force and each
 *                      constraint's reaction, every step (long format: one row per object)
 *   replay_NNNNNN.vtk  every body (positions, von Mises stress, regions) every N steps (--vtk-every)
 * Exit status: 0 when every step reproduced the recording, 3 when the replay diverged (the message
 * names the step), 4 when the recording was cut short (its steps are replayed, then the message
 * says after how many it ends), 1 for another error, 2 for bad arguments. Installed with libmica.
 *
 * usage: mica_replay recording [output-folder] [--vtk-every N]
 */
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mica/mica.h>

#include "cli.h"

static const char kUsage[] =
    "usage: mica_replay recording [output-folder] [--vtk-every N]\n"
    "Replays a libmica recording (mica_world_record_start) step by step, checks each step against the\n"
    "recording bit for bit, and writes replay_steps.csv (solver figures per step), replay_forces.csv\n"
    "(each tool's force and each constraint's reaction per step, N) and, with --vtk-every N, the\n"
    "bodies every N steps as replay_NNNNNN.vtk (ParaView).\n"
    "  recording      the file written by mica_world_record_start\n"
    "  output-folder  where the files go (made if missing; default .)\n"
    "  --vtk-every N  write the bodies every N steps (default 0: never)\n"
    "  --help         this text\n"
    "Exit status 0: every step reproduced; 3: the replay diverged; 4: the recording was cut short\n"
    "(it ends before the entry that stopping a recording writes); 1: another error; 2: bad arguments.\n";

/* The exit status for a replay that stopped with `status`. */
static int exit_status_of(mica_status status) {
  return status == MICA_ERR_DIVERGED ? 3 : status == MICA_ERR_TRUNCATED ? 4 : 1;
}

/* Writes each object's force of one kind: tools' forces or constraints' reactions. */
static int write_forces(mica_world* w, FILE* csv, int64_t step, int32_t kind) {
  uint64_t ids[256];
  int32_t count = 0;
  if (mica_world_get_ids(w, kind, ids, 256, &count) != MICA_OK) return -1;
  for (int32_t k = 0; k < count; ++k) {
    double f[3] = {0, 0, 0};
    const mica_status s = kind == MICA_OBJECT_TOOL ? mica_tool_get_force(w, ids[k], f, NULL, NULL)
                                                   : mica_lpc_get_reaction(w, ids[k], f);
    if (s != MICA_OK) return -1;
    fprintf(csv, "%" PRId64 ",%s,0x%016" PRIx64 ",%.17g,%.17g,%.17g\n", step, kind == MICA_OBJECT_TOOL ? "tool" : "lpc",
            ids[k], f[0], f[1], f[2]);
  }
  return 0;
}

int main(int argc, char** argv) {
  static const char* const options[] = {"--vtk-every N", NULL};
  const int cli = cli_check(argc, argv, kUsage, options);
  if (cli >= 0) return cli;
  const char* positional[2] = {NULL, "."};
  int n_positional = 0, vtk_every = 0;
  for (int i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--vtk-every") == 0) {
      if (!cli_int(argv[0], "--vtk-every", argv[++i], 0, INT32_MAX, &vtk_every)) return 2;
    } else if (n_positional < 2) {
      positional[n_positional++] = argv[i];
    }
  }
  if (n_positional < 1) {
    fputs(kUsage, stderr);
    return 2;
  }
  if (!cli_make_folder(argv[0], positional[1])) return 1;
  mica_replay* replay = NULL;
  const mica_status opened = mica_replay_open(positional[0], &replay);
  if (opened != MICA_OK) {
    fprintf(stderr, "mica_replay: %s\n", mica_world_last_error(NULL));
    return exit_status_of(opened);
  }
  mica_world* w = mica_replay_world(replay);
  char path[4096];
  snprintf(path, sizeof path, "%s/replay_steps.csv", positional[1]);
  FILE* steps_csv = fopen(path, "w");
  snprintf(path, sizeof path, "%s/replay_forces.csv", positional[1]);
  FILE* forces_csv = fopen(path, "w");
  if (!steps_csv || !forces_csv) {
    fprintf(stderr, "mica_replay: cannot write into %s\n", positional[1]);
    return 1;
  }
  fprintf(steps_csv, "step,status,iterations,residual,contacts,ms\n");
  fprintf(forces_csv, "step,kind,id,fx_N,fy_N,fz_N\n");
  int64_t step = 0;
  int32_t stepped = 1;
  int exit_status = 0;
  double ms = 0;
  while (stepped) {
    const mica_status s = mica_replay_step(replay, &stepped);
    if (s == MICA_ERR_TRUNCATED) {
      fprintf(stderr, "mica_replay: %s\n", mica_world_last_error(w));
      exit_status = exit_status_of(s);
      break;
    }
    if (s < 0 && s != MICA_ERR_NUMERICAL) { /* a recorded step that failed fails again: not an error */
      fprintf(stderr, "mica_replay: step %" PRId64 ": %s\n  %s\n", step + 1, mica_status_string(s), mica_world_last_error(w));
      exit_status = exit_status_of(s);
      break;
    }
    if (!stepped) break;
    ++step;
    mica_world_stats st = {.struct_size = sizeof st};
    mica_world_get_stats(w, &st);
    ms += st.ms_last_step;
    fprintf(steps_csv, "%" PRId64 ",%d,%d,%.6g,%d,%.3f\n", step, s, st.solver_iterations, st.solver_residual, st.contacts,
            st.ms_last_step);
    if (write_forces(w, forces_csv, step, MICA_OBJECT_TOOL) != 0 || write_forces(w, forces_csv, step, MICA_OBJECT_LPC) != 0) {
      fprintf(stderr, "mica_replay: reading step %" PRId64 ": %s\n", step, mica_world_last_error(w));
      exit_status = 1;
      break;
    }
    if (vtk_every > 0 && step % vtk_every == 0) {
      snprintf(path, sizeof path, "%s/replay_%06" PRId64 ".vtk", positional[1], step);
      if (mica_world_write_vtk(w, path) != MICA_OK) {
        fprintf(stderr, "mica_replay: %s\n", mica_world_last_error(w));
        exit_status = 1;
        break;
      }
    }
  }
  fclose(steps_csv);
  fclose(forces_csv);
  mica_replay_close(replay);
  printf("mica_replay: %" PRId64 " steps replayed in %.1f ms of stepping, %s\n", step, ms,
         exit_status == 0   ? "each as recorded, bit for bit"
         : exit_status == 4 ? "each as recorded; then the recording ends, cut short (see above)"
                            : "stopped (see above)");
  return exit_status;
}
