/* SPDX-License-Identifier: Apache-2.0 */
/* Analytic anchors: mesh convergence toward Hertz (a sphere indenting a deep block) and toward
 * Euler-Bernoulli (a cantilever under its own weight). Both are static, small-strain linear
 * elasticity problems, so the bodies are MICA_MODEL_LINEAR first (and the co-rotational and
 * neo-Hookean ones beside it, on Hertz's finest mesh and every beam), with the exact solver
 * (MICA_SOLVER_DIRECT), stepped with h = 1 s: the mass term M / h^2 is then some 1e-8 of the
 * stiffness, and each step is a Newton step of the static problem (a linear body's matrix is
 * factored once). What is measured is the discretisation error, not the solver's.
 *
 * Hertz: a quarter of a block [0, W] x [-D, 0] x [0, W] (W = D = 0.1 m = 45 contact radii),
 * symmetry planes x = 0 and z = 0 (sliding projection constraints), the base fixed, sides free;
 * E = 1e4 Pa, nu = 0.3. A sphere of R = 1 cm centred on the axis is pushed to d = 0.5 mm
 * (d / R = 0.05, contact radius a = sqrt(R d) = 2.24 mm) in 4 increments of 2 steps, then 3
 * more steps. The mesh is a tensor grid graded alike along each axis, x_i = W sinh(4 i / n) /
 * sinh(4) for i = 0 ... n (nearly uniform near the contact, growing by e^(4/n) per cell
 * outward, so raising n refines every cell alike), each cell cut into 5 tets (the cut
 * alternating with the cell parity); n = 8, 12, 16, 20, 24 (2560 ... 69120 tets). The element
 * size reported is the cell size at the contact edge x = a. F_FEM = 4 x the tool's force
 * against F_Hertz = 4/3 E/(1 - nu^2) sqrt(R) d^1.5; the mean of the last 3 steps, since the
 * contact set still flickers between steps on the coarser meshes (the spread is reported).
 *
 * Euler-Bernoulli: a beam L = 0.2 m, square section H = 0.02 m, E = 1e7 Pa, nu = 0.3,
 * rho = 1000, clamped (all nodes of x = 0 fixed), under gravity; the tip deflection (mean over
 * the nodes of the end face) against w = q L^4 / (8 E I), q = rho g H^2 (Timoshenko's shear
 * term, q L^2 / (2 k G A) with k = 5/6, is printed beside it: about +1%). Box meshes of
 * 10 n x n x n cubes x 6 tets, n = 1 ... 8; linear, co-rotational and neo-Hookean bodies.
 *
 * Uniaxial compression (the material axis at large strain): the cube of scenes/uniaxial_scene.h
 * (0.1 m, 8^3 cubes x 6 tets, E = 1e4 Pa, nu = 0.45) on frictionless ends, pressed by its top
 * plate in 5 % increments to 40 %, each increment one step of h = 1 s that moves the plate and 6
 * steps that hold it (the static answer: the mass term is some 1e-3 of the stiffness). The
 * deformation is homogeneous, which linear tets represent exactly, so the plate's reaction over the
 * rest area differs from a closed form only by the model: against the stable neo-Hookean closed
 * form (uniaxial_neo_hookean_nominal_stress) and Hooke's E (s - 1), which the linear and the
 * co-rotational bodies are here (no rotation). Per increment: the stepping thread's CPU ms of the
 * loading step and its velocity solves (the Newton re-solves of a large step), and the median CPU
 * ms of the increment's 7 steps. Linear, co-rotational and neo-Hookean bodies, one after the other.
 *
 * usage: study_anchors <out-dir> [quick]
 * Writes <out-dir>/anchors.csv (one row per mesh), <out-dir>/hertz_curve.csv (F against d
 * on every Hertz level) and <out-dir>/uniaxial.csv (one row per model and increment).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mica/mica.h>

#include "node_selection.h"
#include "study_common.h"
#include "uniaxial_scene.h"
#include "cli.h"

#define HERTZ_R 0.01
#define HERTZ_D 0.0005
#define HERTZ_E 1e4
#define HERTZ_NU 0.3
#define HERTZ_W 0.1

/* A 1D graded coordinate list from 0 to `length` in n cells: x_i = length sinh(k i / n) / sinh(k),
 * nearly uniform near 0 and growing geometrically (by e^(k/n) per cell) further out, so that
 * raising n refines every cell alike. Returns the count of points, n + 1. */
