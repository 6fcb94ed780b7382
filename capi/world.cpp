// SPDX-License-Identifier: Apache-2.0
// World lifetime, settings, stepping, statistics and output.
#include <deque>
#include <fstream>

#include "capi_internal.hpp"
#include "fem/element_fields.hpp"
#include "mesh/mesh_io.hpp"

using namespace mica_capi;

static_assert(MICA_STAGE_COUNT == mica::kStageCount, "the C stage list must match the core's");
static_assert(MICA_STAGE_SOLVE == int(mica::Stage::Solve) && MICA_STAGE_COLLIDE == int(mica::Stage::Collide) &&
                  MICA_STAGE_FORCES == int(mica::Stage::Forces),
              "the C stage order must match the core's");

namespace {

mica_world_def world_defaults() {
  mica_world_def d{};
  d.struct_size = sizeof d;
  d.header_version = MICA_VERSION_NUMBER;
  d.gravity[1] = -9.81;
  d.solver = MICA_SOLVER_MICA;  // since 0.5: the haptic default (0.2-0.4: MICA_SOLVER_DIRECT)
  d.max_iterations = 200;
  d.tolerance = 1e-8;
  d.pgs_sweeps = 1;
  d.max_recovery_speed = 1.0;
  d.body_contact = 1;
  d.body_margin = 0.001;
  d.warm_start = 1;
  d.relaxation = 1.0;
  d.mica_sweep = MICA_SWEEP_FACTORED;  // since 0.5 (0.3-0.4: MICA_SWEEP_GAUSS_SEIDEL)
  d.threads = 1;
  d.relinearise_tolerance = 1e-3;
  d.relinearise_max = 8;
  return d;
}

// Since 0.7: the host's job system in place of the world's own workers.
void host_tasks(const mica_world_def& d, mica::WorldSettings& s) {
  if (!d.enqueue_task != !d.finish_task)
    refuse(MICA_ERR_INVALID_ARGUMENT, d.enqueue_task ? "def->finish_task is NULL but def->enqueue_task is set: give both or neither"
                                                     : "def->enqueue_task is NULL but def->finish_task is set: give both or neither");
  const std::string count = std::to_string(d.task_worker_count);
  if (!d.enqueue_task) {
    if (d.task_worker_count != 0)
      refuse(MICA_ERR_INVALID_ARGUMENT, "def->task_worker_count is " + count + " but def->enqueue_task is NULL: leave it at 0, "
                                        "or give the host's job system");
    return;
  }
  if (d.task_worker_count < 1 || d.task_worker_count > mica::kMaxThreads)
    refuse(MICA_ERR_INVALID_ARGUMENT, "def->task_worker_count is " + count + ": with def->enqueue_task set it must be the host's "
                                      "worker count, in 1.." + std::to_string(mica::kMaxThreads));
  if (d.threads != 1)
    refuse(MICA_ERR_INVALID_ARGUMENT, "def->threads is " + std::to_string(d.threads) + ": with def->enqueue_task set the step's "
                                      "threads are def->task_worker_count (leave threads at 1)");
  s.threads = d.task_worker_count;
  s.tasks.enqueue = d.enqueue_task;
  s.tasks.finish = d.finish_task;
  s.tasks.user = d.task_user;
}

// The C values into the core's settings; the core validates the numbers (mica::validate).
mica::WorldSettings translate(const mica_world_def& d) {
  mica::WorldSettings s;
  s.gravity = vec3(d.gravity, "def->gravity");
  switch (d.solver) {
    case MICA_SOLVER_DIRECT: s.solver = mica::SolverKind::Direct; break;
    case MICA_SOLVER_PCG: s.solver = mica::SolverKind::Pcg; break;
    case MICA_SOLVER_MICA: s.solver = mica::SolverKind::Mica; break;
    default: refuse(MICA_ERR_INVALID_ARGUMENT, "def->solver is " + std::to_string(d.solver) + ", not a MICA_SOLVER_* value");
  }
  if (d.paper_norm != 0 && d.paper_norm != 1) refuse(MICA_ERR_INVALID_ARGUMENT, "def->paper_norm must be 0 or 1");
  s.pgs_sweeps = d.pgs_sweeps;
  s.paper_norm = d.paper_norm == 1;
  s.max_recovery_speed = d.max_recovery_speed;
  if (d.body_contact != 0 && d.body_contact != 1) refuse(MICA_ERR_INVALID_ARGUMENT, "def->body_contact must be 0 or 1");
  s.body_contact = d.body_contact == 1;
  s.body_margin = d.body_margin;
  s.body_friction = d.body_friction;
  if (d.warm_start != 0 && d.warm_start != 1) refuse(MICA_ERR_INVALID_ARGUMENT, "def->warm_start must be 0 or 1");
  s.warm_start = d.warm_start == 1;
  s.max_iterations = d.max_iterations;
  s.tolerance = d.tolerance;
  s.plan_all_stages = d.plan_all_stages != 0;
  s.relaxation = d.relaxation;
  s.time_budget_ms = d.time_budget_ms;
  s.threads = d.threads;
  host_tasks(d, s);
  s.relinearise_tolerance = d.relinearise_tolerance;
  s.relinearise_max = d.relinearise_max;
  s.refactor_interval = d.refactor_interval;
  switch (d.mica_sweep) {
    case MICA_SWEEP_GAUSS_SEIDEL: s.mica_sweep = mica::MicaSweep::GaussSeidel; break;
    case MICA_SWEEP_FACTORED: s.mica_sweep = mica::MicaSweep::Factored; break;
    default: refuse(MICA_ERR_INVALID_ARGUMENT, "def->mica_sweep is " + std::to_string(d.mica_sweep) + ", not a MICA_SWEEP_* value");
  }
  return s;
}

// The fields a body's piece points to (a deque: adding one keeps the others where they are).
struct VtkStorage {
  std::deque<mica::Vec3List> vectors;
  std::deque<std::vector<double>> scalars;
};

mica::VtkPiece vtk_piece(const mica::Body& b, VtkStorage& storage) {
  mica::Vec3List& displacement = storage.vectors.emplace_back(b.x.size());
  for (size_t i = 0; i < b.x.size(); ++i) displacement[i] = b.x[i] - b.fem.rest[i];
  std::vector<double>& von_mises = storage.scalars.emplace_back();
  mica::element_von_mises(b.fem, b.x, b.settings.model, von_mises);
  const std::vector<double>& region = storage.scalars.emplace_back(b.regions.begin(), b.regions.end());
  mica::VtkPiece piece;
  piece.positions = &b.x;
  piece.tets = &b.tets;
  piece.point_vectors = {{"velocity", &b.v}, {"displacement", &displacement}};
  piece.cell_scalars = {{"von_mises", &von_mises}, {"region", &region}};
  return piece;
}

}  // namespace

