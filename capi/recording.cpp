// SPDX-License-Identifier: Apache-2.0
// Recording a world's session and replaying it (world/recording.hpp, world/replay.hpp).
#include "capi_internal.hpp"
#include "world/replay.hpp"

using namespace mica_capi;

struct mica_replay {
  mica_replay(mica::Replay r) : replay(std::move(r)), world(replay.settings()) {}
  mica::Replay replay;
  mica_world world;
};

MICA_API mica_status mica_world_record_start(mica_world* world, const char* path) {
  return guarded(world, "mica_world_record_start", [&] {
    require(world, "world");
    require(path, "path");
    world->world.start_recording(path);
    return MICA_OK;
  });
}

MICA_API mica_status mica_world_record_stop(mica_world* world) {
  return guarded(world, "mica_world_record_stop", [&] {
    require(world, "world");
    world->world.stop_recording();
    return MICA_OK;
  });
}

MICA_API mica_status mica_replay_open(const char* path, mica_replay** out_replay) {
  if (out_replay) *out_replay = nullptr;
  return guarded(nullptr, "mica_replay_open", [&] {
    require(path, "path");
    require(out_replay, "out_replay");
    *out_replay = new mica_replay(mica::Replay::open(path));
    return MICA_OK;
  });
}

MICA_API void mica_replay_close(mica_replay* replay) { delete replay; }

MICA_API mica_world* mica_replay_world(const mica_replay* replay) {
  return replay ? const_cast<mica_world*>(&replay->world) : nullptr;
}

MICA_API mica_status mica_replay_step(mica_replay* replay, int32_t* out_stepped) {
  if (out_stepped) *out_stepped = 0;
  mica_world* world = replay ? &replay->world : nullptr;
  const int64_t before = replay ? replay->replay.steps() : 0;
  const mica_status status = guarded(world, "mica_replay_step", [&] {
    require(replay, "replay");
    const bool stepped = replay->replay.next_step(world->world);
    return !stepped || world->world.stats().converged ? MICA_OK : MICA_WARN_NOT_CONVERGED;
  });
  if (out_stepped && replay) *out_stepped = replay->replay.steps() > before ? 1 : 0;
  return status;
}
