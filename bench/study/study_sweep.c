/* SPDX-License-Identifier: Apache-2.0 */
/* What accuracy costs in time: every solver knob of the C API, swept on one haptic scene, each
 * configuration timed in-process and compared with the exact solver on the same scene.
 *
 * Scene ("press"): a 0.1 m cube (cells^3 cubes x 6 tets; E = 2e4 Pa, nu = 0.3, rho = 1000,
 * Rayleigh alpha = 2 1/s) fixed at its base, under gravity. A 2 cm sphere starts 5 mm above
 * the top face, presses 10 mm into it over 0.6 s, holds 0.2 s and rises 5 mm over 0.2 s,
 * while a grasp on the side x = 0.1 drags that face along z at 2 cm/s for the first 0.4 s and
 * then holds it. 1 s of simulated time (100 steps of 10 ms by default).
 *
 * Per configuration: wall-clock ms of each mica_step (median and p95 over the steps after a
 * warm-up of a tenth of the run) and the stepping thread's CPU ms (median and p95 alike: what
 * the step cost when other processes share the core), solver iterations and velocity solves per
 * step, and, against the exact solver
 * (MICA_SOLVER_DIRECT: CHOLMOD + the exact Delassus LCP) run on the identical scene:
 * position error (RMS over nodes, worst step, and max over nodes and steps), tool force error
 * (worst step), the deepest penetration of a surface node into the sphere, and the error of
 * the total energy (kinetic + elastic + gravity), relative to the reference's peak of kinetic +
 * elastic energy. Groups:
 *   tolerance   MICA at tol 1e-1 ... 1e-10, PCG at every other decade (cap 100000): the
 *               fixed-tolerance mode
 *   iterations  MICA at tol 1e-300 with a cap of 1 ... 1000, PCG with 1 ... 200 (PCG's cap is
 *               per linear solve, one per contact row plus one): the fixed-iteration mode
 *   pgs         MICA with 1, 2, 4, 8 PGS sweeps per iteration (tol 1e-6)
 *   norm        MICA with the paper's 2-norm stopping test (paper_norm = 1)
 *   warmstart   MICA with the warm start off (velocities and impulses from zero each step),
 *               and on, at tol 1e-4, 1e-6, 1e-8 (if the API has mica_world_def.warm_start)
 *   dt          time step 5 ... 40 ms: MICA tol 1e-6 and exact; "model" error against the
 *               exact run at 5 ms (at the same simulated times)
 *   mesh        cells per side 4 ... 10: MICA tol 1e-6 and exact; "model" error = tool force
 *               against the exact run on the finest mesh
 *   model       the material axis: co-rotational, linear (R = I) and neo-Hookean bodies, each
 *               exact, MICA and MICA-F (PCG on the linear body too), each solver on the three
 *               bodies one after the other;
 *               "model" error against exact co-rotational (quick: exact and MICA-F,
 *               co-rotational and neo-Hookean)
 *   mass        lumped against consistent (MICA, exact); "model" error against exact consistent
 *   stiffness   E = 1e3 ... 1e7 Pa (nu = 0.3), MICA tol 1e-8, PCG tol 1e-8, exact; 0.5 s;
 *               per-step iterations in stiffness_steps.csv (the paper's Figure 2)
 *   drift       free vibration, no damping, no tool, no gravity: the cube's top half pushed
 *               sideways (20 N for 5 steps), then let go; total energy after 1 s over the energy
 *               when the push ended, exact against iterative
 *
 * usage: study_sweep <out-dir> [quick]     (quick: a few configurations, for a smoke test)
 * Writes <out-dir>/sweep.csv and <out-dir>/stiffness_steps.csv.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mica/mica.h>

#include "box_scene.h"
#include "node_selection.h"
#include "study_common.h"
#include "cli.h"

#define L_CUBE 0.1
#define R_TOOL 0.02
/* The study's own code for MICA with the factored sweep (MICA_SOLVER_MICA + MICA_SWEEP_FACTORED). */
#define STUDY_MICA_FACTORED 100
#define SOLVER_NAME(s)                                                                                      \
  ((s) == MICA_SOLVER_MICA ? "MICA" : (s) == STUDY_MICA_FACTORED ? "MICA-F" : (s) == MICA_SOLVER_PCG ? "PCG" \
                                                                                                    : "exact")