extern "C" {

MICA_API mica_status mica_world_def_init(mica_world_def* def, uint32_t struct_size, uint32_t header_version) {
  const mica_status s = init_def(def, struct_size, world_defaults(), "mica_world_def_init");
  if (s == MICA_OK) def->header_version = header_version;
  return s;
}

MICA_API mica_status mica_world_create(const mica_world_def* def, mica_world** out_world) {
  if (out_world) *out_world = nullptr;
  return guarded(nullptr, "mica_world_create", [&] {
    require(out_world, "out_world");
    mica_world_def d = read_def(def, world_defaults(), "def");
    // Any 0.x header works with this library (older minors are drop-in within SONAME 0); a
    // header of another major version has another ABI.
    if (d.header_version / 10000 != MICA_VERSION_MAJOR)
      refuse(MICA_ERR_VERSION_MISMATCH, "the caller was compiled with libmica header " +
                                            version_text(d.header_version) + " (header_version " +
                                            std::to_string(d.header_version) + "), this library is " + version_text() +
                                            ": a different major version");
    // In 0.3 the slot of `threads` was reserved3 ("zero"): a 0.3 def (it ends before
    // relinearise_tolerance) gets the default thread count, not 0 = every CPU.
    if (def->struct_size <= offsetof(mica_world_def, relinearise_tolerance)) d.threads = world_defaults().threads;
    mica::WorldSettings settings = translate(d);
    if (d.log) {
      const mica_log_fn log = d.log;
      void* const user = d.log_user;
      settings.log = [log, user](mica::LogLevel level, const std::string& message) {
        log(level == mica::LogLevel::Error ? MICA_LOG_ERROR : level == mica::LogLevel::Warning ? MICA_LOG_WARNING : MICA_LOG_INFO,
            message.c_str(), user);
      };
    }
    auto* world = new mica_world(settings);
    world->log = d.log;
    world->log_user = d.log_user;
    *out_world = world;
    return MICA_OK;
  });
}

MICA_API void mica_world_destroy(mica_world* world) { delete world; }

MICA_API mica_status mica_world_set_gravity(mica_world* world, const double gravity[3]) {
  return guarded(world, "mica_world_set_gravity", [&] {
    require(world, "world");
    world->world.set_gravity(vec3(gravity, "gravity"));
    return MICA_OK;
  });
}

MICA_API mica_status mica_step(mica_world* world, double dt) {
  return guarded(world, "mica_step", [&] {
    require(world, "world");
    world->world.step(dt);
    world->topology_warning.clear();  // a blade's cut: its render meshes' warnings went to the log
    return world->world.stats().converged ? MICA_OK : MICA_WARN_NOT_CONVERGED;
  });
}

MICA_API mica_status mica_world_get_stats(const mica_world* world, mica_world_stats* out) {
  return guarded(world, "mica_world_get_stats", [&] {
    require(world, "world");
    require(out, "out");
    if (out->struct_size < offsetof(mica_world_stats, stages) || out->struct_size > sizeof(mica_world_stats))
      refuse(MICA_ERR_STRUCT_SIZE, "out->struct_size is " + std::to_string(out->struct_size) +
                                       ": set it to sizeof(mica_world_stats)");
    const mica::WorldStats& s = world->world.stats();
    mica_world_stats r{};
    r.struct_size = out->struct_size;
    r.converged = s.converged ? 1 : 0;
    r.out_of_time = s.out_of_time ? 1 : 0;
    r.step_count = s.step_count;
    r.solver_iterations = s.solver_iterations;
    r.solves = s.solver_solves;
    r.factorizations = s.factorizations;
    r.factor_waits = s.factor_waits;
    r.solver_residual = s.solver_residual;
    r.ms_last_step = s.ms_last_step;
    for (int k = 0; k < MICA_STAGE_COUNT; ++k) {
      r.stages[k].runs_last_step = s.stages[k].runs_last_step;
      r.stages[k].runs_total = s.stages[k].runs_total;
      r.stages[k].ms_last_step = s.stages[k].ms_last_step;
      r.stages[k].ms_total = s.stages[k].ms_total;
    }
    const std::vector<mica::Contact>& contacts = world->world.contacts();
    r.contacts = int32_t(contacts.size());
    r.body_contacts = int32_t(std::count_if(contacts.begin(), contacts.end(), [](const mica::Contact& c) { return c.tool < 0; }));
    std::memcpy(static_cast<void*>(out), &r, out->struct_size);
    return MICA_OK;
  });
}

MICA_API mica_status mica_body_write_vtk(const mica_world* world, mica_body_id body, const char* path) {
  return guarded(world, "mica_body_write_vtk", [&] {
    require(world, "world");
    require(path, "path");
    VtkStorage storage;
    mica::write_vtk_file(path, {vtk_piece(world->world.body(body), storage)}, "libmica body");
    return MICA_OK;
  });
}

MICA_API mica_status mica_world_write_vtk(const mica_world* world, const char* path) {
  return guarded(world, "mica_world_write_vtk", [&] {
    require(world, "world");
    require(path, "path");
    VtkStorage storage;
    std::vector<mica::VtkPiece> pieces;
    world->world.for_each_body([&](mica::Id, const mica::Body& b) { pieces.push_back(vtk_piece(b, storage)); });
    mica::write_vtk_file(path, pieces, "libmica world");
    return MICA_OK;
  });
}

}  // extern "C"

MICA_API mica_status mica_world_get_ids(const mica_world* world, int32_t kind, uint64_t* out, int32_t capacity,
                                        int32_t* out_count) {
  return guarded(world, "mica_world_get_ids", [&] {
    require(world, "world");
    if (kind < MICA_OBJECT_BODY || kind > MICA_OBJECT_EMBEDDING)
      refuse(MICA_ERR_INVALID_ARGUMENT, "kind is " + std::to_string(kind) + ", not a MICA_OBJECT_* value");
    static_assert(MICA_OBJECT_BODY == int(mica::IdKind::Body) && MICA_OBJECT_DEVICE == int(mica::IdKind::Device) &&
                      MICA_OBJECT_EMBEDDING == int(mica::IdKind::Embedding),
                  "the C object kinds are the core's id kinds");
    std::vector<uint64_t> ids = world->world.ids(mica::IdKind(kind));
    // The embeddings are the C layer's (capi/embedding.cpp), not the core world's.
    if (kind == MICA_OBJECT_EMBEDDING)
      world->embeddings.for_each([&](uint64_t id, const mica::Embedding&) { ids.push_back(id); });
    return copy_out(ids.data(), int32_t(ids.size()), 1, out, capacity, out_count);
  });
}
