// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the input bytes are a program of C API calls on a world and its twin.
//
// The first bytes choose a world definition (tried as given on a throwaway world, then
// sanitised into two identical worlds A and B: same solver, no time budget, one thread, so that
// both are deterministic). Each following op reads its arguments from the bytes, adversarial by
// design: NaN, infinities, huge and tiny values, negative counts, wrong struct_size, null, stale,
// forged and foreign ids, double removal, out-of-range node indices, zero-size arrays, callback
// devices that return garbage. Every op runs on A; if A accepts it, on B too.
//
// Oracles (a failure aborts: libFuzzer saves the input):
//  - no sanitizer report (the library is built with ASan and UBSan here);
//  - every status is in the documented set, never MICA_ERR_INTERNAL, and B's equals A's;
//  - a failed call leaves a non-empty message (except the servo path's poll and stats, which
//    write none by design);
//  - a failed call leaves A bit-identical to B (a hash of every observable: ids, counts,
//    positions, velocities, rest positions, surfaces, energies, tool poses, forces and contact
//    counts, constraint nodes and reactions, step statistics without timings, device figures);
//  - after a call that succeeded, every readable figure of the world is finite (positions,
//    velocities, tool poses, forces and torques, constraint reactions);
//  - a device is never sent a non-finite force or one above its clamp.
//
// Built by fuzz/CMakeLists.txt (clang, libFuzzer) and, without libFuzzer, by tests/ as a replay of
// fuzz/corpus/api (MICA_FUZZ_REPLAY: main() runs each file given).
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <string>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

#include "mica/mica.h"
#include "mica/mica_device.h"

