/* SPDX-License-Identifier: Apache-2.0 */
/* Two hands on one soft block, each device on its own 1 kHz servo thread (mica_device_start), the
 * simulation stepping at 100 Hz on the main thread. Hand 1, a simulated virtual hand, drives a
 * grasp (mica_device_def.lpc) on the top face and pulls it up and sideways; hand 2, another
 * virtual hand, drives a sphere tool pressing the top face elsewhere. Prints each hand's rendered
 * force (mica_device_get_stats), writes two_hands.csv, and checks:
 * - the momentum balance: the forces on everything holding the block (tool, grasp, the fixed
 *   base) equal its weight less its inertia and mass damping, to 1e-6 of the forces in play, in
 *   the last step (both hands still) and in every step, with the sphere apart (the block
 *   accelerating under the grasp) and moving in contact;
 * - each hand's rendered force points the right way (hand 1 pulled back down toward the tissue,
 *   hand 2 pushed up) and matches the force of the last step.
 * Exits 1 when a check fails.
 *
 * usage: two_hands [output-folder] [seconds]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include <mica/mica.h>
#include <mica/mica_device.h>

#include "box_scene.h"
#include "wall_clock.h"
#include "cli.h"

#ifndef SIM_HZ
#define SIM_HZ 100
#endif
#define MAX_ROWS 100000

/* The grasp's centre on the top face (y = 0) and the sphere's point of first touch. */
static const double kGrasp[3] = {-0.025, 0, 0};
static const double kPress[3] = {0.025, 0, 0};
static const double kSphereRadius = 0.015;

static double ramp(double t) { return t < 1.0 ? t : 1.0; } /* 0 to 1 over the first second, then held */

/* Hand 1 aims 8 mm up and 4 mm toward -x from where it grasped (the block pulls it back). */
static void pull(double t, double p[3], void* user) {
  (void)user;
  p[0] = kGrasp[0] - 0.004 * ramp(t);
  p[1] = kGrasp[1] + 0.008 * ramp(t);
  p[2] = kGrasp[2];
}

/* Hand 2 aims its sphere 8 mm into the top face (the block pushes it back). */
static void press(double t, double p[3], void* user) {
  (void)user;
  p[0] = kPress[0];
  p[1] = kPress[1] + kSphereRadius + 0.001 - 0.009 * ramp(t);
  p[2] = kPress[2];
}