typedef struct {
  const char* group;
  int32_t solver;
  double tol;
  int32_t cap;
  double dt;
  int32_t cells;
  int32_t model;
  int32_t mass;
  int32_t warm; /* 1 on (the default), 0 off */
  int32_t pgs;
  int32_t paper;
  double E;
  double T;      /* simulated seconds */
  int32_t scene; /* 0 press, 1 free vibration */
} cfg;

typedef struct {
  int steps, nodes;
  double dt;
  double* x;      /* steps x 3 nodes */
  double* f;      /* steps x 3 */
  double* energy; /* steps: kinetic + elastic + potential */
  double peak_ke; /* peak kinetic + elastic */
  double peak_f;  /* peak |tool force| */
} traj;

typedef struct {
  int ok, failed_step;
  char error[200];
  int steps, nodes, tets;
  double ms_median, ms_p95, ms_mean;
  double cpu_median, cpu_p95; /* the stepping thread's CPU ms */
  double iters_mean, iters_max, solves_mean;
  int not_converged;
  double disp_rms, disp_rms_rel, disp_max, force_err, force_err_rel, energy_err, penetration;
  double model_disp_rms, model_force_err, model_force_err_rel;
  double energy_ratio; /* drift: energy at the end / at the start */
  double peak_force;
} result;

static void tool_y(double t, double* y) {
  const double start = L_CUBE + R_TOOL + 0.005;
  double travel;
  if (t <= 0.6) travel = 0.015 * t / 0.6;
  else if (t <= 0.8) travel = 0.015;
  else travel = 0.015 - 0.005 * (t - 0.8) / 0.2;
  *y = start - travel;
}

static void free_traj(traj* r) {
  free(r->x);
  free(r->f);
  free(r->energy);
  memset(r, 0, sizeof *r);
}

static int steps_of(const cfg* c) { return (int)floor(c->T / c->dt + 0.5); }

/* Index of the reference step at the time of step k of a run with step dt, or -1. */
static int ref_index(const traj* ref, int k, double dt) {
  if (!ref || !ref->steps) return -1;
  const double t = (k + 1) * dt;
  const int j = (int)floor(t / ref->dt + 0.5) - 1;
  if (j < 0 || j >= ref->steps || fabs((j + 1) * ref->dt - t) > 1e-9) return -1;
  return j;
}

/* Runs one configuration. Records its trajectory into `rec` (if not NULL), compares with
 * `ref` (same scene, exact) and `model_ref` (another discretisation, exact; NULL for none). */