namespace {

[[noreturn]] void bug(const std::string& what) {
  std::fprintf(stderr, "\n==== mica fuzz: BUG: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

// ---- Reading the program

struct Bytes {
  const uint8_t* data;
  size_t size, at = 0;
  bool done() const { return at >= size; }
  uint8_t u8() { return at < size ? data[at++] : 0; }
  uint32_t u32() {
    uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v = (v << 8) | u8();
    return v;
  }
  uint64_t u64() {
    const uint64_t high = u32();
    return (high << 32) | u32();
  }
  bool coin() { return u8() & 1; }
  // A double: mostly plausible (a few cm, a few units), often adversarial.
  double d() {
    static const double kTable[] = {0.0,   -0.0,    1.0,    -1.0,   0.5,     0.01,    -0.01,   0.05,
                                    0.1,   -0.1,    2.0,    10.0,   1e3,     1e6,     1e300,   -1e300,
                                    1e-300, 5e-324, 1.7976931348623157e308, NAN, INFINITY, -INFINITY, 1e-9,
                                    1e-10, 0.999,   1.0000001, 1e-3, 0.02,   -0.05,   0.001,   1e200,  -2.5};
    const uint8_t c = u8();
    if (c < 128) return double(int8_t(u8())) / 1000.0;  // -0.128 .. 0.127
    if (c < 224) return kTable[c % (sizeof kTable / sizeof kTable[0])];
    double v;
    const uint64_t bits = u64();
    std::memcpy(&v, &bits, sizeof v);
    return v;
  }
  double positive() {  // mostly a sane positive value
    const uint8_t c = u8();
    if (c < 160) return 0.005 + (c % 20) * 0.005;
    return d();
  }
  int32_t count(int32_t most) {  // mostly 0..most, sometimes adversarial
    const uint8_t c = u8();
    if (c < 200) return int32_t(c % uint8_t(most + 1));
    static const int32_t kBad[] = {-1, -2, INT32_MIN, INT32_MAX, most + 1, 1 << 20};
    return kBad[c % 6];
  }
  uint32_t struct_size(uint32_t right) {
    const uint8_t c = u8();
    if (c < 230) return right;
    static const uint32_t kBad[] = {0, 4, 8, 16};
    if (c < 240) return kBad[c % 4];
    return c < 248 ? right + 8 : right - 8;
  }
};

// ---- Observing a world

struct Pools {
  std::vector<uint64_t> bodies, lpcs, tools, devices;
};

struct Hash {
  uint64_t h = 1469598103934665603ull;
  void bytes(const void* p, size_t n) {
    const auto* b = static_cast<const uint8_t*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  }
  template <class T>
  void add(const T& v) {
    bytes(&v, sizeof v);
  }
};

void require_finite(const double* v, size_t n, const char* what, uint64_t id) {
  for (size_t i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) {
      char text[160];
      std::snprintf(text, sizeof text, "after a call that succeeded, %s of 0x%llx has a non-finite value (%g)", what,
                    (unsigned long long)id, v[i]);
      bug(text);
    }
}

// The hash of everything a host can read; with `finite`, also the finiteness oracle.
uint64_t observe(const mica_world* w, const Pools& pools, bool finite) {
  Hash h;
  std::vector<double> values;
  std::vector<int32_t> ints;
  for (uint64_t id : pools.bodies) {
    int32_t n = -1, t = -1, s = -1;
    h.add(mica_body_get_counts(w, id, &n, &t, &s));
    h.add(n), h.add(t), h.add(s);
    if (n < 0) continue;
    using Getter = mica_status (*)(const mica_world*, uint64_t, double*, int32_t, int32_t*);
    const Getter getters[] = {mica_body_get_positions, mica_body_get_velocities, mica_body_get_rest_positions};
    for (Getter get : getters) {
      values.assign(size_t(3 * n), 0.0);
      int32_t count = -1;
      h.add(get(w, id, values.data(), n, &count));
      h.bytes(values.data(), values.size() * sizeof(double));
      if (finite) require_finite(values.data(), values.size(), "a body's positions or velocities", id);
    }
    ints.assign(size_t(3 * s), 0);
    int32_t count = -1;
    h.add(mica_body_get_surface(w, id, ints.data(), s, &count));
    h.bytes(ints.data(), ints.size() * sizeof(int32_t));
    double e[3] = {0, 0, 0};
    h.add(mica_body_get_energy(w, id, &e[0], &e[1], &e[2]));
    h.add(e);  // not in the finiteness oracle: 1/2 m v^2 of a finite 1e200 m/s overflows
  }
  for (uint64_t id : pools.tools) {
    double pose[7] = {0}, f[6] = {0};
    int32_t contacts = -1;
    const mica_status a = mica_tool_get_pose(w, id, pose, pose + 3);
    const mica_status b = mica_tool_get_force(w, id, f, f + 3, &contacts);
    h.add(a), h.add(b), h.add(pose), h.add(f), h.add(contacts);
    if (finite && a == MICA_OK) require_finite(pose, 7, "a tool's pose", id);
    if (finite && b == MICA_OK) require_finite(f, 6, "a tool's force or torque", id);
  }
  for (uint64_t id : pools.lpcs) {
    int32_t n = -1;
    h.add(mica_lpc_get_nodes(w, id, nullptr, 0, &n));
    if (n >= 0) {
      ints.assign(size_t(n), 0);
      h.add(mica_lpc_get_nodes(w, id, ints.data(), n, &n));
      h.bytes(ints.data(), ints.size() * sizeof(int32_t));
    }
    double r[3] = {0, 0, 0};
    const mica_status s = mica_lpc_get_reaction(w, id, r);
    h.add(s), h.add(r);
    if (finite && s == MICA_OK) require_finite(r, 3, "a constraint's reaction", id);
  }
  for (uint64_t id : pools.devices) {
    mica_device_info info;
    std::memset(&info, 0, sizeof info);
    info.struct_size = sizeof info;
    h.add(mica_device_get_info(w, id, &info));
    h.add(info);
    mica_device_stats st;
    std::memset(&st, 0, sizeof st);
    st.struct_size = sizeof st;
    h.add(mica_device_get_stats(w, id, &st));
    h.add(st.polls), h.add(st.failures), h.add(st.last_status);  // the rest depends on the clock
  }
  mica_world_stats st;
  std::memset(&st, 0, sizeof st);
  st.struct_size = sizeof st;
  h.add(mica_world_get_stats(w, &st));
  h.add(st.step_count), h.add(st.converged), h.add(st.solver_iterations), h.add(st.out_of_time);
  h.add(st.solver_residual);
  for (const mica_stage_stats& s : st.stages) h.add(s.runs_total), h.add(s.runs_last_step);
  return h.h;
}

// ---- Devices that return garbage

struct Script {
  uint8_t mode = 0;       // what goes wrong
  int32_t fail_after = 0; // read_state fails from this call on (0: never)
  int32_t open_fails = 0, info_mode = 0;
  double base[3] = {0, 0, 0}, step[3] = {0, 0, 0};
  double q[4] = {1, 0, 0, 0};
  double clamp = 1e300;   // the most the device may be sent (N), known after creation
  int64_t reads = 0;
  double time = 0;
};

mica_status script_open(void* user) { return static_cast<Script*>(user)->open_fails ? MICA_ERR_DEVICE : MICA_OK; }

mica_status script_info(void* user, mica_device_info* out) {
  const Script& s = *static_cast<Script*>(user);
  static const double kFigures[] = {1e300, NAN, -1, 0, INFINITY, 5e-324, 1e6, 2.5};
  switch (s.info_mode % 4) {
    case 0: return MICA_ERR_UNSUPPORTED;
    case 1: break;
    default:
      out->max_force = kFigures[s.info_mode % 8];
      out->continuous_force = kFigures[(s.info_mode / 2) % 8];
      out->nominal_stiffness = kFigures[(s.info_mode / 3) % 8];
      out->nominal_damping = kFigures[(s.info_mode / 5) % 8];
      out->workspace_radius = kFigures[(s.info_mode / 7) % 8];
  }
  std::memset(out->name, 'x', sizeof out->name);  // not NUL-terminated
  return MICA_OK;
}

mica_status script_read(void* user, mica_device_state* out) {
  Script& s = *static_cast<Script*>(user);
  ++s.reads;
  if (s.fail_after > 0 && s.reads >= s.fail_after) return s.reads % 2 ? MICA_ERR_DEVICE : -1000;
  const double k = double(s.reads);
  for (int i = 0; i < 3; ++i) out->position[i] = s.base[i] + k * s.step[i];
  for (int i = 0; i < 4; ++i) out->orientation[i] = s.q[i];
  s.time += 1e-3;
  out->timestamp = s.time;
  switch (s.mode % 8) {
    case 1: out->position[s.reads % 3] = NAN; break;
    case 2: out->orientation[0] *= 1.5; break;
    case 3: out->timestamp = s.reads % 3 ? s.time : -1; break;
    case 4: out->velocity[0] = INFINITY; break;
    case 5: for (double& c : out->orientation) c = -c; break;  // flipped: the same rotation
    case 6: out->orientation[0] = 3e200; break;
    default: break;
  }
  return s.mode == 7 ? MICA_WARN_DEVICE : MICA_OK;
}

mica_status script_write(void* user, const double force[3], const double torque[3]) {
  const Script& s = *static_cast<Script*>(user);
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(force[k]) || !std::isfinite(torque[k])) bug("a device was sent a non-finite force or torque");
  const double m = std::sqrt(force[0] * force[0] + force[1] * force[1] + force[2] * force[2]);
  if (m > s.clamp * (1 + 1e-9)) bug("a device was sent " + std::to_string(m) + " N, above its clamp " + std::to_string(s.clamp));
  return s.mode == 7 && s.reads % 5 == 0 ? MICA_ERR_DEVICE : MICA_OK;
}

// ---- Files for the loader op

struct Files {
  std::string dir, valid, duplicate, fifo, zero, directory, missing;
  Files() {
    char templ[] = "/tmp/mica-fuzz-api-XXXXXX";
    if (!mkdtemp(templ)) bug("cannot make a temporary directory");
    dir = templ;
    valid = dir + "/tet.msh";
    duplicate = dir + "/twice.msh";
    fifo = dir + "/fifo.msh";
    zero = dir + "/zero.node";
    directory = dir + "/dir.msh";
    missing = dir + "/missing.ele";
    const char* head = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n4\n1 0 0 0\n2 0.1 0 0\n3 0 0.1 0\n4 0 0 0.1\n$EndNodes\n";
    write(valid, std::string(head) + "$Elements\n1\n1 4 2 1 1 1 2 3 4\n$EndElements\n");
    write(duplicate, std::string(head) + "$Elements\n2\n1 4 2 1 1 1 2 3 4\n2 4 2 1 1 2 1 4 3\n$EndElements\n");
    mkfifo(fifo.c_str(), 0600);
    if (symlink("/dev/zero", zero.c_str()) != 0) zero = "/dev/zero";
    mkdir(directory.c_str(), 0700);
  }
  ~Files() {
    for (const std::string& f : {valid, duplicate, fifo, zero}) unlink(f.c_str());
    rmdir(directory.c_str());
    rmdir(dir.c_str());
  }
  static void write(const std::string& path, const std::string& text) {
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) bug("cannot write " + path);
    std::fputs(text.c_str(), f);
    std::fclose(f);
  }
  const char* pick(uint8_t c) const {
    switch (c % 8) {
      case 0: return valid.c_str();
      case 1: return duplicate.c_str();
      case 2: return fifo.c_str();
      case 3: return zero.c_str();
      case 4: return directory.c_str();
      case 5: return missing.c_str();
      case 6: return "";
      default: return nullptr;
    }
  }
};

// ---- The program

class Program {
 public:
  Program(const uint8_t* data, size_t size) : in_{data, size} {}
  ~Program() {
    for (mica_world* w : w_) mica_world_destroy(w);
  }

