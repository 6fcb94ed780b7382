// SPDX-License-Identifier: Apache-2.0
// Embedded meshes: a host's render mesh bound to a body's tets, placed after each step.
#include <memory>

#include "capi_internal.hpp"

using namespace mica_capi;

namespace {

mica_embedding_def embedding_defaults() {
  mica_embedding_def d{};
  d.struct_size = sizeof d;
  d.radius = 1e-3;
  return d;
}

mica::Embedding& embedding(const mica_world* world, mica_embedding_id id) {
  return world->embeddings.get(id, "embedding");
}

// The embedding's body as it is now; a destroyed body is refused by name.
const mica::Body& body_of(const mica_world* world, const mica::Embedding& e) {
  try {
    return world->world.body(e.body());
  } catch (const mica::Error& error) {
    if (error.code() != mica::Errc::StaleId) throw;
    refuse(MICA_ERR_STALE_ID, std::string("the embedding's ") + error.what() + ": destroy the embedding");
  }
}

// "3 of 100 vertices are unbound ... (the first: vertex 41)".
std::string unbound_message(const mica::Embedding& e, double radius) {
  const std::vector<int32_t>& kinds = e.kinds();
  const auto first = std::find(kinds.begin(), kinds.end(), MICA_EMBED_UNBOUND) - kinds.begin();
  return std::to_string(e.count(mica::VertexKind::Unbound)) + " of " + std::to_string(e.vertex_count()) +
         " vertices are farther than the radius (" + mica::number_text(radius) +
         " m) from the body and unbound (the first: vertex " + std::to_string(first) +
         "); mica_embedding_update leaves their positions as they are";
}

}  // namespace

namespace mica_capi {

void follow_topology(mica_world* world, const mica::TopologyChange& change, const mica::Body& body) noexcept {
  world->embeddings.for_each([&](uint64_t id, mica::Embedding& e) {
    if (e.body() != change.body) return;
    std::string message;
    try {
      const mica::Embedding::FollowReport r = e.follow(change, body.fem.rest, body.tets, body.surface);
      if (r.unbound > 0)
        message = "embedding " + decltype(world->embeddings)::hex(id) + ": " + std::to_string(r.unbound) + " of the " +
                  std::to_string(r.inside + r.projected + r.unbound) + " vertices whose tets went are farther than "
                  "the radius (" + mica::number_text(e.radius()) + " m) from the body and unbound; " +
                  std::to_string(e.count(mica::VertexKind::Unbound)) + " of " + std::to_string(e.vertex_count()) +
                  " are unbound now, and mica_embedding_update leaves their positions as they are";
    } catch (...) {
      e.unbind_all(int32_t(body.x.size()), int32_t(body.tets.size()), change.topology_version);  // consistent, and says so
      try {
        message = "embedding " + decltype(world->embeddings)::hex(id) + " could not follow the change of its body's tets: all " +
                  std::to_string(e.vertex_count()) + " vertices are unbound (destroy it and embed again)";
      } catch (...) {
      }
    }
    if (message.empty()) return;
    try {
      if (!world->topology_warning.empty()) world->topology_warning += "; ";
      world->topology_warning += message;
    } catch (...) {
    }
    if (world->log) world->log(MICA_LOG_WARNING, message.c_str(), world->log_user);
  });
}

mica_status topology_warning(mica_world* world, const char* function) {
  if (world->topology_warning.empty()) return MICA_OK;
  world->last_error = std::string(function) + ": " + world->topology_warning;
  world->topology_warning.clear();
  return MICA_WARN_UNBOUND_VERTICES;
}

}  // namespace mica_capi

static_assert(MICA_EMBED_INSIDE == int(mica::VertexKind::Inside) && MICA_EMBED_PROJECTED == int(mica::VertexKind::Projected) &&
                  MICA_EMBED_UNBOUND == int(mica::VertexKind::Unbound),
              "the C vertex kinds are the core's");