static void run(const cfg* c, traj* rec, const traj* ref, const traj* model_ref, FILE* log, result* res) {
  memset(res, 0, sizeof *res);
  res->ok = 1;
  res->failed_step = -1;
  res->disp_rms = res->disp_rms_rel = res->disp_max = res->force_err = res->force_err_rel = res->energy_err = NAN;
  res->model_disp_rms = res->model_force_err = res->model_force_err_rel = res->energy_ratio = NAN;
  mica_world_def wd = mica_world_def_default();
  wd.gravity[0] = wd.gravity[2] = 0;
  wd.gravity[1] = c->scene == 0 ? -9.81 : 0;
  wd.solver = c->solver == STUDY_MICA_FACTORED ? MICA_SOLVER_MICA : c->solver;
  wd.mica_sweep = c->solver == STUDY_MICA_FACTORED ? MICA_SWEEP_FACTORED : MICA_SWEEP_GAUSS_SEIDEL;
  wd.tolerance = c->tol;
  wd.max_iterations = c->cap;
  wd.pgs_sweeps = c->pgs;
  wd.paper_norm = c->paper;
#ifdef MICA_STUDY_HAVE_WARM_START
  wd.warm_start = c->warm;
#endif
  mica_world* w = NULL;
  if (mica_world_create(&wd, &w) != MICA_OK) {
    res->ok = 0;
    snprintf(res->error, sizeof res->error, "world: %s", mica_world_last_error(NULL));
    return;
  }
  /* The cube of scenes/box_scene.h, its base fixed; the press adds the drag and the sphere. */
  box_scene_def def = box_scene_def_default();
  def.body.youngs_modulus = c->E;
  def.body.poisson_ratio = 0.3;
  def.body.density = 1000;
  def.body.rayleigh_alpha = c->scene == 0 ? 2.0 : 0.0;
  def.body.model = c->model;
  def.body.mass = c->mass;
  def.hi[0] = def.hi[1] = def.hi[2] = L_CUBE;
  def.cells[0] = def.cells[1] = def.cells[2] = c->cells;
  def.tool_radius = 0;
  if (c->scene == 0) {
    def.drag_velocity[2] = 0.02;
    def.tool_radius = R_TOOL;
    def.tool_margin = 0.002;
    def.tool_position[0] = def.tool_position[2] = 0.5 * L_CUBE;
    tool_y(0, &def.tool_position[1]);
  }
  box_scene scene;
  if (box_scene_create(w, &def, &scene) != MICA_OK) {
    res->ok = 0;
    snprintf(res->error, sizeof res->error, "scene: %s", mica_world_last_error(w));
    mica_world_destroy(w);
    return;
  }
  const mica_body_id body = scene.body;
  const mica_lpc_id drag = scene.drag;
  const mica_tool_id tool = scene.tool;
  const int32_t nodes = scene.nodes;
  int32_t nsurf = 0;
  int32_t* surf = NULL;
  res->nodes = nodes;
  res->tets = scene.tets;
  if (c->scene == 0) {
    surf = study_surface_nodes(w, body, &nsurf);
  } else {
    /* Free vibration: push the top half sideways (node forces for the first 5 steps). */
    int32_t n = 0;
    const double mid[3] = {0, 0.5 * L_CUBE, 0}, down[3] = {0, -1, 0};
    int32_t* sel = scene_select_plane(w, body, mid, down, 1e-9, &n);
    double* f = calloc(3 * (size_t)n, sizeof(double));
    for (int32_t i = 0; i < n; ++i) f[3 * i] = 20.0 / n;
    mica_body_set_node_forces(w, body, sel, f, n);
    free(f);
    free(sel);
  }

  const int steps = steps_of(c), warm = steps / 10 > 2 ? steps / 10 : 2;
  res->steps = steps;
  double* ms = malloc(sizeof(double) * (size_t)steps);
  double* cpu = malloc(sizeof(double) * (size_t)steps);
  double* x = malloc(sizeof(double) * 3 * (size_t)nodes);
  double* x0 = malloc(sizeof(double) * 3 * (size_t)nodes);
  mica_body_get_rest_positions(w, body, x0, nodes, NULL);
  if (rec) {
    memset(rec, 0, sizeof *rec);
    rec->steps = steps;
    rec->nodes = nodes;
    rec->dt = c->dt;
    rec->x = malloc(sizeof(double) * 3 * (size_t)nodes * (size_t)steps);
    rec->f = calloc(3 * (size_t)steps, sizeof(double));
    rec->energy = malloc(sizeof(double) * (size_t)steps);
  }
  double worst_rms = 0, worst_max = 0, worst_f = 0, worst_e = 0, worst_pen = 0, worst_mrms = 0, worst_mf = 0;
  double sum_ms = 0, sum_it = 0, sum_solves = 0, max_it = 0, e_start = NAN, e_end = NAN, peak_f = 0;
  int timed = 0, compared = 0, mcompared_x = 0, mcompared_f = 0;
  for (int k = 0; k < steps; ++k) {
    const double t = (k + 1) * c->dt;
    if (c->scene == 0) {
      double p[3] = {0.5 * L_CUBE, 0, 0.5 * L_CUBE};
      const double q[4] = {1, 0, 0, 0};
      tool_y(t, &p[1]);
      mica_tool_set_pose(w, tool, p, q);
      if (t > 0.4 + 1e-9 && drag != MICA_NULL_ID) {
        const double still[3] = {0, 0, 0};
        mica_lpc_set_velocity(w, drag, still);
      }
    } else if (k == 5) {
      int32_t n = 0;
      const double mid[3] = {0, 0.5 * L_CUBE, 0}, down[3] = {0, -1, 0};
      int32_t* sel = scene_select_plane(w, body, mid, down, 1e-9, &n);
      double* f = calloc(3 * (size_t)n, sizeof(double));
      mica_body_set_node_forces(w, body, sel, f, n);
      free(f);
      free(sel);
    }
    const double t0 = study_now_ms(), c0 = study_cpu_ms();
    const mica_status s = mica_step(w, c->dt);
    const double elapsed = study_now_ms() - t0, elapsed_cpu = study_cpu_ms() - c0;
    if (s < 0) {
      res->ok = 0;
      res->failed_step = k;
      snprintf(res->error, sizeof res->error, "step %d: %s", k, mica_world_last_error(w));
      break;
    }
    mica_world_stats st;
    memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    mica_world_get_stats(w, &st);
    if (k >= warm) {
      cpu[timed] = elapsed_cpu;
      ms[timed++] = elapsed;
      sum_ms += elapsed;
      sum_it += st.solver_iterations;
      sum_solves += st.solves;
      if (st.solver_iterations > max_it) max_it = st.solver_iterations;
      if (!st.converged) res->not_converged++;
    }
    if (log)
      fprintf(log, "%.3g,%s,%d,%d,%d,%.4f\n", c->E, SOLVER_NAME(c->solver), k + 1, st.solver_iterations, st.converged,
              elapsed);
    mica_body_get_positions(w, body, x, nodes, NULL);
    double f[3] = {0, 0, 0};
    if (tool != MICA_NULL_ID) mica_tool_get_force(w, tool, f, NULL, NULL);
    const double fn = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    if (fn > peak_f) peak_f = fn;
    double ke = 0, el = 0, pot = 0;
    mica_body_get_energy(w, body, &ke, &el, &pot);
    const double energy = ke + el + pot;
    if (k == 4) e_start = energy; /* drift: the push ends with step 4 */
    e_end = energy;
    if (rec) {
      memcpy(rec->x + 3 * (size_t)nodes * k, x, sizeof(double) * 3 * (size_t)nodes);
      memcpy(rec->f + 3 * k, f, sizeof f);
      rec->energy[k] = energy;
      if (ke + el > rec->peak_ke) rec->peak_ke = ke + el;
      if (fn > rec->peak_f) rec->peak_f = fn;
    }
    /* Penetration of surface nodes into the sphere. */
    if (tool != MICA_NULL_ID) {
      double c3[3];
      mica_tool_get_pose(w, tool, c3, NULL);
      for (int32_t a = 0; a < nsurf; ++a) {
        const double* p = x + 3 * surf[a];
        const double d = R_TOOL - sqrt((p[0] - c3[0]) * (p[0] - c3[0]) + (p[1] - c3[1]) * (p[1] - c3[1]) +
                                       (p[2] - c3[2]) * (p[2] - c3[2]));
        if (d > worst_pen) worst_pen = d;
      }
    }
    /* Against the exact run of the same scene. */
    const int j = ref_index(ref, k, c->dt);
    if (j >= 0 && ref->nodes == nodes) {
      const double* xr = ref->x + 3 * (size_t)nodes * j;
      double s2 = 0, m = 0;
      for (int32_t i = 0; i < nodes; ++i) {
        const double dx = x[3 * i] - xr[3 * i], dy = x[3 * i + 1] - xr[3 * i + 1], dz = x[3 * i + 2] - xr[3 * i + 2];
        const double d2 = dx * dx + dy * dy + dz * dz;
        s2 += d2;
        if (d2 > m) m = d2;
      }
      const double rms = sqrt(s2 / nodes);
      if (rms > worst_rms) worst_rms = rms;
      if (sqrt(m) > worst_max) worst_max = sqrt(m);
      const double* fr = ref->f + 3 * j;
      const double df = sqrt((f[0] - fr[0]) * (f[0] - fr[0]) + (f[1] - fr[1]) * (f[1] - fr[1]) +
                             (f[2] - fr[2]) * (f[2] - fr[2]));
      if (df > worst_f) worst_f = df;
      const double de = fabs(energy - ref->energy[j]);
      if (de > worst_e) worst_e = de;
      ++compared;
    }
    const int jm = ref_index(model_ref, k, c->dt);
    if (jm >= 0) {
      if (model_ref->nodes == nodes) {
        const double* xr = model_ref->x + 3 * (size_t)nodes * jm;
        double s2 = 0;
        for (int32_t i = 0; i < 3 * nodes; ++i) s2 += (x[i] - xr[i]) * (x[i] - xr[i]);
        if (sqrt(s2 / nodes) > worst_mrms) worst_mrms = sqrt(s2 / nodes);
        ++mcompared_x;
      }
      const double* fr = model_ref->f + 3 * jm;
      const double df = sqrt((f[0] - fr[0]) * (f[0] - fr[0]) + (f[1] - fr[1]) * (f[1] - fr[1]) +
                             (f[2] - fr[2]) * (f[2] - fr[2]));
      if (df > worst_mf) worst_mf = df;
      ++mcompared_f;
    }
  }
  res->ms_median = study_quantile(ms, timed, 0.5);
  res->ms_p95 = study_quantile(ms, timed, 0.95);
  res->ms_mean = timed ? sum_ms / timed : NAN;
  res->cpu_median = study_quantile(cpu, timed, 0.5);
  res->cpu_p95 = study_quantile(cpu, timed, 0.95);
  res->iters_mean = timed ? sum_it / timed : NAN;
  res->solves_mean = timed ? sum_solves / timed : NAN;
  res->iters_max = max_it;
  res->penetration = worst_pen;
  res->peak_force = peak_f;
  if (compared && res->ok) {
    res->disp_rms = worst_rms;
    res->disp_max = worst_max;
    res->force_err = worst_f;
    res->force_err_rel = ref->peak_f > 0 ? worst_f / ref->peak_f : NAN;
    res->energy_err = ref->peak_ke > 0 ? worst_e / ref->peak_ke : NAN;
    /* Relative to the reference's RMS displacement from rest at its last step. */
    const double* xr = ref->x + 3 * (size_t)nodes * (ref->steps - 1);
    double s2 = 0;
    for (int32_t i = 0; i < 3 * nodes; ++i) s2 += (xr[i] - x0[i]) * (xr[i] - x0[i]);
    res->disp_rms_rel = s2 > 0 ? worst_rms / sqrt(s2 / nodes) : NAN;
  }
  if (res->ok && mcompared_x) res->model_disp_rms = worst_mrms;
  if (res->ok && mcompared_f) {
    res->model_force_err = worst_mf;
    res->model_force_err_rel = model_ref->peak_f > 0 ? worst_mf / model_ref->peak_f : NAN;
  }
  if (res->ok && c->scene == 1) res->energy_ratio = e_end / e_start;
  free(ms);
  free(cpu);
  free(x);
  free(x0);
  free(surf);
  mica_world_destroy(w);
}