  void run() {
    make_worlds();
    for (int op = 0; op < kMaxOps && !in_.done() && step_seconds_ < kStepSeconds; ++op) one_op();
  }

 private:
  static constexpr int kMaxOps = 48, kMaxSteps = 10, kMaxBodies = 2, kMaxDevices = 4;
  // A program stops once its steps have taken this long (s, both worlds): a valid scene can be
  // slow (the exact solvers on many body contacts with friction, docs/solvers.md), and the
  // fuzzer is after wrong answers, not long ones (libFuzzer's timeout is 10 s, under ASan).
  static constexpr double kStepSeconds = 2.0;

  static bool documented(mica_status s) { return s >= MICA_ERR_OUT_OF_MEMORY && s <= MICA_WARN_BODIES_OVERLAP; }

  // Runs f(world, side) on A, then on B if A accepted; checks statuses, messages and the twins.
  template <class F>
  mica_status both(const char* what, F&& f) {
    trace_start_ = std::chrono::steady_clock::now();
    const mica_status a = f(w_[0], 0);
    check_status(what, a);
    if (a < 0) {
      if (!*mica_world_last_error(w_[0])) bug(std::string(what) + " failed with no message");
      compare(what, false);
      return a;
    }
    const mica_status b = f(w_[1], 1);
    if (b != a) bug(std::string(what) + ": world A returned " + std::to_string(a) + ", its twin " + std::to_string(b));
    compare(what, true);
    return a;
  }

  // The servo path: changes the device's statistics even when it fails, so it runs on both
  // worlds whatever A returned; it writes no message.
  template <class F>
  void both_always(const char* what, F&& f) {
    const mica_status a = f(w_[0], 0);
    check_status(what, a);
    const mica_status b = f(w_[1], 1);
    if (b != a) bug(std::string(what) + ": world A returned " + std::to_string(a) + ", its twin " + std::to_string(b));
    compare(what, a >= 0);
  }

  // MICA_FUZZ_TRACE=1: each call and its status on stderr (for reading a seed or a crasher).
  static bool tracing() {
    static const bool on = std::getenv("MICA_FUZZ_TRACE") != nullptr;
    return on;
  }

