// SPDX-License-Identifier: Apache-2.0
// The scene, the oracle on a status and the entry points of the file targets (fuzz_files.hpp).
#include "fuzz_files.hpp"

#include <cstdio>
#include <cstring>

namespace mica_fuzz {

void require_ok(const mica_world* w, mica_status s, const char* what) {
  if (s < 0) bug(std::string(what) + ": " + mica_status_string(s) + ": " + mica_world_last_error(w));
}

void check_status(const mica_world* w, mica_status s, const char* what) {
  if (s < MICA_ERR_TRUNCATED || s > MICA_WARN_BODIES_OVERLAP || s == MICA_ERR_INTERNAL)
    bug(std::string(what) + " returned " + std::to_string(s) + " (" + mica_status_string(s) + "): " +
        mica_world_last_error(w));
  if (s < 0 && mica_world_last_error(w)[0] == 0) bug(std::string(what) + " failed without a message");
}

mica_world* new_world(int solver) {
  mica_world_def wd = mica_world_def_default();
  wd.solver = solver == 2 ? MICA_SOLVER_DIRECT : MICA_SOLVER_MICA;
  wd.mica_sweep = solver == 1 ? MICA_SWEEP_GAUSS_SEIDEL : MICA_SWEEP_FACTORED;
  wd.max_iterations = 100;
  mica_world* w = nullptr;
  require_ok(nullptr, mica_world_create(&wd, &w), "mica_world_create");
  return w;
}

namespace {
// The device's hand: a little sideways over time.
void sway(double t, double p[3], void*) {
  p[0] = 0.1 + 0.01 * t;
  p[1] = 0;
  p[2] = 0;
}
}  // namespace

Scene build_scene(mica_world* w) {
  Scene s;
  s.world = w;
  mica_body_def bd = mica_body_def_default();
  bd.youngs_modulus = 1e4;
  bd.rayleigh_alpha = 2;
  const double lo[3] = {-0.05, -0.1, -0.05}, hi[3] = {0.05, 0, 0.05};
  const int32_t cells[3] = {1, 1, 1};
  require_ok(w, mica_body_create_box(w, &bd, lo, hi, cells, 5, &s.body), "mica_body_create_box");
  const double base[3] = {0, -0.1, 0}, up[3] = {0, 1, 0};
  int32_t nodes[8], count = 0;
  require_ok(w, mica_body_select_nodes_by_plane(w, s.body, base, up, 1e-9, 1, nodes, 8, &count), "select the base");
  const mica_lpc_def fixed = mica_lpc_def_default();
  require_ok(w, mica_add_lpc(w, s.body, nodes, count, &fixed, &s.base), "mica_add_lpc");
  const double corner[3] = {0.05, 0, 0.05};
  require_ok(w, mica_lpc_grab(w, s.body, corner, 0.01, MICA_NULL_ID, &s.grab), "mica_lpc_grab");
  mica_tool_def sphere = mica_tool_def_default();
  sphere.radius = 0.02;
  sphere.position[1] = 0.021;
  require_ok(w, mica_tool_create(w, &sphere, &s.sphere), "mica_tool_create");
  mica_tool_def box = mica_tool_def_default();
  box.shape = MICA_TOOL_BOX;
  box.half_extents[0] = box.half_extents[1] = box.half_extents[2] = 0.01;
  box.position[0] = 0.1;
  require_ok(w, mica_tool_create(w, &box, &s.box), "mica_tool_create");
  mica_device_def dd = mica_device_def_default();
  dd.backend = MICA_DEVICE_SIMULATED;
  dd.trajectory = sway;
  dd.tool = s.box;
  dd.filter_window = 4;
  require_ok(w, mica_device_create(w, &dd, &s.device), "mica_device_create");
  return s;
}

void press(const Scene& s, int steps) {
  for (int k = 0; k < steps; ++k) {
    for (int i = 0; i < 4; ++i) mica_device_poll(s.world, s.device, nullptr, nullptr);
    double p[3] = {0, 0.021, 0};
    const double q[4] = {1, 0, 0, 0};
    mica_tool_get_pose(s.world, s.sphere, p, nullptr);
    p[1] -= 0.001;
    require_ok(s.world, mica_tool_set_pose(s.world, s.sphere, p, q), "mica_tool_set_pose");
    const double handle[3] = {0.05, 0.0005 * k, 0.05};
    require_ok(s.world, mica_lpc_set_handle_pose(s.world, s.grab, handle, q), "mica_lpc_set_handle_pose");
    require_ok(s.world, mica_step(s.world, 0.01), "mica_step");
  }
}

void read_world(mica_world* w) {
  std::uint64_t ids[64];
  for (int32_t kind : {MICA_OBJECT_BODY, MICA_OBJECT_TOOL, MICA_OBJECT_LPC, MICA_OBJECT_DEVICE}) {
    int32_t count = 0;
    require_ok(w, mica_world_get_ids(w, kind, ids, 64, &count), "mica_world_get_ids");
    for (int32_t k = 0; k < count; ++k) {
      double f[3];
      int32_t nodes = 0;
      if (kind == MICA_OBJECT_BODY) {
        require_ok(w, mica_body_get_counts(w, ids[k], &nodes, nullptr, nullptr), "mica_body_get_counts");
        std::vector<double> x(3 * size_t(nodes));
        require_ok(w, mica_body_get_positions(w, ids[k], x.data(), nodes, &nodes), "mica_body_get_positions");
        check_status(w, mica_body_get_velocities(w, ids[k], x.data(), nodes, &nodes), "mica_body_get_velocities");
      }
      if (kind == MICA_OBJECT_TOOL) require_ok(w, mica_tool_get_force(w, ids[k], f, nullptr, nullptr), "mica_tool_get_force");
      if (kind == MICA_OBJECT_LPC) require_ok(w, mica_lpc_get_reaction(w, ids[k], f), "mica_lpc_get_reaction");
      if (kind == MICA_OBJECT_DEVICE) check_status(w, mica_device_poll(w, ids[k], nullptr, f), "mica_device_poll");
    }
  }
  int32_t count = 0;
  const mica_status s = mica_world_get_contacts(w, nullptr, 0, &count);
  if (s != MICA_ERR_BUFFER_TOO_SMALL) require_ok(w, s, "mica_world_get_contacts");
  std::vector<mica_contact> contacts(size_t(count) + 1);
  contacts[0].struct_size = sizeof(mica_contact);
  require_ok(w, mica_world_get_contacts(w, contacts.data(), count + 1, &count), "mica_world_get_contacts");
  mica_world_stats stats{};
  stats.struct_size = sizeof stats;
  require_ok(w, mica_world_get_stats(w, &stats), "mica_world_get_stats");
}

bool write_file(const std::string& path, const Bytes& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return false;
  const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  return std::fclose(f) == 0 && ok;
}

bool read_file(const std::string& path, Bytes& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  bytes.clear();
  for (int c; (c = std::fgetc(f)) != EOF;) bytes.push_back(std::uint8_t(c));
  std::fclose(f);
  return true;
}

}  // namespace mica_fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, size_t size) {
  mica_fuzz::file_target::run(data, size);
  return 0;
}

