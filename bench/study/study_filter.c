/* SPDX-License-Identifier: Apache-2.0 */
/* The device-side knob: the moving-average window N of the rendered force (filter_window),
 * against its delay and its smoothness, with the simulated stylus driven through
 * mica_device_poll() in lockstep with the simulation (16 servo polls of 1 ms per 16 ms step,
 * so the run is the same on any machine).
 *
 * Scene (the paper's Figure 1): a 10 cm cube (8^3 cubes x 6 tets, E = 1e4 Pa, nu = 0.4,
 * Rayleigh alpha = 2) fixed at its base, no gravity; the stylus carries a 2 cm sphere from 1 mm
 * above the top face 15 mm into it over 0.5 s, holds 0.5 s, lifts out over 0.5 s and waits
 * 0.5 s. MICA at tolerance 1e-5. The device's clamp and rate limit are opened (1000 N, 1e9 N/s)
 * so what is measured is the filter alone. Two force modes: the local model (the default:
 * F0 + H (x - x0) evaluated at every poll) and the zero-order hold (the step's force, held).
 *
 * Per (mode, N): the delay of the rendered force behind the raw one (how much later its
 * centre of mass in time comes, over the whole press: (N - 1) / 2 samples for a plain moving
 * average of any signal, a little less with the restarts at contact and release), the ripple (RMS of the change
 * between consecutive samples while in contact, N per ms) and the largest single jump, the
 * peak forces, and the RMS difference from the raw force.
 *
 * usage: study_filter <out-dir>
 * Writes <out-dir>/filter.csv and <out-dir>/filter_samples.csv (every servo sample).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mica/mica.h>
#include <mica/mica_device.h>

#include "box_scene.h"
#include "study_common.h"
#include "cli.h"

#define POLLS_PER_STEP 16
#define STEP_S 0.016
#define DURATION_S 2.0
#define MAX_SAMPLES 4000

static void press(double t, double p[3], void* user) {
  (void)user;
  const double depth = t < 0.5 ? 0.016 * t / 0.5 : t < 1.0 ? 0.016 : t < 1.5 ? 0.016 * (1.5 - t) / 0.5 : 0;
  p[0] = 0.002;
  p[1] = 0.021 - depth; /* the sphere (R = 2 cm) touches the top face y = 0 at p_y = 0.02 */
  p[2] = 0.001;
}

typedef struct {
  int n;
  double t[MAX_SAMPLES], y[MAX_SAMPLES], raw[MAX_SAMPLES], out[MAX_SAMPLES], sim[MAX_SAMPLES];
} samples;

static int run(int mode, int window, samples* s) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[1] = 0;
  wd.solver = MICA_SOLVER_MICA;
  wd.mica_sweep = MICA_SWEEP_GAUSS_SEIDEL; /* the paper's sweep */
  wd.tolerance = 1e-5;
  wd.max_iterations = 5000;
  mica_world* w = NULL;
  if (mica_world_create(&wd, &w) != MICA_OK) return 1;
  /* The soft block of scenes/box_scene.h (as examples_c/haptic_loop.c), E = 1e4 Pa. */
  box_scene_def def = box_scene_block_def();
  def.body.youngs_modulus = 1e4;
  def.body.poisson_ratio = 0.4;
  def.body.rayleigh_alpha = 2;
  box_scene scene;
  mica_device_def dd = mica_device_def_default();
  mica_device_id dev;
  if (box_scene_create(w, &def, &scene) != MICA_OK) goto fail;
  dd.backend = MICA_DEVICE_SIMULATED;
  dd.simulated_kind = MICA_SIMULATED_TRAJECTORY;
  dd.trajectory = press;
  dd.tool = scene.tool;
  dd.force_mode = mode;
  dd.filter_window = window;
  dd.max_force = 1000;
  dd.max_force_rate = 1e9;
  if (mica_device_create(w, &dd, &dev) != MICA_OK) goto fail;
  s->n = 0;
  const int steps = (int)(DURATION_S / STEP_S + 0.5);
  double sim_force = 0;
  for (int k = 0; k < steps; ++k) {
    for (int p = 0; p < POLLS_PER_STEP && s->n < MAX_SAMPLES; ++p) {
      mica_device_state state;
      memset(&state, 0, sizeof state);
      state.struct_size = sizeof state;
      double f[3] = {0, 0, 0};
      if (mica_device_poll(w, dev, &state, f) < 0) goto fail;
      mica_device_stats st;
      memset(&st, 0, sizeof st);
      st.struct_size = sizeof st;
      mica_device_get_stats(w, dev, &st);
      s->t[s->n] = state.timestamp;
      s->y[s->n] = state.position[1];
      s->raw[s->n] = st.last_raw_force[1];
      s->out[s->n] = f[1];
      s->sim[s->n] = sim_force;
      s->n++;
    }
    if (mica_step(w, STEP_S) < 0) goto fail;
    double f[3];
    mica_tool_get_force(w, scene.tool, f, NULL, NULL);
    sim_force = f[1];
  }
  mica_device_destroy(w, dev);
  mica_world_destroy(w);
  return 0;