static int graded(int n, double k, double length, double* out) {
  for (int i = 0; i <= n; ++i) out[i] = length * sinh(k * i / n) / sinh(k);
  return n + 1;
}

/* 5-tet cuts of a cube, corner index = x + 2 y + 4 z. */
static const int cut_even[5][4] = {{0, 3, 5, 6}, {1, 0, 3, 5}, {2, 0, 6, 3}, {4, 0, 5, 6}, {7, 3, 6, 5}};
static const int cut_odd[5][4] = {{1, 2, 4, 7}, {0, 1, 4, 2}, {3, 1, 2, 7}, {5, 1, 7, 4}, {6, 2, 4, 7}};

static double det3(const double* a, const double* b, const double* c, const double* d) {
  const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
  const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
  const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
  return u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0]);
}

typedef struct {
  double h, value, theory, timoshenko, ms, spread;
  int32_t nodes, tets;
  int ok;
} level_result;

static double g_kappa = 4.0, g_W = HERTZ_W;
static int g_trace = 0;

/* A world with the exact solver and gravity gz along z (m/s^2). */
static mica_world* direct_world(double gz) {
  mica_world_def wd = mica_world_def_default();
  wd.gravity[0] = wd.gravity[1] = 0;
  wd.gravity[2] = gz;
  wd.solver = MICA_SOLVER_DIRECT;
  mica_world* w = NULL;
  mica_world_create(&wd, &w);
  return w;
}