#ifdef MICA_FUZZ_REPLAY
// `PROGRAM --write-seeds DIR` writes the target's seeds; `PROGRAM FILE...` runs each file, which
// must be read whole, and each of its fixed mutations.
int main(int argc, char** argv) {
  namespace target = mica_fuzz::file_target;
  if (argc == 3 && std::strcmp(argv[1], "--write-seeds") == 0) {
    if (target::write_seeds(argv[2])) return 0;
    std::fprintf(stderr, "%s: cannot write the seeds into %s\n", argv[0], argv[2]);
    return 1;
  }
  size_t runs = 0;
  for (int i = 1; i < argc; ++i) {
    mica_fuzz::Bytes bytes;
    if (!mica_fuzz::read_file(argv[i], bytes)) {
      std::fprintf(stderr, "%s: cannot read %s\n", argv[0], argv[i]);
      return 2;
    }
    if (!target::run(bytes.data(), bytes.size())) {
      std::fprintf(stderr, "%s: the seed %s is not read whole by this libmica: write the seeds again (%s --write-seeds "
                           "<its folder>)\n", argv[0], argv[i], argv[0]);
      return 1;
    }
    const std::vector<mica_fuzz::Bytes> mutated = target::mutations(bytes);
    for (const mica_fuzz::Bytes& m : mutated) target::run(m.data(), m.size());
    runs += 1 + mutated.size();
  }
  std::printf("%s: %d files, %zu inputs with their mutations, no finding\n", argv[0], argc - 1, runs);
  return 0;
}
#endif