/* ---- the plan */

#define MAX_CFG 256
static cfg plan[MAX_CFG];
static int nplan = 0;

static cfg base_cfg(void) {
  cfg c;
  memset(&c, 0, sizeof c);
  c.group = "tolerance";
  c.solver = MICA_SOLVER_MICA;
  c.tol = 1e-6;
  c.cap = 100000;
  c.dt = 0.01;
  c.cells = 8;
  c.model = MICA_MODEL_COROTATIONAL;
  c.mass = MICA_MASS_CONSISTENT;
  c.warm = 1;
  c.pgs = 1;
  c.paper = 0;
  c.E = 2e4;
  c.T = 1.0;
  c.scene = 0;
  return c;
}

static void add(cfg c) {
  if (nplan < MAX_CFG) plan[nplan++] = c;
}

/* Same scene (everything but the solver settings) as the exact reference? */
static int same_scene(const cfg* a, const cfg* b) {
  return a->dt == b->dt && a->cells == b->cells && a->model == b->model && a->mass == b->mass && a->E == b->E &&
         a->T == b->T && a->scene == b->scene;
}

/* A rough cost, for the progress bar: steps x nodes x a per-solver factor. */
static double cost(const cfg* c) {
  const double n = (c->cells + 1.0) * (c->cells + 1.0) * (c->cells + 1.0) / 729.0;
  double f = c->solver == MICA_SOLVER_MICA ? 1.0 : c->solver == MICA_SOLVER_PCG ? 4.0 : 4.0; /* MICA-F too */
  if (c->solver == MICA_SOLVER_MICA && c->E > 1e5) f *= c->E / 1e5;
  if (c->solver == MICA_SOLVER_PCG && c->E > 1e5) f *= sqrt(c->E / 1e5);
  if (c->solver == MICA_SOLVER_DIRECT) f *= n; /* factorisation grows faster than linearly */
  return steps_of(c) * n * f;
}

