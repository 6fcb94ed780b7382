// SPDX-License-Identifier: Apache-2.0
// A world's saved state (world/state_io.cpp) and the contacts readout of the last step.
#include "capi_internal.hpp"

using namespace mica_capi;

namespace {

// The contacts of the last step, as the C struct (struct_size left to the caller's).
std::vector<mica_contact> contacts_of(const mica::World& w) {
  const std::vector<mica::Contact>& contacts = w.contacts();
  const mica::ContactRows& rows = w.contact_rows();
  const std::vector<double>& lambda = w.impulses();
  const mica::Vec3List& curvature = w.curvature_impulses();
  std::vector<mica_contact> out(contacts.size());
  for (size_t k = 0; k < contacts.size(); ++k) {
    const mica::Contact& c = contacts[k];
    mica_contact& r = out[k];
    r = mica_contact{};
    r.kind = c.a.count;  // MICA_CONTACT_NODE, _EDGE, _TRIANGLE are the point's node counts
    r.body = w.step_bodies()[size_t(c.a.body)];
    r.other_kind = c.tool >= 0 ? MICA_CONTACT_OTHER_TOOL : MICA_CONTACT_OTHER_BODY;
    r.other = c.other;
    for (int j = 0; j < 3; ++j) {
      r.nodes[j] = j < c.a.count ? c.a.nodes[j] : -1;
      r.weights[j] = j < c.a.count ? c.a.weights[j] : 0.0;
      r.other_nodes[j] = j < c.b.count ? c.b.nodes[j] : -1;
      r.other_weights[j] = j < c.b.count ? c.b.weights[j] : 0.0;
      r.point[j] = c.point[j];
      r.normal[j] = c.normal[j];
      r.curvature_impulse[j] = k < curvature.size() ? curvature[k][j] : 0.0;
    }
    r.gap = c.gap;
    r.friction = c.friction;
  }
  // The impulses of each contact's rows (a normal row, then its tangent pair).
  for (size_t row = 0; row < rows.size() && row < lambda.size(); ++row) {
    mica_contact& r = out[size_t(rows.contact[row])];
    if (rows.normal_of[row] < 0) {
      r.normal_impulse = lambda[row];
      continue;
    }
    for (int j = 0; j < 3; ++j) r.tangent_impulse[j] += lambda[row] * rows.direction[row][j];
  }
  return out;
}

}  // namespace

extern "C" {

MICA_API mica_status mica_world_state_size(const mica_world* world, size_t* out_bytes) {
  return guarded(world, "mica_world_state_size", [&] {
    require(world, "world");
    require(out_bytes, "out_bytes");
    *out_bytes = world->world.save_state().size();
    return MICA_OK;
  });
}

MICA_API mica_status mica_world_save_state(const mica_world* world, void* buffer, size_t bytes) {
  return guarded(world, "mica_world_save_state", [&] {
    require(world, "world");
    require(buffer, "buffer");
    const std::vector<uint8_t> state = world->world.save_state();
    if (bytes < state.size())
      refuse(MICA_ERR_BUFFER_TOO_SMALL, "the buffer has " + std::to_string(bytes) + " bytes, the state needs " +
                                            std::to_string(state.size()) + " (mica_world_state_size)");
    std::memcpy(buffer, state.data(), state.size());
    return MICA_OK;
  });
}

MICA_API mica_status mica_world_restore_state(mica_world* world, const void* buffer, size_t bytes) {
  return guarded(world, "mica_world_restore_state", [&] {
    require(world, "world");
    require(buffer, "buffer");
    world->world.restore_state(static_cast<const uint8_t*>(buffer), bytes);
    return MICA_OK;
  });
}

MICA_API mica_status mica_world_get_contacts(const mica_world* world, mica_contact* out, int32_t capacity,
                                             int32_t* out_count) {
  return guarded(world, "mica_world_get_contacts", [&] {
    require(world, "world");
    if (!out) require(out_count, "out_count");
    if (capacity < 0) refuse(MICA_ERR_INVALID_ARGUMENT, "capacity is " + std::to_string(capacity) + ", must be >= 0");
    // The caller's struct_size is the array's stride: a later, larger mica_contact still fills an
    // older caller's array (each element up to its size).
    const uint32_t size = out && capacity > 0 ? out[0].struct_size : uint32_t(sizeof(mica_contact));
    if (size != sizeof(mica_contact))  // 0.6's is the first and only size so far
      refuse(MICA_ERR_STRUCT_SIZE, "out[0].struct_size is " + std::to_string(size) +
                                       ": set it to sizeof(mica_contact) (" + std::to_string(sizeof(mica_contact)) + ")");
    const int32_t count = int32_t(world->world.contacts().size());
    if (out && capacity < count) {
      if (out_count) *out_count = count;
      refuse(MICA_ERR_BUFFER_TOO_SMALL, "buffer too small: capacity " + std::to_string(capacity) + ", needed " +
                                            std::to_string(count));
    }
    const std::vector<mica_contact> contacts = out ? contacts_of(world->world) : std::vector<mica_contact>{};
    if (out_count) *out_count = count;
    for (size_t k = 0; k < contacts.size(); ++k) {
      mica_contact c = contacts[k];
      c.struct_size = size;
      std::memcpy(reinterpret_cast<char*>(out) + k * size, &c, size);
    }
    return MICA_OK;
  });
}

}  // extern "C"