extern "C" {

MICA_API mica_status mica_embedding_def_init(mica_embedding_def* def, uint32_t struct_size) {
  return init_def(def, struct_size, embedding_defaults(), "mica_embedding_def_init");
}

MICA_API mica_status mica_embedding_create(mica_world* world, mica_body_id body, const mica_embedding_def* def,
                                           const double* xyz, int32_t vertex_count, const int32_t* triangles,
                                           int32_t triangle_count, mica_embedding_id* out_embedding) {
  return guarded(world, "mica_embedding_create", [&] {
    require(world, "world");
    require(out_embedding, "out_embedding");
    const mica_embedding_def d = read_def(def, embedding_defaults(), "def");
    require(xyz, "xyz");
    if (vertex_count < 1 || vertex_count > INT32_MAX / 3)
      refuse(MICA_ERR_INVALID_ARGUMENT, "vertex_count is " + std::to_string(vertex_count) + ", must be in 1.." +
                                            std::to_string(INT32_MAX / 3));
    if (triangle_count < 0 || triangle_count > INT32_MAX / 3)
      refuse(MICA_ERR_INVALID_ARGUMENT, "triangle_count is " + std::to_string(triangle_count) + ", must be in 0.." +
                                            std::to_string(INT32_MAX / 3));
    if (triangle_count > 0) require(triangles, "triangles");
    const mica::Body& b = world->world.body(body);
    auto e = std::make_unique<mica::Embedding>(body, b.fem.rest, b.tets, b.surface, xyz, vertex_count, triangles,
                                               triangle_count, d.radius);
    e->set_topology_version(b.topology_version);
    const bool unbound = e->count(mica::VertexKind::Unbound) > 0;
    std::string warning = unbound ? "mica_embedding_create: " + unbound_message(*e, d.radius) : std::string();
    *out_embedding = world->embeddings.insert(std::move(e));  // nothing may fail after this
    if (!unbound) return MICA_OK;
    world->last_error.swap(warning);
    if (world->log) world->log(MICA_LOG_WARNING, world->last_error.c_str(), world->log_user);
    return MICA_WARN_UNBOUND_VERTICES;
  });
}

MICA_API mica_status mica_embedding_destroy(mica_world* world, mica_embedding_id id) {
  return guarded(world, "mica_embedding_destroy", [&] {
    require(world, "world");
    embedding(world, id);  // refuses a stale id
    world->embeddings.erase(id);
    return MICA_OK;
  });
}

MICA_API mica_status mica_embedding_get_counts(const mica_world* world, mica_embedding_id id, int32_t* vertex_count,
                                               int32_t* inside, int32_t* projected, int32_t* unbound) {
  return guarded(world, "mica_embedding_get_counts", [&] {
    require(world, "world");
    const mica::Embedding& e = embedding(world, id);
    if (vertex_count) *vertex_count = e.vertex_count();
    if (inside) *inside = e.count(mica::VertexKind::Inside);
    if (projected) *projected = e.count(mica::VertexKind::Projected);
    if (unbound) *unbound = e.count(mica::VertexKind::Unbound);
    return MICA_OK;
  });
}

MICA_API mica_status mica_embedding_get_kinds(const mica_world* world, mica_embedding_id id, int32_t* out,
                                              int32_t capacity, int32_t* out_count) {
  return guarded(world, "mica_embedding_get_kinds", [&] {
    require(world, "world");
    const mica::Embedding& e = embedding(world, id);
    return copy_out(e.kinds().data(), e.vertex_count(), 1, out, capacity, out_count);
  });
}

MICA_API mica_status mica_embedding_update(const mica_world* world, mica_embedding_id id, double* out_xyz,
                                           double* out_normals) {
  return guarded(world, "mica_embedding_update", [&] {
    require(world, "world");
    require(out_xyz, "out_xyz");
    const mica::Embedding& e = embedding(world, id);
    if (out_normals && e.triangle_count() == 0)
      refuse(MICA_ERR_WRONG_STATE, "the embedding was made without triangles: it has no normals (pass out_normals NULL)");
    const uintptr_t bytes = 3 * sizeof(double) * uintptr_t(e.vertex_count()), a = uintptr_t(out_xyz),
                    n = uintptr_t(out_normals);  // as integers: the two may be unrelated arrays
    if (out_normals && n < a + bytes && a < n + bytes)
      refuse(MICA_ERR_INVALID_ARGUMENT, "out_xyz and out_normals overlap: pass two arrays");
    const mica::Body& b = body_of(world, e);
    if (b.topology_version != e.topology_version())  // every change is followed: this is a bug
      refuse(MICA_ERR_INTERNAL, "the embedding is of the body's tets at topology version " +
                                    std::to_string(e.topology_version()) + ", the body is at " +
                                    std::to_string(b.topology_version));
    e.update(b.x, b.tets, out_xyz, out_normals);
    return MICA_OK;
  });
}

}  // extern "C"