static void make_plan(int quick) {
  const double tols[] = {1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10};
  const int caps[] = {1, 2, 5, 10, 20, 50, 100, 200, 500, 1000};
  cfg c = base_cfg();
  c.solver = MICA_SOLVER_DIRECT;
  add(c); /* the exact reference of the base scene, first */
  for (int s = 0; s < 3; ++s)
    for (int k = 0; k < 10; ++k) {
      if (quick && k % 3) continue;
      if (s >= 1 && (k == 2 || k == 4 || k == 6 || k == 8)) continue; /* PCG, MICA-F: every other decade */
      c = base_cfg();
      c.solver = s == 0 ? MICA_SOLVER_MICA : s == 1 ? MICA_SOLVER_PCG : STUDY_MICA_FACTORED;
      c.tol = tols[k];
      add(c);
    }
  for (int s = 0; s < 2; ++s)
    for (int k = 0; k < 10; ++k) {
      if (quick && k % 3) continue;
      if (s == 1 && caps[k] > 200) continue; /* PCG's cap is per solve, and there is one per contact row */
      c = base_cfg();
      c.group = "iterations";
      c.solver = s == 0 ? MICA_SOLVER_MICA : MICA_SOLVER_PCG;
      c.tol = 1e-300;
      c.cap = caps[k];
      add(c);
    }
  /* The material axis: co-rotational, linear and (0.8) neo-Hookean, error and ms per step; each
   * solver runs the three bodies one after the other, so that they are timed close together
   * (quick: co-rotational and neo-Hookean, exact and MICA-F). */
  for (int s = 0; s < 4; ++s)
    for (int m = 0; m < 3; ++m) {
      c = base_cfg();
      c.group = "model";
      c.model = m == 0 ? MICA_MODEL_COROTATIONAL : m == 1 ? MICA_MODEL_LINEAR : MICA_MODEL_NEO_HOOKEAN;
      if (s == 3 && m != 1) continue; /* PCG only where it differs: the linear body */
      c.solver = s == 0 ? MICA_SOLVER_DIRECT : s == 1 ? MICA_SOLVER_MICA : s == 2 ? STUDY_MICA_FACTORED : MICA_SOLVER_PCG;
      if (quick && (m == 1 || s == 1 || s == 3)) continue;
      add(c);
    }
  if (quick) return;
  for (int p = 2; p <= 8; p *= 2) {
    c = base_cfg();
    c.group = "pgs";
    c.pgs = p;
    add(c);
  }
  for (int k = 1; k <= 7; k += 2) {
    c = base_cfg();
    c.group = "norm";
    c.paper = 1;
    c.tol = tols[k];
    add(c);
  }
#ifdef MICA_STUDY_HAVE_WARM_START
  for (int k = 3; k <= 7; k += 2) {
    c = base_cfg();
    c.group = "warmstart";
    c.warm = 0;
    c.tol = tols[k];
    add(c);
    c.warm = 1;
    add(c); /* the same with the warm start, in this group for the table */
  }
#endif
  const double dts[] = {0.005, 0.01, 0.02, 0.04};
  for (int k = 0; k < 4; ++k)
    for (int s = 0; s < 2; ++s) {
      c = base_cfg();
      c.group = "dt";
      c.dt = dts[k];
      c.solver = s == 0 ? MICA_SOLVER_DIRECT : MICA_SOLVER_MICA;
      add(c);
    }
  const int meshes[] = {10, 8, 6, 4};
  for (int k = 0; k < 4; ++k)
    for (int s = 0; s < 2; ++s) {
      c = base_cfg();
      c.group = "mesh";
      c.cells = meshes[k];
      c.solver = s == 0 ? MICA_SOLVER_DIRECT : MICA_SOLVER_MICA;
      add(c);
    }
  for (int m = 0; m < 2; ++m)
    for (int s = 0; s < 3; ++s) {
      c = base_cfg();
      c.group = "mass";
      c.mass = m == 0 ? MICA_MASS_CONSISTENT : MICA_MASS_LUMPED;
      if (s == 2) continue;
      c.solver = s == 0 ? MICA_SOLVER_DIRECT : s == 1 ? MICA_SOLVER_MICA : MICA_SOLVER_PCG;
      add(c);
    }
  const double Es[] = {1e3, 1e4, 1e5, 1e6, 1e7};
  for (int k = 0; k < 5; ++k)
    for (int s = 0; s < 4; ++s) {
      c = base_cfg();
      c.group = "stiffness";
      c.E = Es[k];
      c.T = 0.5;
      c.tol = 1e-8;
      c.solver = s == 0 ? MICA_SOLVER_DIRECT : s == 1 ? MICA_SOLVER_MICA : s == 2 ? MICA_SOLVER_PCG : STUDY_MICA_FACTORED;
      add(c);
    }
  const double dtols[] = {1e-2, 1e-4, 1e-6, 1e-8};
  c = base_cfg();
  c.group = "drift";
  c.scene = 1;
  c.solver = MICA_SOLVER_DIRECT;
  add(c);
  for (int k = 0; k < 4; ++k) {
    c.solver = MICA_SOLVER_MICA;
    c.tol = dtols[k];
    add(c);
  }
  for (int k = 1; k < 4; k += 2) {
    c.solver = MICA_SOLVER_PCG;
    c.tol = dtols[k];
    add(c);
  }
}