static level_result hertz_level(int cells, int32_t model, FILE* curve) {
  level_result r;
  memset(&r, 0, sizeof r);
  const double a = sqrt(HERTZ_R * HERTZ_D);
  double gx[256] = {0}, gy[256] = {0};
  const int nx = graded(cells, g_kappa, g_W, gx);
  const double h0 = gx[1];
  const int ny = nx; /* the same sequence downward */
  memcpy(gy, gx, sizeof(double) * (size_t)nx);
  const int cx = nx - 1, cy = ny - 1, cz = nx - 1;
  const int32_t nodes = nx * ny * nx;
  double* p = malloc(sizeof(double) * 3 * (size_t)nodes);
  int32_t* t = malloc(sizeof(int32_t) * 4 * 5 * (size_t)cx * cy * cz);
  for (int k = 0; k < nx; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        double* q = p + 3 * ((size_t)(k * ny + j) * nx + i);
        q[0] = gx[i];
        q[1] = -gy[ny - 1 - j]; /* y from -D up to 0: fine near the top */
        q[2] = gx[k];
      }
  int32_t ntet = 0;
  for (int k = 0; k < cz; ++k)
    for (int j = 0; j < cy; ++j)
      for (int i = 0; i < cx; ++i) {
        int32_t c[8];
        for (int m = 0; m < 8; ++m)
          c[m] = ((k + ((m >> 2) & 1)) * ny + (j + ((m >> 1) & 1))) * nx + (i + (m & 1));
        const int(*cut)[4] = ((i + j + k) % 2 == 0) ? cut_even : cut_odd;
        for (int e = 0; e < 5; ++e) {
          int32_t* o = t + 4 * (size_t)ntet++;
          for (int v = 0; v < 4; ++v) o[v] = c[cut[e][v]];
          if (det3(p + 3 * o[0], p + 3 * o[1], p + 3 * o[2], p + 3 * o[3]) < 0) {
            const int32_t s = o[2];
            o[2] = o[3];
            o[3] = s;
          }
        }
      }
  mica_world* w = direct_world(0);
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = HERTZ_E;
  bd.poisson_ratio = HERTZ_NU;
  bd.model = model;
  mica_body_id body;
  const double t0 = study_now_ms();
  if (mica_body_create(w, &bd, p, nodes, t, ntet, &body) != MICA_OK) {
    fprintf(stderr, "hertz: %s\n", mica_world_last_error(w));
    mica_world_destroy(w);
    free(p);
    free(t);
    return r;
  }
  /* Symmetry: x = 0 slides in its plane, z = 0 too; the base is fixed. */
  mica_lpc_id lx, lz, base;
  const double o[3] = {0, 0, 0}, nxp[3] = {1, 0, 0}, nzp[3] = {0, 0, 1}, bottom[3] = {0, -HERTZ_W, 0},
               up[3] = {0, 1, 0};
  int32_t n = 0;
  int32_t* sel = scene_select_plane(w, body, o, nxp, 1e-9, &n);
  mica_lpc_def plane = mica_lpc_def_default();
  plane.kind = MICA_LPC_PLANE;
  plane.direction[0][0] = 1;
  mica_add_lpc(w, body, sel, n, &plane, &lx);
  free(sel);
  sel = scene_select_plane(w, body, o, nzp, 1e-9, &n);
  plane.direction[0][0] = 0;
  plane.direction[0][2] = 1;
  mica_add_lpc(w, body, sel, n, &plane, &lz);
  free(sel);
  scene_fix_plane(w, body, bottom, up, 1e-9, NULL, &base);
  mica_tool_def td = mica_tool_def_default();
  td.radius = HERTZ_R;
  td.margin = 1e-4;
  td.position[1] = HERTZ_R + 1e-4;
  mica_tool_id tool;
  mica_tool_create(w, &td, &tool);
  const double q[4] = {1, 0, 0, 0};
  const int increments = 4, settle = 2, final_settle = 3;
  double f[3] = {0, 0, 0}, last3[3] = {0, 0, 0};
  r.ok = 1;
  for (int inc = 1; inc <= increments && r.ok; ++inc) {
    const double d = HERTZ_D * inc / increments;
    const double pos[3] = {0, HERTZ_R - d, 0};
    mica_tool_set_pose(w, tool, pos, q);
    const int steps = inc == increments ? settle + final_settle : settle;
    for (int s = 0; s < steps; ++s)
      if (mica_step(w, 1.0) < 0) {
        fprintf(stderr, "hertz h0 %.3g: %s\n", h0, mica_world_last_error(w));
        r.ok = 0;
        break;
      } else {
        mica_tool_get_force(w, tool, f, NULL, NULL);
        if (inc == increments && s >= steps - 3) last3[s - (steps - 3)] = 4 * f[1];
        if (g_trace) printf("  d %.4g step %d F %.6g (%.0f ms)\n", d, s, 4 * f[1], study_now_ms() - t0);
      }
    int32_t contacts = 0;
    mica_tool_get_force(w, tool, f, NULL, &contacts);
    const double hertz = 4.0 / 3.0 * HERTZ_E / (1 - HERTZ_NU * HERTZ_NU) * sqrt(HERTZ_R) * pow(d, 1.5);
    if (curve) fprintf(curve, "%.6g,%.6g,%.9g,%.9g,%d\n", h0, d, 4 * f[1], hertz, contacts);
  }
  r.ms = study_now_ms() - t0;
  r.h = h0;
  for (int i = 0; i + 1 < nx; ++i)
    if (gx[i] <= a && a < gx[i + 1]) r.h = gx[i + 1] - gx[i]; /* the cell size at the contact edge */
  /* The contact set still flickers between steps on coarse meshes (nodes and triangle points
   * entering and leaving): the force is the mean of the last 3 steps, its spread reported. */
  r.value = (last3[0] + last3[1] + last3[2]) / 3;
  r.spread = (fmax(last3[0], fmax(last3[1], last3[2])) - fmin(last3[0], fmin(last3[1], last3[2]))) / r.value;
  r.theory = 4.0 / 3.0 * HERTZ_E / (1 - HERTZ_NU * HERTZ_NU) * sqrt(HERTZ_R) * pow(HERTZ_D, 1.5);
  r.timoshenko = NAN;
  r.nodes = nodes;
  r.tets = ntet;
  mica_world_destroy(w);
  free(p);
  free(t);
  return r;
}

static const int32_t kModels[3] = {MICA_MODEL_LINEAR, MICA_MODEL_COROTATIONAL, MICA_MODEL_NEO_HOOKEAN};

static const char* model_name(int32_t model) {
  return model == MICA_MODEL_LINEAR ? "linear" : model == MICA_MODEL_NEO_HOOKEAN ? "neo-hookean" : "corotational";
}