fail:
  fprintf(stderr, "filter run (mode %d, N %d): %s\n", mode, window, mica_world_last_error(w));
  mica_world_destroy(w);
  return 1;
}

static const char kUsage[] =
    "usage: study_filter <out-dir>\n"
    "The rendered force's moving-average window against its delay and smoothness, the simulated stylus\n"
    "polled in lockstep with the simulation. Writes <out-dir>/filter.csv and\n"
    "<out-dir>/filter_samples.csv.\n"
    "  out-dir  where the CSV files go (made if missing)\n"
    "  --help   this text\n";

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  if (argc < 2) {
    fprintf(stderr, "usage: study_filter <out-dir>\n");
    return 2;
  }
  if (!cli_make_folder(argv[0], argv[1])) return 1;
  char path[1024], machine[256];
  study_machine(machine, sizeof machine);
  snprintf(path, sizeof path, "%s/filter.csv", argv[1]);
  FILE* csv = fopen(path, "w");
  snprintf(path, sizeof path, "%s/filter_samples.csv", argv[1]);
  FILE* smp = fopen(path, "w");
  if (!csv || !smp) {
    fprintf(stderr, "cannot write into %s\n", argv[1]);
    return 1;
  }
  fprintf(csv, "# study_filter: %s; libmica %d; %d polls of 1 ms per %.3f s step\n", machine, mica_version(),
          POLLS_PER_STEP, STEP_S);
  fprintf(csv,
          "mode,N,delay_ms,delay_theory_ms,ripple_rms_N_per_ms,ripple_raw_N_per_ms,max_jump_N,max_jump_raw_N,"
          "peak_raw_N,peak_filtered_N,rms_vs_raw_N\n");
  fprintf(smp, "mode,N,t_s,device_y_m,raw_force_y_N,filtered_force_y_N,step_force_y_N\n");
  const int windows[] = {1, 2, 5, 10, 20, 40, 80};
  const int nw = 7;
  static samples s;
  printf("%-6s %4s %9s %9s %12s %12s %10s %10s %9s %9s\n", "mode", "N", "delay ms", "(N-1)/2", "ripple N/ms",
         "raw N/ms", "max jump", "raw jump", "peak raw", "peak out");
  for (int m = 0; m < 2; ++m)
    for (int k = 0; k < nw; ++k) {
      const int mode = m == 0 ? MICA_FORCE_LOCAL_MODEL : MICA_FORCE_HOLD;
      const char* name = m == 0 ? "local" : "hold";
      if (run(mode, windows[k], &s)) return 1;
      /* Delay: how much later the rendered force's centre of mass in time comes than the raw
       * one's, over the whole press. A causal moving average of N samples delays the centroid of
       * any signal by exactly (N - 1) / 2 samples; the restarts at contact and release make it
       * a little less. */
      double m_raw = 0, t_raw = 0, m_out = 0, t_out = 0;
      for (int i = 0; i < s.n; ++i) {
        m_raw += s.raw[i];
        t_raw += s.t[i] * s.raw[i];
        m_out += s.out[i];
        t_out += s.t[i] * s.out[i];
      }
      const double delay = m_raw > 0 && m_out > 0 ? 1e3 * (t_out / m_out - t_raw / m_raw) : NAN;
      double r2 = 0, rr2 = 0, jump = 0, jump_raw = 0, peak_raw = 0, peak_out = 0, d2 = 0;
      int nc = 0;
      for (int i = 1; i < s.n; ++i) {
        const double d = s.out[i] - s.out[i - 1], dr = s.raw[i] - s.raw[i - 1];
        if (s.raw[i] != 0 && s.raw[i - 1] != 0) {
          r2 += d * d;
          rr2 += dr * dr;
          ++nc;
          if (fabs(d) > jump) jump = fabs(d);
          if (fabs(dr) > jump_raw) jump_raw = fabs(dr);
        }
      }
      for (int i = 0; i < s.n; ++i) {
        if (s.raw[i] > peak_raw) peak_raw = s.raw[i];
        if (s.out[i] > peak_out) peak_out = s.out[i];
        d2 += (s.out[i] - s.raw[i]) * (s.out[i] - s.raw[i]);
        fprintf(smp, "%s,%d,%.4f,%.7g,%.7g,%.7g,%.7g\n", name, windows[k], s.t[i], s.y[i], s.raw[i], s.out[i],
                s.sim[i]);
      }
      const double ripple = nc ? sqrt(r2 / nc) : NAN, ripple_raw = nc ? sqrt(rr2 / nc) : NAN;
      fprintf(csv, "%s,%d,%.2f,%.1f,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", name, windows[k], delay,
              0.5 * (windows[k] - 1), ripple, ripple_raw, jump, jump_raw, peak_raw, peak_out, sqrt(d2 / s.n));
      printf("%-6s %4d %9.2f %9.1f %12.4g %12.4g %10.4g %10.4g %9.4f %9.4f\n", name, windows[k], delay,
             0.5 * (windows[k] - 1), ripple, ripple_raw, jump, jump_raw, peak_raw, peak_out);
      fflush(stdout);
      study_progress(m * nw + k + 1, 2 * nw);
    }
  fclose(csv);
  fclose(smp);
  return 0;
}