/* Exact references kept for the run: one per scene. */
#define MAX_REF 32
static cfg ref_cfg[MAX_REF];
static traj ref_traj[MAX_REF];
static int nref = 0;

static const traj* find_ref(const cfg* c) {
  for (int r = 0; r < nref; ++r)
    if (same_scene(&ref_cfg[r], c)) return &ref_traj[r];
  return NULL;
}

/* The exact run of another discretisation that a configuration's "model" error is taken against. */
static const traj* find_model_ref(const cfg* c) {
  cfg m = *c;
  if (strcmp(c->group, "dt") == 0) m.dt = 0.005;
  else if (strcmp(c->group, "mesh") == 0) m.cells = 10;
  else if (strcmp(c->group, "model") == 0) m.model = MICA_MODEL_COROTATIONAL;
  else if (strcmp(c->group, "mass") == 0) m.mass = MICA_MASS_CONSISTENT;
  else return NULL;
  return find_ref(&m);
}

static const char* model_name(int32_t model) {
  return model == MICA_MODEL_LINEAR ? "linear" : model == MICA_MODEL_NEO_HOOKEAN ? "neo-hookean" : "corotational";
}

static void fmt(FILE* f, double v) {
  if (isnan(v)) fprintf(f, ",");
  else fprintf(f, ",%.6g", v);
}

