/* A program as a user built it against an earlier libmica header, run against the current
 * library (drop-in upgrade within SONAME 0). The build compiles this file once per header set
 * in tests/abi_fixtures/<version>/mica/ (the public headers as released) and links each
 * against the libmica.so.0 of the build; ctest runs them (label "abi").
 *
 * Only what every released header has (0.2.0 onwards) is used: worlds, bodies, projection
 * constraints, tools and devices created from their defs filled by the header's own inline
 * *_default() functions, a few steps with a device pressing a tool into a block, and the
 * forces read back. The cases run in order (each builds on the last); the first failure stops
 * the run with the library's message. */
#include <mica/mica.h>
#include <mica/mica_device.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#ifndef FIXTURE_VERSION
#error "compile with -DFIXTURE_VERSION=<MICA_VERSION_NUMBER of the fixture header>"
#endif
#if MICA_VERSION_NUMBER != FIXTURE_VERSION
#error "this consumer is not compiled against the fixture header it is meant for"
#endif

typedef struct scene {
  mica_world* world;
  mica_body_id body;
  mica_lpc_id clamp;
  mica_tool_id tool;
  mica_device_id device;
  int log_messages;
  double force[3];
  int32_t contacts;
} scene;

static const double kDt = 0.01;
static const int kSteps = 20;
static const int kPollsPerStep = 10; /* the 1 kHz servo loop beside 100 Hz steps */