static level_result beam_level(int n, int model) {
  level_result r;
  memset(&r, 0, sizeof r);
  const double L = 0.2, H = 0.02, E = 1e7, nu = 0.3, rho = 1000, g = 9.81;
  mica_world* w = direct_world(-g);
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = E;
  bd.poisson_ratio = nu;
  bd.density = rho;
  bd.model = model;
  const double lo[3] = {0, 0, 0}, hi[3] = {L, H, H};
  const int32_t cells[3] = {10 * n, n, n};
  mica_body_id body;
  const double t0 = study_now_ms();
  mica_body_create_box(w, &bd, lo, hi, cells, 6, &body);
  mica_body_get_counts(w, body, &r.nodes, &r.tets, NULL);
  mica_lpc_id clamp;
  const double o[3] = {0, 0, 0}, nx[3] = {1, 0, 0}, tip_p[3] = {L, 0, 0}, tip_n[3] = {-1, 0, 0};
  scene_fix_plane(w, body, o, nx, 1e-9, NULL, &clamp);
  int32_t ntip = 0;
  int32_t* tip = scene_select_plane(w, body, tip_p, tip_n, 1e-9, &ntip);
  double* x = malloc(sizeof(double) * 3 * (size_t)r.nodes);
  double* x0 = malloc(sizeof(double) * 3 * (size_t)r.nodes);
  mica_body_get_rest_positions(w, body, x0, r.nodes, NULL);
  double wtip = 0, last = -1;
  r.ok = 1;
  for (int s = 0; s < 30; ++s) {
    if (mica_step(w, 1.0) < 0) {
      r.ok = 0;
      break;
    }
    mica_body_get_positions(w, body, x, r.nodes, NULL);
    wtip = 0;
    for (int32_t k = 0; k < ntip; ++k) wtip += x0[3 * tip[k] + 2] - x[3 * tip[k] + 2];
    wtip /= ntip;
    if (s >= 2 && fabs(wtip - last) <= 1e-10 * fabs(wtip)) break;
    last = wtip;
  }
  r.ms = study_now_ms() - t0;
  const double I = H * H * H * H / 12.0, q = rho * g * H * H, G = E / (2 * (1 + nu));
  r.h = H / n;
  r.value = wtip;
  r.theory = q * L * L * L * L / (8 * E * I);
  r.timoshenko = r.theory + q * L * L / (2 * (5.0 / 6.0) * G * H * H);
  free(x);
  free(x0);
  free(tip);
  mica_world_destroy(w);
  return r;
}

#define UNIAXIAL_INCREMENTS 8 /* of 5 %: to 40 % */
#define UNIAXIAL_HOLD 6

/* The uniaxial compression of one model: a row of uniaxial.csv per increment. Returns the
 * largest |error| against the neo-Hookean closed form, NAN when a step failed. */
static double uniaxial_run(int32_t model, int32_t cells, FILE* csv) {
  mica_world* w = direct_world(0);
  uniaxial_scene_def def = uniaxial_scene_def_default();
  def.body.model = model;
  def.cells = cells;
  const double E = def.body.youngs_modulus, nu = def.body.poisson_ratio, h = 1.0;
  uniaxial_scene sc;
  if (uniaxial_scene_create(w, &def, &sc) != MICA_OK) {
    fprintf(stderr, "uniaxial: %s\n", mica_world_last_error(w));
    mica_world_destroy(w);
    return NAN;
  }
  double worst = 0;
  for (int inc = 1; inc <= UNIAXIAL_INCREMENTS; ++inc) {
    double cpu[1 + UNIAXIAL_HOLD];
    int32_t load_solves = 0, warned = 0;
    for (int k = 0; k <= UNIAXIAL_HOLD; ++k) {
      const double v[3] = {0, 0, k == 0 ? -0.05 * def.side / h : 0};
      mica_lpc_set_velocity(w, sc.plate, v);
      const double c0 = study_cpu_ms();
      const mica_status st = mica_step(w, h);
      cpu[k] = study_cpu_ms() - c0;
      if (st < 0) {
        fprintf(stderr, "uniaxial %s, increment %d: %s\n", model_name(model), inc, mica_world_last_error(w));
        mica_world_destroy(w);
        return NAN;
      }
      warned += st == MICA_WARN_NOT_CONVERGED;
      if (k == 0) {
        mica_world_stats stats;
        memset(&stats, 0, sizeof stats);
        stats.struct_size = sizeof stats;
        mica_world_get_stats(w, &stats);
        load_solves = stats.solves;
      }
    }
    const double load_cpu = cpu[0];
    const double median_cpu = study_quantile(cpu, 1 + UNIAXIAL_HOLD, 0.5);
    double s = 0, lateral = 0, got = 0, t_nh = 0, t_hooke = 0;
    uniaxial_scene_measure(w, &sc, &s, &lateral, &got);
    const double nh = uniaxial_neo_hookean_nominal_stress(E, nu, s, &t_nh);
    const double hooke = uniaxial_hooke_nominal_stress(E, nu, s, &t_hooke);
    const double err = (got - nh) / nh, err_hooke = (got - hooke) / hooke;
    worst = fmax(worst, fabs(err));
    fprintf(csv, "%s,%d,%d,%d,%.6g,%.9g,%.9g,%.9g,%.6g,%.9g,%.6g,%.9g,%.9g,%.9g,%d,%.4f,%.4f,%d\n", model_name(model),
            cells, sc.nodes, sc.tets, 1 - s, s, got, nh, err, hooke, err_hooke, lateral, t_nh, t_hooke, load_solves,
            load_cpu, median_cpu, warned);
    printf("%-8s %-12s %6.0f%% %12.2f %12.2f %+9.2f%% %12.2f %+9.2f%% %9.5f %9.5f %7d %9.2f %9.2f%s\n", "uniaxial",
           model_name(model), 100 * (1 - s), got, nh, 100 * err, hooke, 100 * err_hooke, lateral, t_nh, load_solves,
           load_cpu, median_cpu, warned ? "  (a step did not converge)" : "");
    fflush(stdout);
  }
  mica_world_destroy(w);
  return worst;
}