  void check_status(const char* what, mica_status s) {
    if (tracing())
      std::fprintf(stderr, "%-28s %3d %8.2f ms %s\n", what, s,
                   std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - trace_start_).count(),
                   s < 0 ? mica_world_last_error(w_[0]) : "");
    if (!documented(s)) bug(std::string(what) + " returned " + std::to_string(s) + ", not a documented status");
    if (s == MICA_ERR_INTERNAL) bug(std::string(what) + ": MICA_ERR_INTERNAL: " + mica_world_last_error(w_[0]));
  }

  void compare(const char* what, bool succeeded) {
    const uint64_t a = observe(w_[0], pools_, succeeded), b = observe(w_[1], pools_, false);
    if (a != b)
      bug(std::string(what) + (succeeded ? " succeeded on both worlds, which then differ"
                                         : " failed and left the world different from its twin"));
  }

  void keep(std::vector<uint64_t>& pool, uint64_t a, uint64_t b, const char* what) {
    if (a != b) bug(std::string(what) + ": the twins returned different ids");
    if (a && pool.size() < 64) pool.push_back(a);
  }

  uint64_t pick_id(const std::vector<uint64_t>& same) {
    const uint8_t c = in_.u8();
    const std::vector<uint64_t>* pools[] = {&pools_.bodies, &pools_.lpcs, &pools_.tools, &pools_.devices};
    switch (c % 8) {
      case 0: case 1: case 2: case 3:
        if (!same.empty()) return same[in_.u8() % same.size()];
        return 0;
      case 4: {
        const std::vector<uint64_t>& other = *pools[in_.u8() % 4];
        return other.empty() ? 0 : other[in_.u8() % other.size()];
      }
      case 5: return 0;
      case 6: return in_.u64();
      default: {  // a live-looking id with another generation or slot
        const uint64_t id = same.empty() ? (uint64_t(1) << 56) | (uint64_t(1) << 32) | 1 : same[in_.u8() % same.size()];
        return id + (in_.coin() ? (uint64_t(1) << 32) : 1);
      }
    }
  }

  void make_worlds() {
    // The definition as given, on a throwaway world.
    mica_world_def def = mica_world_def_default();
    def.struct_size = in_.struct_size(sizeof def);
    def.header_version = in_.u8() < 240 ? MICA_VERSION_NUMBER : in_.u32();
    for (double& g : def.gravity) g = in_.d();
    def.solver = in_.u8() % 4;
    def.max_iterations = in_.count(60);
    def.tolerance = in_.d();
    def.pgs_sweeps = in_.count(3);
    def.max_recovery_speed = in_.d();
    def.body_contact = in_.u8() % 3;
    def.body_margin = in_.d();
    def.body_friction = in_.d();
    def.relaxation = in_.d();
    def.time_budget_ms = in_.d();
    def.mica_sweep = in_.u8() % 3;
    def.threads = in_.count(2);
    def.relinearise_tolerance = in_.d();
    def.relinearise_max = in_.count(8);
    def.refactor_interval = in_.count(3);
    mica_world* probe = nullptr;
    const mica_status s = mica_world_create(&def, &probe);
    check_status("mica_world_create", s);
    if (s < 0 && !*mica_world_last_error(nullptr)) bug("mica_world_create failed with no message");
    if ((s < 0) != (probe == nullptr)) bug("mica_world_create: status and world disagree");
    mica_world_destroy(probe);
    // The twins: deterministic (no time budget, one thread), every other choice kept if valid.
    // Caps small enough that one input stays within the fuzzer's timeout: under its sanitizers and
    // coverage the dense contact solves run ~100x slower than in Release (60 MICA iterations of a
    // 14-contact frictional solve: 124 ms a step in Release, 40 s fuzzed). Small caps are still
    // reached, so the capped paths are fuzzed as before. The caps hold for the default definition
    // too (taken when the given one is refused: its 200 iterations made one step of a fuzzed
    // press take 32 s, found_default_def_uncapped).
    mica_world_def t = mica_world_def_default();
    if (s >= 0 && def.struct_size == sizeof def) {  // (a shorter def left the later fields unread)
      t = def;
      t.struct_size = sizeof t;
      t.header_version = MICA_VERSION_NUMBER;
      t.time_budget_ms = 0;
      t.threads = 1;
    }
    if (t.max_iterations > 20) t.max_iterations = 20;
    if (t.relinearise_max > 4) t.relinearise_max = 4;
    t.log = nullptr;
    for (mica_world*& w : w_)
      if (mica_world_create(&t, &w) != MICA_OK) bug("the sanitised twin definition was refused");
  }

