// SPDX-License-Identifier: Apache-2.0
// Haptic devices: creation from the def, the servo poll, the servo loop, statistics.
#include "capi_internal.hpp"
#include "device_callbacks.hpp"
#include "devices/null_device.hpp"
#include "devices/simulated_device.hpp"
#include "devices/touch_device.hpp"
#include "devices/trajectory.hpp"
#include "mica/mica_device.h"

using namespace mica_capi;

namespace {

mica_device_def device_defaults() {
  mica_device_def d{};
  d.struct_size = sizeof d;
  d.backend = MICA_DEVICE_NULL;
  d.scale = 1;
  d.rotation[0] = 1;
  d.force_mode = MICA_FORCE_LOCAL_MODEL;
  d.filter_window = 20;
  d.max_force_rate = 1000;
  d.stall_timeout = 0.1;
  d.stall_ramp = 0.05;
  d.coupling_stiffness = 300;
  d.coupling_damping = 2;
  d.simulated_kind = MICA_SIMULATED_TRAJECTORY;
  d.hand_mass = 0.1;
  d.hand_stiffness = 200;
  d.hand_damping = 5;
  return d;
}

mica::Trajectory trajectory_of(const mica_device_def& d) {
  if (d.name) return mica::load_trajectory_csv(d.name);
  if (!d.trajectory) return [](double) { return mica::Vec3::Zero(); };
  const mica_trajectory_fn fn = d.trajectory;
  void* const user = d.trajectory_user;
  return [fn, user](double t) {
    double p[3] = {0, 0, 0};
    fn(t, p, user);
    return mica::Vec3(p[0], p[1], p[2]);
  };
}

std::unique_ptr<mica::Device> make_device(const mica_device_def& d) {
  switch (d.backend) {
    case MICA_DEVICE_CALLBACKS: {
      require(d.callbacks, "def->callbacks");
      if (d.callbacks->struct_size != sizeof(mica_device_callbacks))
        refuse(MICA_ERR_STRUCT_SIZE, "def->callbacks->struct_size must be sizeof(mica_device_callbacks)");
      return std::make_unique<CallbackDevice>(*d.callbacks);
    }
    case MICA_DEVICE_NULL: return std::make_unique<mica::NullDevice>();
    case MICA_DEVICE_SIMULATED:
      if (d.simulated_kind == MICA_SIMULATED_HAND)
        return std::make_unique<mica::VirtualHand>(trajectory_of(d),
                                                   mica::HandParams{d.hand_mass, d.hand_stiffness, d.hand_damping});
      if (d.simulated_kind != MICA_SIMULATED_TRAJECTORY)
        refuse(MICA_ERR_INVALID_ARGUMENT, "def->simulated_kind is " + std::to_string(d.simulated_kind) +
                                              ", not a MICA_SIMULATED_* value");
      return std::make_unique<mica::SimulatedStylus>(trajectory_of(d));
    case MICA_DEVICE_TOUCH: return std::make_unique<mica::TouchDevice>(d.name ? d.name : "");
    default:
      refuse(MICA_ERR_INVALID_ARGUMENT, "def->backend is " + std::to_string(d.backend) + ", not a MICA_DEVICE_* value");
  }
}

mica::DeviceSettings translate(const mica_device_def& d) {
  mica::DeviceSettings s;
  s.tool = d.tool;
  s.lpc = d.lpc;
  s.scale = d.scale;
  s.offset = vec3(d.offset, "def->offset");
  s.rotation = quaternion(d.rotation, "def->rotation");
  switch (d.force_mode) {
    case MICA_FORCE_LOCAL_MODEL: s.mode = mica::ForceMode::LocalModel; break;
    case MICA_FORCE_HOLD: s.mode = mica::ForceMode::Hold; break;
    case MICA_FORCE_COUPLING: s.mode = mica::ForceMode::Coupling; break;
    default: refuse(MICA_ERR_INVALID_ARGUMENT, "def->force_mode is " + std::to_string(d.force_mode) + ", not a MICA_FORCE_* value");
  }
  s.filter_window = d.filter_window;
  if (d.filter_plain != 0 && d.filter_plain != 1) refuse(MICA_ERR_INVALID_ARGUMENT, "def->filter_plain must be 0 or 1");
  s.filter_restart_on_contact = d.filter_plain == 0;
  s.safety = {d.max_force, d.max_force_rate, d.stall_timeout, d.stall_ramp};
  s.coupling_stiffness = d.coupling_stiffness;
  s.coupling_damping = d.coupling_damping;
  return s;
}

}  // namespace