static const char kUsage[] =
    "usage: study_anchors <out-dir> [quick]\n"
    "Mesh convergence toward the analytic anchors: Hertz (a sphere indenting a deep block) and\n"
    "Euler-Bernoulli (a cantilever under its own weight; linear, co-rotational and neo-Hookean\n"
    "bodies), and uniaxial compression of a cube to 40 % against the neo-Hookean closed form (every\n"
    "model), MICA_SOLVER_DIRECT. Writes <out-dir>/anchors.csv, <out-dir>/hertz_curve.csv and\n"
    "<out-dir>/uniaxial.csv.\n"
    "  out-dir  where the CSV files go (made if missing)\n"
    "  quick    the coarser meshes only (a smoke test)\n"
    "  --help   this text\n";

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  if (argc < 2) {
    fprintf(stderr, "usage: study_anchors <out-dir> [quick]\n");
    return 2;
  }
  const int quick = argc > 2 && strcmp(argv[2], "quick") == 0;
  if (argc > 5 && strcmp(argv[2], "hertz") == 0) { /* experiments: hertz <cells> <kappa> <W> */
    int cells = 0;
    if (!cli_int(argv[0], "cells", argv[3], 1, 64, &cells) || !cli_double(argv[0], "kappa", argv[4], 0.01, 20, &g_kappa) ||
        !cli_double(argv[0], "W", argv[5], 1e-4, 1, &g_W))
      return 2;
    g_trace = 1;
    const level_result r = hertz_level(cells, MICA_MODEL_LINEAR, stdout);
    printf("h0 %.4g: %d nodes %d tets F %.6g Hertz %.6g ratio %.4f, %.0f ms\n", r.h, r.nodes, r.tets, r.value,
           r.theory, r.value / r.theory, r.ms);
    return 0;
  }
  if (!cli_make_folder(argv[0], argv[1])) return 1;
  char path[1024], machine[256];
  study_machine(machine, sizeof machine);
  snprintf(path, sizeof path, "%s/anchors.csv", argv[1]);
  FILE* csv = fopen(path, "w");
  snprintf(path, sizeof path, "%s/hertz_curve.csv", argv[1]);
  FILE* curve = fopen(path, "w");
  if (!csv || !curve) {
    fprintf(stderr, "cannot write into %s\n", argv[1]);
    return 1;
  }
  fprintf(csv, "# study_anchors: %s; libmica %d\n", machine, mica_version());
  fprintf(csv, "test,model,h_m,nodes,tets,fem,theory,rel_error,timoshenko,rel_error_timoshenko,ms,spread\n");
  fprintf(curve, "h0_m,depth_m,force_N,hertz_N,contacts\n");
  const double a = sqrt(HERTZ_R * HERTZ_D);
  const int divisors[] = {8, 12, 16, 20, 24};
  const int beams[] = {1, 2, 3, 4, 6, 8};
  const int nh = quick ? 2 : 5, nbm = quick ? 3 : 6, uniaxial_cells = quick ? 4 : 8;
  /* progress weights: roughly the cost of each level */
  double total = 0, done = 0;
  for (int k = 0; k < nh + 2; ++k) total += pow(divisors[k < nh ? k : nh - 1] / 8.0, 4);
  for (int k = 0; k < nbm; ++k) total += 3 * 0.2 * pow(beams[k], 3);
  total += 3 * pow(uniaxial_cells / 8.0, 3);
  printf("# Hertz: sphere R = %.3f m to d = %.4f m (a = %.4f m) on a graded quarter block; E = %.0f Pa, nu = %.2f\n",
         HERTZ_R, HERTZ_D, a, HERTZ_E, HERTZ_NU);
  printf("%-6s %-12s %10s %8s %8s %12s %12s %10s %9s\n", "test", "model", "h (m)", "nodes", "tets", "FEM", "theory",
         "rel err", "ms");
  /* The linear body on every level; the co-rotational and neo-Hookean bodies on the finest, where
   * at this small indentation (d = 0.22 a) the three models should agree. */
  for (int k = 0; k < nh + 2; ++k) {
    const int level = k < nh ? k : nh - 1;
    const int32_t model = k < nh ? MICA_MODEL_LINEAR : k == nh ? MICA_MODEL_COROTATIONAL : MICA_MODEL_NEO_HOOKEAN;
    const level_result r = hertz_level(divisors[level], model, k < nh ? curve : NULL);
    fflush(curve);
    const double err = (r.value - r.theory) / r.theory;
    fprintf(csv, "hertz,%s,%.6g,%d,%d,%.9g,%.9g,%.6g,,,%.1f,%.4g\n", model_name(model), r.h, r.nodes, r.tets, r.value,
            r.theory, r.ok ? err : NAN, r.ms, r.spread);
    printf("%-6s %-12s %10.3e %8d %8d %12.5g %12.5g %10.4f %9.0f  (last 3 steps spread %.1f%%)\n", "hertz",
           model_name(model), r.h, r.nodes, r.tets, r.value, r.theory, err, r.ms, 100 * r.spread);
    fflush(stdout);
    done += pow(divisors[level] / 8.0, 4);
    study_progress(done, total);
  }
  for (int m = 0; m < 3; ++m)
    for (int k = 0; k < nbm; ++k) {
      const int32_t model = kModels[m];
      const level_result r = beam_level(beams[k], model);
      const double err = (r.value - r.theory) / r.theory, errt = (r.value - r.timoshenko) / r.timoshenko;
      fprintf(csv, "cantilever,%s,%.6g,%d,%d,%.9g,%.9g,%.6g,%.9g,%.6g,%.1f,\n", model_name(model), r.h, r.nodes,
              r.tets, r.value, r.theory, r.ok ? err : NAN, r.timoshenko, r.ok ? errt : NAN, r.ms);
      printf("%-6s %-12s %10.3e %8d %8d %12.5g %12.5g %10.4f %9.0f  (Timoshenko %.5g: %+.4f)\n", "beam",
             model_name(model), r.h, r.nodes, r.tets, r.value, r.theory, err, r.ms, r.timoshenko, errt);
      fflush(stdout);
      done += 0.2 * pow(beams[k], 3);
      study_progress(done, total);
    }
  fclose(csv);
  fclose(curve);
  snprintf(path, sizeof path, "%s/uniaxial.csv", argv[1]);
  FILE* uni = fopen(path, "w");
  if (!uni) {
    fprintf(stderr, "cannot write into %s\n", argv[1]);
    return 1;
  }
  fprintf(uni, "# study_anchors: %s; libmica %d\n", machine, mica_version());
  fprintf(uni, "model,cells,nodes,tets,strain,stretch,nominal_fem_Pa,nominal_neo_hookean_Pa,rel_error,nominal_hooke_Pa,"
               "rel_error_hooke,lateral_fem,lateral_neo_hookean,lateral_hooke,load_solves,load_cpu_ms,cpu_ms_median,"
               "steps_not_converged\n");
  printf("# uniaxial compression: %d^3 cells x 6 tets, frictionless ends, 5 %% a step of 1 s, held 6 steps\n",
         uniaxial_cells);
  printf("%-8s %-12s %7s %12s %12s %10s %12s %10s %9s %9s %7s %9s %9s\n", "test", "model", "strain", "P FEM", "P neoH",
         "err", "P Hooke", "err", "lateral", "neoH", "solves", "load cpu", "med cpu");
  int failed = 0;
  for (int m = 0; m < 3; ++m) {
    failed += isnan(uniaxial_run(kModels[m], uniaxial_cells, uni));
    fflush(uni);
    done += pow(uniaxial_cells / 8.0, 3);
    study_progress(done, total);
  }
  fclose(uni);
  return failed ? 1 : 0;
}