  void one_op() {
    const uint8_t op = in_.u8();
    switch (op % 25) {
      case 0: create_box(); break;
      case 1: create_raw(); break;
      case 2: create_from_file(); break;
      case 3: both("mica_body_destroy", [&, id = pick_id(pools_.bodies)](mica_world* w, int) {
                return mica_body_destroy(w, id);
              });
        break;
      case 4: node_forces(); break;
      case 5: add_lpc(); break;
      case 6: both("mica_lpc_remove", [&, id = pick_id(pools_.lpcs)](mica_world* w, int) { return mica_lpc_remove(w, id); });
        break;
      case 7: {
        const uint64_t id = pick_id(pools_.lpcs);
        const double v[3] = {in_.d(), in_.d(), in_.d()};
        const double* velocity = in_.u8() < 250 ? v : nullptr;
        both("mica_lpc_set_velocity", [&](mica_world* w, int) { return mica_lpc_set_velocity(w, id, velocity); });
        break;
      }
      case 8: set_targets(); break;
      case 9: grab(); break;
      case 10: handle_pose(); break;
      case 11: create_tool(); break;
      case 12: both("mica_tool_destroy", [&, id = pick_id(pools_.tools)](mica_world* w, int) { return mica_tool_destroy(w, id); });
        break;
      case 13: tool_pose(); break;
      case 14: case 15: case 16: step(); break;
      case 17: {
        const double g[3] = {in_.d(), in_.d(), in_.d()};
        both("mica_world_set_gravity", [&](mica_world* w, int) { return mica_world_set_gravity(w, g); });
        break;
      }
      case 18: create_device(); break;
      case 19: both("mica_device_destroy", [&, id = pick_id(pools_.devices)](mica_world* w, int) {
                 return mica_device_destroy(w, id);
               });
        break;
      case 20: case 21: poll(); break;
      case 22: readers(); break;
      case 23: cut(); break;
      case 24: remove_tets(); break;
      default: select(); break;
    }
  }

  mica_body_def body_def() {
    mica_body_def d = mica_body_def_default();
    d.struct_size = in_.struct_size(sizeof d);
    const uint8_t c = in_.u8();
    if (c & 1) d.model = in_.u8() % 3;
    if (c & 2) d.mass = in_.u8() % 3;
    if (c & 4) d.is_static = in_.u8() % 3;
    if (c & 8) d.youngs_modulus = in_.u8() < 200 ? 1e3 * (1 + in_.u8() % 50) : in_.d();
    if (c & 16) d.poisson_ratio = in_.u8() < 200 ? 0.01 * (in_.u8() % 50) : in_.d();
    if (c & 32) d.density = in_.u8() < 200 ? 10.0 * (1 + in_.u8() % 200) : in_.d();
    if (c & 64) d.rayleigh_alpha = in_.d(), d.rayleigh_beta = in_.u8() < 200 ? 0 : in_.d();
    if (c & 128) {
      for (double& t : d.translation) t = in_.d();
      for (double& v : d.velocity) v = in_.d();
    }
    return d;
  }

  int bodies_alive() const {
    int n = 0;
    for (uint64_t id : pools_.bodies) n += mica_body_get_counts(w_[0], id, nullptr, nullptr, nullptr) == MICA_OK;
    return n;
  }

  void create_box() {
    if (bodies_alive() >= kMaxBodies) return;
    const mica_body_def d = body_def();
    double lo[3], hi[3];
    for (int k = 0; k < 3; ++k) {
      lo[k] = in_.d();
      hi[k] = in_.u8() < 200 ? lo[k] + in_.positive() : in_.d();
    }
    // At most 2 x 2 x 2 cells: three overlapping 3 x 3 x 3 boxes made hundreds of body contacts,
    // whose exact solve (one linear solve per row, docs/solvers.md) took seconds under ASan.
    static const int32_t kCells[] = {1, 2, 1, 2, 1, 0, -1, INT32_MAX};
    const int32_t cells[3] = {kCells[in_.u8() % 8], kCells[in_.u8() % 8], kCells[in_.u8() % 8]};
    const int32_t per = in_.u8() < 220 ? 5 + in_.coin() : in_.count(7);
    uint64_t out[2] = {0, 0};
    both("mica_body_create_box", [&](mica_world* w, int side) {
      return mica_body_create_box(w, &d, lo, hi, cells, per, &out[side]);
    });
    keep(pools_.bodies, out[0], out[1], "mica_body_create_box");
  }

  void create_raw() {
    if (bodies_alive() >= kMaxBodies) return;
    const mica_body_def d = body_def();
    // Nodes near the corners of a 5 cm cube (or adversarial); tets from the bytes.
    double nodes[3 * 12];
    const int32_t n = in_.count(12), t = in_.count(8);
    const int32_t n_used = n >= 0 && n <= 12 ? n : 12, t_used = t >= 0 && t <= 8 ? t : 8;
    for (int32_t i = 0; i < 12; ++i)
      for (int k = 0; k < 3; ++k) nodes[3 * i + k] = in_.u8() < 230 ? 0.05 * ((i >> k) & 1) + 0.01 * (i / 8) : in_.d();
    int32_t tets[4 * 8];
    for (int32_t e = 0; e < 8; ++e)
      for (int a = 0; a < 4; ++a) tets[4 * e + a] = in_.u8() < 230 ? int32_t(in_.u8() % 12) : int32_t(in_.u32());
    const bool null_nodes = in_.u8() > 250, null_tets = in_.u8() > 250;
    uint64_t out[2] = {0, 0};
    both("mica_body_create", [&](mica_world* w, int side) {
      // A count above the arrays' 12 and 8 would make the caller read past them: clamp.
      return mica_body_create(w, &d, null_nodes ? nullptr : nodes, n > 12 ? n_used : n, null_tets ? nullptr : tets,
                              t > 8 ? t_used : t, &out[side]);
    });
    keep(pools_.bodies, out[0], out[1], "mica_body_create");
  }