static const char kUsage[] =
    "usage: study_sweep <out-dir> [quick]\n"
    "What accuracy costs in time: every solver knob of the C API swept on one haptic scene, each\n"
    "configuration timed and compared with the exact solver. Writes <out-dir>/sweep.csv and\n"
    "<out-dir>/stiffness_steps.csv (docs/accuracy-vs-time.md).\n"
    "  out-dir  where the CSV files go (made if missing)\n"
    "  quick    a few configurations (a smoke test)\n"
    "  --help   this text\n";

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  if (argc < 2) {
    fprintf(stderr, "usage: study_sweep <out-dir> [quick]\n");
    return 2;
  }
  const int quick = argc > 2 && strcmp(argv[2], "quick") == 0;
  make_plan(quick);
  if (!cli_make_folder(argv[0], argv[1])) return 1;
  char path[1024], machine[256];
  study_machine(machine, sizeof machine);
  snprintf(path, sizeof path, "%s/sweep.csv", argv[1]);
  FILE* csv = fopen(path, "w");
  snprintf(path, sizeof path, "%s/stiffness_steps.csv", argv[1]);
  FILE* steps_csv = fopen(path, "w");
  if (!csv || !steps_csv) {
    fprintf(stderr, "cannot write into %s\n", argv[1]);
    return 1;
  }
  fprintf(csv, "# study_sweep: %s; libmica %d\n", machine, mica_version());
  fprintf(csv,
          "group,solver,tol,cap,dt_s,cells,nodes,tets,model,mass,warm_start,pgs_sweeps,paper_norm,E_Pa,steps,"
          "ms_median,ms_p95,ms_mean,cpu_ms_median,cpu_ms_p95,iters_mean,iters_max,solves_mean,steps_not_converged,"
          "disp_rms_err_m,disp_rms_err_rel,"
          "disp_max_err_m,force_err_N,force_err_rel,energy_err_rel,penetration_m,peak_force_N,model_disp_rms_err_m,"
          "model_force_err_N,model_force_err_rel,energy_ratio_end,status\n");
  fprintf(steps_csv, "E_Pa,solver,step,iterations,converged,ms\n");
  printf("# study_sweep: %d configurations; %s\n", nplan, machine);
#ifndef MICA_STUDY_HAVE_WARM_START
  printf("# this libmica's mica_world_def has no warm_start: the warm-start axis is skipped\n");