#define CHECK(call)                                                                                   \
  do {                                                                                                \
    mica_status s_ = (call);                                                                          \
    if (s_ < 0) {                                                                                     \
      fprintf(stderr, "%s: %s\n  %s\n", #call, mica_status_string(s_), mica_world_last_error(world)); \
      return 1;                                                                                       \
    }                                                                                                 \
  } while (0)

static const char kUsage[] =
    "usage: two_hands [output-folder] [seconds]\n"
    "Two simulated hands on one soft block, each device on its own 1 kHz servo thread: hand 1 drives\n"
    "a grasp and pulls the top face up and sideways, hand 2 drives a sphere pressing it. Steps the\n"
    "world at 100 Hz, prints each hand's rendered force, writes two_hands.csv (time, each hand's\n"
    "rendered force, the step's grasp and tool forces) and checks the block's force balance and the\n"
    "direction and size of each hand's force; exit status 1 when a check fails.\n"
    "  output-folder  where the CSV goes (made if missing; default .)\n"
    "  seconds        how long the hands act (default 3, at least 1.5; they stop moving at 1 s)\n"
    "  --help         this text\n";

typedef struct {
  double t, hand1[3], hand2[3], grasp[3], tool[3];
} row;

static row rows[MAX_ROWS];

static void rendered(const mica_world* world, mica_device_id d, double out[3]) {
  mica_device_stats st = {.struct_size = sizeof st};
  mica_device_get_stats(world, d, &st);
  for (int k = 0; k < 3; ++k) out[k] = st.last_force[k];
}

static double norm3(const double v[3]) { return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/* One step's momentum balance: the forces on the holders (tool force, grasp and base reactions:
 * each the force the block puts on it) equal the block's weight less its inertia and its mass
 * damping, sum m g - sum m (v1 - v0) / h - alpha sum m v1; `residual` is what is left over. */
typedef struct {
  double tool[3], grasp[3], base[3], weight[3], inertia[3], damping[3], residual[3];
  double mass, scale; /* kg; N, the sum of the terms' magnitudes */
} balance;

typedef struct {
  mica_world* world;
  mica_body_id body;
  mica_tool_id tool;
  mica_lpc_id grasp, base;
  double gravity[3], alpha;
  int32_t nodes;
  double *m, *v0, *v1;
} balance_scene;

static mica_status step_and_balance(balance_scene* s, double h, balance* b) {
  mica_status st = mica_body_get_velocities(s->world, s->body, s->v0, s->nodes, NULL);
  if (st < 0) return st;
  const mica_status stepped = mica_step(s->world, h);
  if (stepped < 0) return stepped;
  if ((st = mica_body_get_velocities(s->world, s->body, s->v1, s->nodes, NULL)) < 0 ||
      (st = mica_tool_get_force(s->world, s->tool, b->tool, NULL, NULL)) < 0 ||
      (st = mica_lpc_get_reaction(s->world, s->grasp, b->grasp)) < 0 ||
      (st = mica_lpc_get_reaction(s->world, s->base, b->base)) < 0)
    return st;
  b->mass = 0;
  for (int k = 0; k < 3; ++k) b->weight[k] = b->inertia[k] = b->damping[k] = 0;
  for (int32_t i = 0; i < s->nodes; ++i) {
    b->mass += s->m[i];
    for (int k = 0; k < 3; ++k) {
      b->weight[k] += s->m[i] * s->gravity[k];
      b->inertia[k] += s->m[i] * (s->v1[3 * i + k] - s->v0[3 * i + k]) / h;
      b->damping[k] += s->alpha * s->m[i] * s->v1[3 * i + k];
    }
  }
  for (int k = 0; k < 3; ++k)
    b->residual[k] = b->tool[k] + b->grasp[k] + b->base[k] - b->weight[k] + b->inertia[k] + b->damping[k];
  b->scale = norm3(b->tool) + norm3(b->grasp) + norm3(b->base) + norm3(b->weight) + norm3(b->inertia) +
             norm3(b->damping);
  return stepped;
}

int main(int argc, char** argv) {
  const int cli = cli_check(argc, argv, kUsage, NULL);
  if (cli >= 0) return cli;
  const char* out_dir = argc > 1 ? argv[1] : ".";
  double seconds = 3; /* at least 1.5: the hands reach their targets at 1 s, then settle */
  if (argc > 2 && !cli_double(argv[0], "seconds", argv[2], 1.5, 86400, &seconds)) return 2;
  if (!cli_make_folder(argv[0], out_dir)) return 1;
  mica_world* world = NULL;
  mica_world_def wd = mica_world_def_default(); /* MICA, factored sweep, relative tolerance 1e-8 */
  if (mica_world_create(&wd, &world) != MICA_OK) {
    fprintf(stderr, "%s\n", mica_world_last_error(NULL));
    return 1;
  }
  /* The soft block (scenes/box_scene.h): 10 cm wide, its top face at y = 0, fixed at its bottom
   * face; the sphere of hand 2 just above the top face. */
  box_scene_def def = box_scene_block_def();
  def.cells[0] = def.cells[1] = def.cells[2] = 4; /* 25 mm cells: a step in a few ms */
  def.body.youngs_modulus = 1e4;
  def.body.poisson_ratio = 0.4;
  def.body.rayleigh_alpha = 2;
  def.tool_radius = kSphereRadius;
  press(0, def.tool_position, NULL);
  box_scene scene;
  CHECK(box_scene_create(world, &def, &scene));
  /* The block settles under its own weight first (1.5 s), so that the grasp holds only what the
   * hand pulls. */
  for (int k = 0; k < 150; ++k) CHECK(mica_step(world, 0.01));
  /* Hand 1's grasp: the nodes within 26 mm of its centre: the node there and its neighbours. */
  mica_lpc_id grasp;
  CHECK(mica_lpc_grab(world, scene.body, kGrasp, 0.026, MICA_NULL_ID, &grasp));

  mica_device_def hand = mica_device_def_default();
  hand.backend = MICA_DEVICE_SIMULATED;
  hand.simulated_kind = MICA_SIMULATED_HAND;
  hand.hand_stiffness = 400; /* N/m: the arm's pull toward where the hand aims */
  hand.hand_damping = 15;
  mica_device_def hand1 = hand, hand2 = hand;
  hand1.lpc = grasp; /* the grasp's handle follows hand 1 */
  hand1.trajectory = pull;
  hand2.tool = scene.tool; /* the sphere follows hand 2 */
  hand2.trajectory = press;
  mica_device_id d1, d2;
  CHECK(mica_device_create(world, &hand1, &d1));
  CHECK(mica_device_create(world, &hand2, &d2));
  CHECK(mica_device_start(world, d1)); /* two servo threads, one per device */
  CHECK(mica_device_start(world, d2));

  /* What the balance of each step needs. */
  balance_scene bs = {world, scene.body, scene.tool, grasp, scene.base, {0, 0, 0}, def.body.rayleigh_alpha, 0,
                      NULL, NULL, NULL};
  for (int k = 0; k < 3; ++k) bs.gravity[k] = wd.gravity[k];
  CHECK(mica_body_get_node_masses(world, scene.body, NULL, 0, &bs.nodes));
  bs.m = malloc(sizeof(double) * (size_t)bs.nodes);
  bs.v0 = malloc(sizeof(double) * 3 * (size_t)bs.nodes);
  bs.v1 = malloc(sizeof(double) * 3 * (size_t)bs.nodes);
  if (!bs.m || !bs.v0 || !bs.v1) return 1;
  CHECK(mica_body_get_node_masses(world, scene.body, bs.m, bs.nodes, NULL));
  /* The solver stops when the contact impulses change by less than 1e-8 of themselves in a sweep:
   * the velocities answer the impulses of the sweep before the last, so the free nodes are out of
   * balance by about that change. 1e-6 of the forces in play leaves room for 100 such sweeps'
   * worth, and is still far below any term left out (the grasp alone is ~2 N). */
  const double relative_tolerance = 1e-6;
  double worst[2] = {0, 0}, worst_t[2] = {0, 0}; /* the sphere apart, touching */
  balance b;

  /* Simulated time keeps up with the hands' (real) time: a step that fell behind (a loaded
   * machine, a sanitizer) is followed by a longer one, up to 50 ms. Behind them, the hands would
   * move faster than the tissue's own time and the two couplings lose their stability. */
  const double h_nominal = 1.0 / SIM_HZ, h_max = 0.05;
  const double start = now_s();
  double t = 0, longest = h_nominal;
  int n = 0;
  while (n < MAX_ROWS && t < seconds) {
    const double behind = now_s() - start - t;
    const double h = behind > h_nominal ? (behind < h_max ? behind : h_max) : h_nominal;
    if (h > longest) longest = h;
    CHECK(step_and_balance(&bs, h, &b));
    t += h;
    /* Apart, by whether the sphere touches (see the note at the end). */
    const int touching = norm3(b.tool) > 0;
    if (norm3(b.residual) / b.scale > worst[touching]) {
      worst[touching] = norm3(b.residual) / b.scale;
      worst_t[touching] = t;
    }
    row* r = &rows[n++];
    r->t = t;
    rendered(world, d1, r->hand1);
    rendered(world, d2, r->hand2);
    CHECK(mica_lpc_get_reaction(world, grasp, r->grasp));
    CHECK(mica_tool_get_force(world, scene.tool, r->tool, NULL, NULL));
    if (n % 25 == 0)
      printf("t %.2f s  hand 1 (grasp) renders (%+.3f, %+.3f) N, grasp %+.3f N;  hand 2 (sphere) renders %+.3f N, "
             "tool %+.3f N (y)\n",
             r->t, r->hand1[0], r->hand1[1], r->grasp[1], r->hand2[1], r->tool[1]);
    sleep_until(start + t);
  }
  const double elapsed = now_s() - start;
  mica_device_stats s1 = {.struct_size = sizeof s1}, s2 = {.struct_size = sizeof s2};
  CHECK(mica_device_get_stats(world, d1, &s1));
  CHECK(mica_device_get_stats(world, d2, &s2));
  printf("%d steps (%.1f s simulated, the longest step %.0f ms) in %.2f s; servo rates %.0f and %.0f Hz; device "
         "failures %lld and %lld\n",
         n, t, 1e3 * longest, elapsed, s1.rate_hz,
         s2.rate_hz, (long long)s1.failures, (long long)s2.failures);
  CHECK(mica_device_stop(world, d1));
  CHECK(mica_device_stop(world, d2));
  int failed = 0;

  /* Each hand's force: direction, and size against the last step's force (the hands are nearly
   * still by now: the local model adds little, the filter has settled). */
  const row* last = &rows[n - 1];
  printf("hand 1: renders (%+.4f, %+.4f, %+.4f) N, the grasp's reaction (%+.4f, %+.4f, %+.4f) N\n", last->hand1[0],
         last->hand1[1], last->hand1[2], last->grasp[0], last->grasp[1], last->grasp[2]);
  printf("hand 2: renders (%+.4f, %+.4f, %+.4f) N, the tool force (%+.4f, %+.4f, %+.4f) N\n", last->hand2[0],
         last->hand2[1], last->hand2[2], last->tool[0], last->tool[1], last->tool[2]);
  /* Pulled up and toward -x, the grasped tissue pulls the hand down and toward +x. */
  if (!(last->hand1[1] < -0.1 && last->hand1[0] > 0)) {
    fprintf(stderr, "FAIL: hand 1 is not pulled back toward the tissue (down and toward +x)\n");
    failed = 1;
  }
  if (!(last->hand2[1] > 0.1)) {
    fprintf(stderr, "FAIL: hand 2 is not pushed up by the tissue\n");
    failed = 1;
  }
  const double* sim[2] = {last->grasp, last->tool};
  const double* out[2] = {last->hand1, last->hand2};
  for (int k = 0; k < 2; ++k) {
    const double diff[3] = {out[k][0] - sim[k][0], out[k][1] - sim[k][1], out[k][2] - sim[k][2]};
    /* 10% of the force plus 20 mN: what the hand's drift over one 10 ms step moves the model, and
     * the filter's lag behind a force still settling. */
    if (!(norm3(diff) <= 0.1 * norm3(sim[k]) + 0.02)) {
      fprintf(stderr, "FAIL: hand %d renders %.4f N away from the step's force (%.4f N)\n", k + 1, norm3(diff),
              norm3(sim[k]));
      failed = 1;
    }
  }

  /* The balance of one more step (the hands still), and the worst of every step while they
   * moved: momentum, not statics, so it holds while the block accelerates too. */
  CHECK(step_and_balance(&bs, h_nominal, &b));
  mica_world_stats ws = {.struct_size = sizeof ws};
  CHECK(mica_world_get_stats(world, &ws));
  printf("balance of the last step (N):\n");
  printf("  tool force        %+.6f %+.6f %+.6f\n", b.tool[0], b.tool[1], b.tool[2]);
  printf("  grasp reaction    %+.6f %+.6f %+.6f\n", b.grasp[0], b.grasp[1], b.grasp[2]);
  printf("  base reaction     %+.6f %+.6f %+.6f\n", b.base[0], b.base[1], b.base[2]);
  printf("  - weight (%.4f kg) %+.6f %+.6f %+.6f\n", b.mass, -b.weight[0], -b.weight[1], -b.weight[2]);
  printf("  + inertia         %+.6f %+.6f %+.6f\n", b.inertia[0], b.inertia[1], b.inertia[2]);
  printf("  + mass damping    %+.6f %+.6f %+.6f\n", b.damping[0], b.damping[1], b.damping[2]);
  printf("  = residual        %+.3e %+.3e %+.3e  (|r| %.3e N, tolerance %.3e N; solver %d iterations, %s)\n",
         b.residual[0], b.residual[1], b.residual[2], norm3(b.residual), relative_tolerance * b.scale,
         ws.solver_iterations, ws.converged ? "converged" : "NOT converged");
  printf("worst step while the hands moved: %.3e of the forces in play with the sphere apart (t %.2f s), %.3e "
         "with it touching (t %.2f s); tolerance %.0e\n",
         worst[0], worst_t[0], worst[1], worst_t[1], relative_tolerance);
  /* Checked: the last step (both hands still, both touching) and every step, the sphere apart
   * (the grasp pulling, the block accelerating) or moving in contact (the tool force carries the
   * contact-curvature term a rounded tool adds to the step's matrix: docs/method.md). */
  if (!(norm3(b.residual) <= relative_tolerance * b.scale) || !ws.converged || !(worst[0] <= relative_tolerance) ||
      !(worst[1] <= relative_tolerance)) {
    fprintf(stderr, "FAIL: the forces on the block do not balance\n");
    failed = 1;
  }
  free(bs.m);
  free(bs.v0);
  free(bs.v1);

  char path[1024];
  snprintf(path, sizeof path, "%s/two_hands.csv", out_dir);
  FILE* csv = fopen(path, "w");
  if (!csv) {
    fprintf(stderr, "cannot write %s\n", path);
    return 1;
  }
  fprintf(csv, "t_s,hand1_fx_N,hand1_fy_N,hand1_fz_N,hand2_fx_N,hand2_fy_N,hand2_fz_N,grasp_fx_N,grasp_fy_N,"
               "grasp_fz_N,tool_fx_N,tool_fy_N,tool_fz_N\n");
  for (int i = 0; i < n; ++i) {
    const row* r = &rows[i];
    fprintf(csv, "%.3f", r->t);
    const double* cols[4] = {r->hand1, r->hand2, r->grasp, r->tool};
    for (int c = 0; c < 4; ++c) fprintf(csv, ",%.9g,%.9g,%.9g", cols[c][0], cols[c][1], cols[c][2]);
    fprintf(csv, "\n");
  }
  fclose(csv);
  printf("forces written to %s\n", path);
  CHECK(mica_device_destroy(world, d1));
  CHECK(mica_device_destroy(world, d2));
  mica_world_destroy(world);
  if (failed) return 1;
  printf("two hands: balanced and rendered\n");
  return 0;
}