  void create_from_file() {
    if (bodies_alive() >= kMaxBodies) return;
    const mica_body_def d = body_def();
    const char* path = files().pick(in_.u8());
    uint64_t out[2] = {0, 0};
    both("mica_body_create_from_file", [&](mica_world* w, int side) {
      return mica_body_create_from_file(w, &d, path, &out[side]);
    });
    keep(pools_.bodies, out[0], out[1], "mica_body_create_from_file");
  }

  void node_indices(int32_t* nodes, int32_t n) {
    for (int32_t i = 0; i < n; ++i) nodes[i] = in_.u8() < 230 ? int32_t(in_.u8() % 70) : int32_t(in_.u32());
  }

  void node_forces() {
    const uint64_t body = pick_id(pools_.bodies);
    const int32_t n = in_.count(4);
    int32_t nodes[4];
    double f[12];
    node_indices(nodes, 4);
    for (double& v : f) v = in_.d();
    both("mica_body_set_node_forces", [&](mica_world* w, int) {
      return mica_body_set_node_forces(w, body, nodes, f, n > 4 ? 4 : n);
    });
  }

  // Resection: a few tets (a box of 2 x 2 x 2 cells has 40), duplicates and out of range included.
  void remove_tets() {
    const uint64_t body = pick_id(pools_.bodies);
    const int32_t n = in_.count(6);
    int32_t tets[6];
    for (int32_t& e : tets) e = in_.u8() < 230 ? int32_t(in_.u8() % 44) : int32_t(in_.u32());
    const bool null_tets = in_.u8() > 250, null_mass = in_.coin();
    double mass = 0;
    both("mica_body_remove_tets", [&](mica_world* w, int) {
      return mica_body_remove_tets(w, body, null_tets ? nullptr : tets, n > 6 ? 6 : n, null_mass ? nullptr : &mass);
    });
  }

  // Incision: one or two triangles, mostly across a box of a few centimetres, sometimes absurd.
  void cut() {
    const uint64_t body = pick_id(pools_.bodies);
    const int32_t n = in_.count(2);
    double t[18];
    for (double& v : t) v = in_.u8() < 230 ? 0.005 * double(in_.u8() % 9) - 0.005 : in_.d();
    const bool null_triangles = in_.u8() > 250, null_out = in_.coin();
    int32_t faces = 0, added = 0;
    both("mica_body_cut", [&](mica_world* w, int) {
      return mica_body_cut(w, body, null_triangles ? nullptr : t, n > 2 ? 2 : n, null_out ? nullptr : &faces,
                           null_out ? nullptr : &added);
    });
  }

  void add_lpc() {
    const uint64_t body = pick_id(pools_.bodies);
    mica_lpc_def d = mica_lpc_def_default();
    d.struct_size = in_.struct_size(sizeof d);
    d.kind = in_.u8() % 5;
    for (auto& dir : d.direction)
      for (double& c : dir) c = in_.d();
    for (double& v : d.velocity) v = in_.u8() < 200 ? 0 : in_.d();
    const int32_t n = in_.count(6);
    int32_t nodes[6];
    node_indices(nodes, 6);
    uint64_t out[2] = {0, 0};
    both("mica_add_lpc", [&](mica_world* w, int side) {
      return mica_add_lpc(w, body, nodes, n > 6 ? 6 : n, &d, &out[side]);
    });
    keep(pools_.lpcs, out[0], out[1], "mica_add_lpc");
  }

  void set_targets() {
    const uint64_t id = pick_id(pools_.lpcs);
    double targets[3 * 8];
    for (double& t : targets) t = in_.d();
    const int32_t n = in_.count(8);
    both("mica_lpc_set_targets", [&](mica_world* w, int) { return mica_lpc_set_targets(w, id, targets, n > 8 ? 8 : n); });
  }

  void grab() {
    const uint64_t body = pick_id(pools_.bodies), tool = in_.coin() ? pick_id(pools_.tools) : 0;
    const double c[3] = {in_.d(), in_.d(), in_.d()};
    const double r = in_.u8() < 200 ? 0.2 : in_.d();
    uint64_t out[2] = {0, 0};
    both("mica_lpc_grab", [&](mica_world* w, int side) { return mica_lpc_grab(w, body, c, r, tool, &out[side]); });
    keep(pools_.lpcs, out[0], out[1], "mica_lpc_grab");
  }

  void quaternion(double q[4]) {
    if (in_.u8() < 200) {
      q[0] = 1, q[1] = q[2] = q[3] = 0;
      const int k = in_.u8() % 4;  // read before the value (C++17 evaluates += right to left)
      q[k] += in_.d();
    } else {
      for (int k = 0; k < 4; ++k) q[k] = in_.d();
    }
  }

  void handle_pose() {
    const uint64_t id = pick_id(pools_.lpcs);
    double p[3] = {in_.d(), in_.d(), in_.d()}, q[4];
    quaternion(q);
    both("mica_lpc_set_handle_pose", [&](mica_world* w, int) { return mica_lpc_set_handle_pose(w, id, p, q); });
  }