#endif
  printf("%-10s %-6s %-12s %8s %6s %6s %3s %8s %8s %8s %8s %8s %10s %10s %9s  %s\n", "group", "solver", "model", "tol",
         "cap", "dt", "n", "E", "med ms", "p95 ms", "cpu ms", "iters", "rms err m", "F err N", "pen mm", "status");
  double total = 0, done = 0;
  for (int i = 0; i < nplan; ++i) total += cost(&plan[i]);
  for (int i = 0; i < nplan; ++i) {
    cfg* c = &plan[i];
    /* A configuration whose exact reference is not in the plan before it: run that first. */
    if (c->solver != MICA_SOLVER_DIRECT && !find_ref(c) && nref < MAX_REF) {
      cfg r = *c;
      r.solver = MICA_SOLVER_DIRECT;
      result rr;
      run(&r, &ref_traj[nref], NULL, NULL, NULL, &rr);
      ref_cfg[nref++] = r;
    }
    result res;
    traj* rec = NULL;
    if (c->solver == MICA_SOLVER_DIRECT && !find_ref(c) && nref < MAX_REF) rec = &ref_traj[nref];
    FILE* log = strcmp(c->group, "stiffness") == 0 ? steps_csv : NULL;
    run(c, rec, rec ? NULL : find_ref(c), find_model_ref(c), log, &res);
    if (rec) {
      ref_cfg[nref++] = *c;
      /* The exact run against itself: zero error by definition. */
      if (res.ok) res.disp_rms = res.disp_rms_rel = res.disp_max = res.force_err = res.force_err_rel = res.energy_err = 0;
      if (res.ok && find_model_ref(c) == rec) res.model_disp_rms = res.model_force_err = res.model_force_err_rel = 0;
    }
    char status[240];
    if (res.ok) snprintf(status, sizeof status, res.not_converged ? "capped" : "ok");
    else snprintf(status, sizeof status, "failed %s", res.error);
    for (char* p = status; *p; ++p)
      if (*p == ',' || *p == '\n') *p = ';';
    fprintf(csv, "%s,%s,%.3g,%d,%.4g,%d,%d,%d,%s,%s,%d,%d,%d,%.3g,%d", c->group, SOLVER_NAME(c->solver),
            c->solver == MICA_SOLVER_DIRECT ? 0.0 : c->tol, c->solver == MICA_SOLVER_DIRECT ? 0 : c->cap, c->dt,
            c->cells, res.nodes, res.tets,
            model_name(c->model),
            c->mass == MICA_MASS_LUMPED ? "lumped" : "consistent", c->warm, c->pgs, c->paper, c->E, res.steps);
    fmt(csv, res.ms_median);
    fmt(csv, res.ms_p95);
    fmt(csv, res.ms_mean);
    fmt(csv, res.cpu_median);
    fmt(csv, res.cpu_p95);
    fmt(csv, res.iters_mean);
    fmt(csv, res.iters_max);
    fmt(csv, res.solves_mean);
    fprintf(csv, ",%d", res.not_converged);
    fmt(csv, res.disp_rms);
    fmt(csv, res.disp_rms_rel);
    fmt(csv, res.disp_max);
    fmt(csv, res.force_err);
    fmt(csv, res.force_err_rel);
    fmt(csv, res.energy_err);
    fmt(csv, res.penetration);
    fmt(csv, res.peak_force);
    fmt(csv, res.model_disp_rms);
    fmt(csv, res.model_force_err);
    fmt(csv, res.model_force_err_rel);
    fmt(csv, res.energy_ratio);
    fprintf(csv, ",%s\n", status);
    fflush(csv);
    printf("%-10s %-6s %-12s %8.0e %6d %6.4f %3d %8.0e %8.3f %8.3f %8.3f %8.1f %10.3g %10.3g %9.4f  %s\n", c->group,
           SOLVER_NAME(c->solver), model_name(c->model), c->solver == MICA_SOLVER_DIRECT ? 0.0 : c->tol,
           c->solver == MICA_SOLVER_DIRECT ? 0 : c->cap, c->dt, c->cells, c->E, res.ms_median, res.ms_p95,
           res.cpu_median, res.iters_mean, res.disp_rms, res.force_err, 1e3 * res.penetration, status);
    fflush(stdout);
    done += cost(c);
    study_progress(done, total);
  }
  fclose(steps_csv);
  fclose(csv);
  for (int r = 0; r < nref; ++r) free_traj(&ref_traj[r]);
  return 0;
}