extern "C" {

MICA_API mica_status mica_device_def_init(mica_device_def* def, uint32_t struct_size) {
  return init_def(def, struct_size, device_defaults(), "mica_device_def_init");
}

MICA_API mica_status mica_device_create(mica_world* world, const mica_device_def* def, mica_device_id* out_device) {
  return guarded(world, "mica_device_create", [&] {
    require(world, "world");
    require(out_device, "out_device");
    const mica_device_def d = read_def(def, device_defaults(), "def");
    const mica::DeviceSettings settings = translate(d);
    world->world.check_device_target(settings);  // a stale or unfit tool or grasp fails before the device is opened
    *out_device = world->world.add_device(make_device(d), settings);
    return MICA_OK;
  });
}

MICA_API mica_status mica_device_destroy(mica_world* world, mica_device_id device) {
  return guarded(world, "mica_device_destroy", [&] {
    require(world, "world");
    world->world.remove_device(device);
    return MICA_OK;
  });
}

MICA_API mica_status mica_device_get_info(const mica_world* world, mica_device_id device, mica_device_info* out) {
  return guarded(world, "mica_device_get_info", [&] {
    require(world, "world");
    require(out, "out");
    const mica::World::DeviceReadGuard guard = world->world.device_read_guard();  // other threads may create devices
    const mica::DeviceLink* link = world->world.find_device(device);
    if (!link) world->world.device(device);  // throws the stale-id error
    const mica::DeviceInfo& in = link->info();
    mica_device_info r{};
    r.struct_size = sizeof r;
    std::memcpy(r.name, in.name.data(), sizeof r.name);
    r.max_force = in.max_force;
    r.continuous_force = in.continuous_force;
    r.nominal_stiffness = in.nominal_stiffness;
    r.nominal_damping = in.nominal_damping;
    r.workspace_radius = in.workspace_radius;
    *out = r;
    return MICA_OK;
  });
}

// The servo path: no guard (it would allocate a message), no exceptions can arise below.
MICA_API mica_status mica_device_poll(mica_world* world, mica_device_id device, mica_device_state* out_state,
                                      double out_force[3]) {
  if (!world) return MICA_ERR_NULL_ARGUMENT;
  const mica::World::DeviceReadGuard guard = world->world.device_read_guard();
  mica::DeviceLink* link = world->world.find_device(device);
  if (!link) return MICA_ERR_STALE_ID;
  mica::DeviceState state;
  mica::Vec3 force;
  const mica::DeviceResult r = link->poll(&state, &force);
  if (out_state) {
    out_state->struct_size = sizeof *out_state;
    out_state->buttons = state.buttons;
    for (int k = 0; k < 3; ++k) {
      out_state->position[k] = state.position[k];
      out_state->velocity[k] = state.velocity[k];
    }
    out_state->orientation[0] = state.orientation.w();
    out_state->orientation[1] = state.orientation.x();
    out_state->orientation[2] = state.orientation.y();
    out_state->orientation[3] = state.orientation.z();
    out_state->timestamp = state.timestamp;
  }
  if (out_force)
    for (int k = 0; k < 3; ++k) out_force[k] = force[k];
  return r.code < 0 ? MICA_ERR_DEVICE : r.code > 0 ? MICA_WARN_DEVICE : MICA_OK;
}

MICA_API mica_status mica_device_start(mica_world* world, mica_device_id device) {
  return guarded(world, "mica_device_start", [&] {
    require(world, "world");
    world->world.device(device).start();
    return MICA_OK;
  });
}

MICA_API mica_status mica_device_stop(mica_world* world, mica_device_id device) {
  return guarded(world, "mica_device_stop", [&] {
    require(world, "world");
    world->world.device(device).stop();
    return MICA_OK;
  });
}

MICA_API mica_status mica_device_get_stats(const mica_world* world, mica_device_id device, mica_device_stats* out) {
  if (!world || !out) return MICA_ERR_NULL_ARGUMENT;
  if (out->struct_size < sizeof(uint32_t) || out->struct_size > sizeof(mica_device_stats)) return MICA_ERR_STRUCT_SIZE;
  const mica::World::DeviceReadGuard guard = world->world.device_read_guard();
  const mica::DeviceLink* link = world->world.find_device(device);
  if (!link) return MICA_ERR_STALE_ID;
  const mica::ServoStats& s = link->stats();
  mica_device_stats r{};
  r.struct_size = out->struct_size;
  const int32_t code = s.last_code.load(std::memory_order_relaxed);
  r.last_status = code < 0 ? MICA_ERR_DEVICE : code > 0 ? MICA_WARN_DEVICE : MICA_OK;
  r.polls = s.polls.load(std::memory_order_relaxed);
  r.failures = s.failures.load(std::memory_order_relaxed);
  r.clamped = s.clamped.load(std::memory_order_relaxed);
  r.rate_hz = s.rate_hz.load(std::memory_order_relaxed);
  for (int k = 0; k < 3; ++k) {
    r.last_force[k] = s.last_force[k].load(std::memory_order_relaxed);
    r.last_raw_force[k] = s.last_raw_force[k].load(std::memory_order_relaxed);
  }
  std::memcpy(static_cast<void*>(out), &r, out->struct_size);
  return MICA_OK;
}

}  // extern "C"