  void create_tool() {
    mica_tool_def d = mica_tool_def_default();
    d.struct_size = in_.struct_size(sizeof d);
    d.shape = in_.u8() % 6;
    const uint8_t c = in_.u8();
    if (c & 1) d.radius = in_.positive();
    if (c & 2) for (double& v : d.normal) v = in_.d();
    for (double& v : d.position) v = in_.d();
    if (c & 4) quaternion(d.orientation);
    if (c & 8) d.margin = in_.u8() < 200 ? 0.001 : in_.d();
    if (c & 16) d.friction = in_.u8() < 200 ? 0.1 * (in_.u8() % 20) : in_.d();
    if (c & 32) d.half_length = in_.positive();
    if (c & 64) for (double& v : d.half_extents) v = in_.positive();
    double hull[3 * 12];
    for (int i = 0; i < 12; ++i)
      for (int k = 0; k < 3; ++k) hull[3 * i + k] = in_.u8() < 230 ? 0.01 * (((i >> k) & 1) * 2 - 1) + 0.001 * (i / 8) : in_.d();
    if (c & 128) {
      d.hull_points = in_.u8() < 250 ? hull : nullptr;
      const int32_t n = in_.count(12);
      d.hull_point_count = n > 12 ? 12 : n;
    }
    uint64_t out[2] = {0, 0};
    both("mica_tool_create", [&](mica_world* w, int side) { return mica_tool_create(w, &d, &out[side]); });
    keep(pools_.tools, out[0], out[1], "mica_tool_create");
  }

  void tool_pose() {
    const uint64_t id = pick_id(pools_.tools);
    double p[3] = {in_.d(), in_.d(), in_.d()}, q[4];
    quaternion(q);
    both("mica_tool_set_pose", [&](mica_world* w, int) { return mica_tool_set_pose(w, id, p, q); });
  }