/* A failed call: say which, with the library's message, and fail the case. */
static int failed(const scene* s, const char* what, mica_status status) {
  printf("  %s -> %d %s\n  last error: %s\n", what, (int)status, mica_status_string(status),
          mica_world_last_error(s ? s->world : NULL));
  return 1;
}
#define CALL(s, expr)                                       \
  do {                                                      \
    mica_status status_ = (expr);                           \
    if (status_ < 0) return failed((s), #expr, status_);    \
  } while (0)
#define EXPECT(cond, ...)                                   \
  do {                                                      \
    if (!(cond)) {                                          \
      printf("  expected %s: ", #cond);            \
      printf(__VA_ARGS__);                         \
      printf("\n");                                \
      return 1;                                             \
    }                                                       \
  } while (0)

static void on_log(int32_t level, const char* message, void* user) {
  (void)level;
  (void)message;
  ((scene*)user)->log_messages++;
}

/* The device's stylus (its clock advances 1 ms a poll): from the block's top surface
 * downward at 5 cm/s. */
static void press(double t, double position[3], void* user) {
  (void)user;
  position[0] = 0.0;
  position[1] = 0.07 - 0.05 * t;
  position[2] = 0.0;
}

static int case_version(scene* s) {
  (void)s;
  const int32_t lib = mica_version();
  EXPECT(lib / 10000 == MICA_VERSION_MAJOR, "library %d, header %d", (int)lib, MICA_VERSION_NUMBER);
  EXPECT(lib >= MICA_VERSION_NUMBER, "library %d older than the header %d", (int)lib, MICA_VERSION_NUMBER);
  return 0;
}

static int case_refusals(scene* s) {
  /* A def smaller than any release, and a header of another major version, are refused. */
  mica_world_def def = mica_world_def_default();
  mica_world* world = NULL;
  def.struct_size = 8;
  EXPECT(mica_world_create(&def, &world) == MICA_ERR_STRUCT_SIZE && world == NULL, "struct_size 8 refused");
  def = mica_world_def_default();
  def.header_version = 10000;
  EXPECT(mica_world_create(&def, &world) == MICA_ERR_VERSION_MISMATCH && world == NULL, "header 1.0 refused");
  (void)s;
  return 0;
}

static int case_world(scene* s) {
  mica_world_def def = mica_world_def_default();
  EXPECT(def.struct_size == sizeof def, "struct_size %u, sizeof %u (the library said: %s)", (unsigned)def.struct_size,
         (unsigned)sizeof def, mica_world_last_error(NULL));
  EXPECT(def.header_version == MICA_VERSION_NUMBER, "header_version %u", (unsigned)def.header_version);
  EXPECT(def.gravity[1] == -9.81 && def.max_iterations == 200, "the defaults (gravity %g, cap %d)",
         def.gravity[1], (int)def.max_iterations);
  def.solver = MICA_SOLVER_MICA;
  def.max_iterations = 500;
  def.tolerance = 1e-6;
  def.log = on_log;
  def.log_user = s;
  CALL(NULL, mica_world_create(&def, &s->world));
  EXPECT(s->world != NULL, "a world");
  return 0;
}

static int case_body(scene* s) {
  const double lo[3] = {-0.05, 0.0, -0.05}, hi[3] = {0.05, 0.05, 0.05};
  const int32_t cells[3] = {4, 2, 4};
  mica_body_def def = mica_body_def_default();
  int32_t nodes = 0, tets = 0, triangles = 0;
  EXPECT(def.struct_size == sizeof def && def.youngs_modulus == 1e4, "the defaults");
  def.youngs_modulus = 3e4;
  def.poisson_ratio = 0.4;
  CALL(s, mica_body_create_box(s->world, &def, lo, hi, cells, 5, &s->body));
  CALL(s, mica_body_get_counts(s->world, s->body, &nodes, &tets, &triangles));
  EXPECT(nodes == 5 * 3 * 5 && tets == 4 * 2 * 4 * 5, "%d nodes, %d tets", (int)nodes, (int)tets);
  return 0;
}

static int case_lpc(scene* s) {
  const double point[3] = {0.0, 0.0, 0.0}, normal[3] = {0.0, 1.0, 0.0};
  int32_t bottom[64];
  int32_t count = 0;
  mica_lpc_def def = mica_lpc_def_default();
  EXPECT(def.struct_size == sizeof def && def.kind == MICA_LPC_FIXED, "the defaults");
  CALL(s, mica_body_select_nodes_by_plane(s->world, s->body, point, normal, 1e-9, 1, bottom, 64, &count));
  EXPECT(count == 25, "%d nodes on the bottom face", (int)count);
  CALL(s, mica_add_lpc(s->world, s->body, bottom, count, &def, &s->clamp));
  return 0;
}

static int case_tool(scene* s) {
  mica_tool_def def = mica_tool_def_default();
  EXPECT(def.struct_size == sizeof def && def.shape == MICA_TOOL_SPHERE && def.radius == 0.01, "the defaults");
  def.radius = 0.02;
  def.position[1] = 0.07;
  CALL(s, mica_tool_create(s->world, &def, &s->tool));
  return 0;
}

static int case_device(scene* s) {
  mica_device_def def = mica_device_def_default();
  mica_device_info info;
  EXPECT(def.struct_size == sizeof def && def.backend == MICA_DEVICE_NULL && def.scale == 1.0, "the defaults");
  def.backend = MICA_DEVICE_SIMULATED;
  def.simulated_kind = MICA_SIMULATED_TRAJECTORY;
  def.trajectory = press;
  def.tool = s->tool;
  CALL(s, mica_device_create(s->world, &def, &s->device));
  memset(&info, 0, sizeof info);
  info.struct_size = sizeof info;
  CALL(s, mica_device_get_info(s->world, s->device, &info));
  EXPECT(info.max_force > 0, "device max force %g N", info.max_force);
  return 0;
}

static int case_steps(scene* s) {
  for (int k = 0; k < kSteps; ++k) {
    double servo_force[3];
    for (int j = 0; j < kPollsPerStep; ++j) CALL(s, mica_device_poll(s->world, s->device, NULL, servo_force));
    CALL(s, mica_step(s->world, kDt));
  }
  CALL(s, mica_tool_get_force(s->world, s->tool, s->force, NULL, &s->contacts));
  EXPECT(s->contacts > 0, "contacts under the pressed tool (%d)", (int)s->contacts);
  EXPECT(s->force[1] > 0.01 && s->force[1] < 100.0, "the block pushes the tool up: force (%g, %g, %g) N",
         s->force[0], s->force[1], s->force[2]);
  return 0;
}

static int case_read_back(scene* s) {
  double reaction[3], position[3], orientation[4], kinetic, elastic, potential;
  mica_world_stats stats;
  mica_device_stats device_stats;
  CALL(s, mica_lpc_get_reaction(s->world, s->clamp, reaction));
  EXPECT(isfinite(reaction[1]) && reaction[1] < 0, "the clamp holds the block down: reaction y %g N", reaction[1]);
  CALL(s, mica_tool_get_pose(s->world, s->tool, position, orientation));
  EXPECT(position[1] > 0.055 && position[1] < 0.065, "the tool follows the device down: y %g m", position[1]);
  CALL(s, mica_body_get_energy(s->world, s->body, &kinetic, &elastic, &potential));
  EXPECT(elastic > 0, "the pressed block stores energy (%g J)", elastic);
  memset(&stats, 0, sizeof stats);
  stats.struct_size = sizeof stats;
  CALL(s, mica_world_get_stats(s->world, &stats));
  EXPECT(stats.step_count == kSteps, "%lld steps", (long long)stats.step_count);
  memset(&device_stats, 0, sizeof device_stats);
  device_stats.struct_size = sizeof device_stats;
  CALL(s, mica_device_get_stats(s->world, s->device, &device_stats));
  EXPECT(device_stats.polls == kSteps * kPollsPerStep, "%lld polls", (long long)device_stats.polls);
  return 0;
}

static int case_teardown(scene* s) {
  CALL(s, mica_device_destroy(s->world, s->device));
  CALL(s, mica_tool_destroy(s->world, s->tool));
  CALL(s, mica_lpc_remove(s->world, s->clamp));
  CALL(s, mica_body_destroy(s->world, s->body));
  EXPECT(mica_body_destroy(s->world, s->body) == MICA_ERR_STALE_ID, "a destroyed body's id is stale");
  mica_world_destroy(s->world);
  s->world = NULL;
  return 0;
}

static const struct {
  const char* name;
  int (*run)(scene*);
} kCases[] = {
    {"version", case_version}, {"world", case_world},         {"body", case_body},
    {"lpc", case_lpc},         {"tool", case_tool},           {"device", case_device},
    {"steps", case_steps},     {"read back", case_read_back}, {"teardown", case_teardown},
    {"refusals", case_refusals},
};

int main(void) {
  scene s;
  memset(&s, 0, sizeof s);
  printf("consumer built against libmica header %d, running on libmica %d\n", MICA_VERSION_NUMBER,
         (int)mica_version());
  for (size_t i = 0; i < sizeof kCases / sizeof kCases[0]; ++i) {
    if (kCases[i].run(&s) != 0) {
      printf("FAIL %s\n", kCases[i].name);
      if (s.world) mica_world_destroy(s.world);
      return 1;
    }
    printf("ok   %s\n", kCases[i].name);
  }
  printf("tool force after %d steps: (%.4g, %.4g, %.4g) N, %d contacts\n", kSteps, s.force[0], s.force[1],
         s.force[2], (int)s.contacts);
  return 0;
}