  void step() {
    if (steps_ >= kMaxSteps) return;
    ++steps_;
    const double dt = in_.u8() < 200 ? 0.001 * (1 + in_.u8() % 30) : in_.d();
    const auto start = std::chrono::steady_clock::now();
    both("mica_step", [&](mica_world* w, int) { return mica_step(w, dt); });
    step_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  void create_device() {
    if (pools_.devices.size() >= size_t(kMaxDevices)) return;
    mica_device_def d = mica_device_def_default();
    d.struct_size = in_.struct_size(sizeof d);
    const uint8_t backend = in_.u8();
    d.backend = backend < 200 ? MICA_DEVICE_CALLBACKS : backend % 5;
    d.tool = in_.coin() ? pick_id(pools_.tools) : 0;
    const uint8_t c = in_.u8();
    if (c & 1) d.scale = in_.u8() < 200 ? 1.0 + in_.u8() % 3 : in_.d();
    if (c & 2) for (double& v : d.offset) v = in_.d();
    if (c & 4) quaternion(d.rotation);
    if (c & 8) d.force_mode = in_.u8() % 4;
    if (c & 16) d.filter_window = in_.count(30);
    if (c & 32) d.max_force = in_.u8() < 200 ? 0.5 * (in_.u8() % 10) : in_.d();
    if (c & 64) d.max_force_rate = in_.d(), d.stall_timeout = in_.positive(), d.stall_ramp = in_.positive();
    if (c & 128) d.coupling_stiffness = in_.d(), d.coupling_damping = in_.d(), d.filter_plain = in_.u8() % 3;
    Script script;
    script.mode = in_.u8();
    script.fail_after = in_.u8() < 200 ? 0 : in_.u8() % 20;
    script.open_fails = in_.u8() > 240;
    script.info_mode = in_.u8();
    for (int k = 0; k < 3; ++k) script.base[k] = in_.d(), script.step[k] = in_.u8() < 200 ? -0.0005 : in_.d();
    Script* scripts[2];
    mica_device_callbacks tables[2];
    for (int side = 0; side < 2; ++side) {
      scripts_[side].push_back(script);
      scripts[side] = &scripts_[side].back();
      tables[side] = {sizeof(mica_device_callbacks), 0, scripts[side], script_open, nullptr, script_info,
                      script_read, script_write};
      if (in_.u8() > 250) tables[side].read_state = nullptr;
    }
    tables[1].read_state = tables[0].read_state;
    const bool null_table = in_.u8() > 250;
    uint64_t out[2] = {0, 0};
    both("mica_device_create", [&](mica_world* w, int side) {
      mica_device_def local = d;
      local.callbacks = null_table ? nullptr : &tables[side];
      return mica_device_create(w, &local, &out[side]);
    });
    keep(pools_.devices, out[0], out[1], "mica_device_create");
    if (out[0]) {  // the clamp the device must never see exceeded
      mica_device_info info;
      std::memset(&info, 0, sizeof info);
      info.struct_size = sizeof info;
      if (mica_device_get_info(w_[0], out[0], &info) != MICA_OK) bug("mica_device_get_info failed on a new device");
      const double clamp = d.max_force > 0 ? d.max_force : info.max_force;
      scripts[0]->clamp = scripts[1]->clamp = clamp;
    }
  }

  void poll() {
    const uint64_t id = pick_id(pools_.devices);
    const bool state = in_.coin(), force = in_.coin();
    both_always("mica_device_poll", [&](mica_world* w, int) {
      mica_device_state s;
      std::memset(&s, 0, sizeof s);
      double f[3] = {0, 0, 0};
      const mica_status st = mica_device_poll(w, id, state ? &s : nullptr, force ? f : nullptr);
      if (force && !(std::isfinite(f[0]) && std::isfinite(f[1]) && std::isfinite(f[2])))
        bug("mica_device_poll returned a non-finite force");
      return st;
    });
  }

  // Read-only calls with adversarial buffers: a status, a message on failure, nothing changed.
  void readers() {
    const uint8_t c = in_.u8();
    const uint64_t body = pick_id(pools_.bodies);
    static const int32_t kCap[] = {0, 1, 7, 64, 1000, -1, INT32_MIN, 3};
    const int32_t cap = kCap[in_.u8() % 8];
    std::vector<double> buffer(3 * 1000 + 3);
    std::vector<int32_t> ints(3 * 1000 + 3);
    int32_t count = -7;
    const bool null_out = in_.coin(), null_count = in_.coin();
    // The library writes at most `needed` items and only if cap >= needed: our buffers hold 1000.
    const int32_t safe_cap = cap > 1000 ? 1000 : cap;
    mica_status s = MICA_OK;
    switch (c % 7) {
      case 0: s = mica_body_get_positions(w_[0], body, null_out ? nullptr : buffer.data(), safe_cap, null_count ? nullptr : &count); break;
      case 1: s = mica_body_get_surface(w_[0], body, null_out ? nullptr : ints.data(), safe_cap, null_count ? nullptr : &count); break;
      case 2: {
        mica_world_stats st;
        std::memset(&st, 0, sizeof st);
        st.struct_size = in_.struct_size(sizeof st);
        s = mica_world_get_stats(w_[0], null_out ? nullptr : &st);
        break;
      }
      case 3: {
        const double* view = nullptr;
        int32_t n = 0;
        s = mica_body_positions_view(w_[0], body, null_out ? nullptr : &view, &n);
        if (s == MICA_OK && view) {
          volatile double sum = 0;
          for (int32_t i = 0; i < 3 * n; ++i) sum = sum + view[i];  // ASan: the view is readable
        }
        break;
      }
      case 4: {
        mica_device_info info;
        std::memset(&info, 0, sizeof info);
        info.struct_size = in_.struct_size(sizeof info);
        s = mica_device_get_info(w_[0], pick_id(pools_.devices), null_out ? nullptr : &info);
        if (s == MICA_OK && !std::memchr(info.name, 0, sizeof info.name)) bug("a device name is not NUL-terminated");
        break;
      }
      case 5: {
        mica_device_stats st;
        std::memset(&st, 0, sizeof st);
        st.struct_size = in_.struct_size(sizeof st);
        const mica_status r = mica_device_get_stats(w_[0], pick_id(pools_.devices), null_out ? nullptr : &st);
        check_status("mica_device_get_stats", r);
        compare("mica_device_get_stats", false);
        return;  // the servo path writes no message
      }
      default: {
        double lo[3] = {in_.d(), in_.d(), in_.d()}, hi[3] = {in_.d(), in_.d(), in_.d()};
        s = mica_body_select_nodes_in_box(w_[0], body, lo, hi, in_.u8() % 3, null_out ? nullptr : ints.data(), safe_cap,
                                          null_count ? nullptr : &count);
      }
    }
    check_status("a read-only call", s);
    if (s < 0 && !*mica_world_last_error(w_[0])) bug("a read-only call failed with no message");
    compare("a read-only call", false);
  }

  void select() {
    const uint64_t body = pick_id(pools_.bodies);
    double point[3] = {in_.d(), in_.d(), in_.d()}, normal[3] = {in_.d(), in_.d(), in_.d()};
    std::vector<int32_t> out(1000);
    int32_t count = -1;
    const double tolerance = in_.d();
    const int32_t use_rest = in_.u8() % 3;
    const mica_status s = mica_body_select_nodes_by_plane(w_[0], body, point, normal, tolerance, use_rest,
                                                          out.data(), 1000, &count);
    check_status("mica_body_select_nodes_by_plane", s);
    if (s < 0 && !*mica_world_last_error(w_[0])) bug("mica_body_select_nodes_by_plane failed with no message");
  }

  static const Files& files() {
    static const Files f;
    return f;
  }

  Bytes in_;
  std::chrono::steady_clock::time_point trace_start_ = std::chrono::steady_clock::now();
  mica_world* w_[2] = {nullptr, nullptr};
  Pools pools_;
  std::deque<Script> scripts_[2];  // stable addresses: the devices keep pointers
  int steps_ = 0;
  double step_seconds_ = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Program(data, size).run();
  return 0;
}

#ifdef MICA_FUZZ_REPLAY
// Without libFuzzer: runs each file named on the command line (the corpus, in CTest).
int main(int argc, char** argv) {
  int ran = 0;
  for (int i = 1; i < argc; ++i) {
    FILE* f = std::fopen(argv[i], "rb");
    if (!f) {
      std::fprintf(stderr, "cannot open %s\n", argv[i]);
      return 2;
    }
    std::vector<uint8_t> bytes;
    int c;
    while ((c = std::fgetc(f)) != EOF) bytes.push_back(uint8_t(c));
    std::fclose(f);
    LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
    ++ran;
  }
  std::printf("fuzz_api: %d inputs replayed, no finding\n", ran);
  return 0;
}
#endif
