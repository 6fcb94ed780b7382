// SPDX-License-Identifier: Apache-2.0
// Shared by the targets of the two file formats a user receives from others: saved states
// (fuzz_state.cpp) and recordings (fuzz_recording.cpp), each built with fuzz_files.cpp. There: the
// small scene their seeds are saved from and recorded in, the oracle on a status, and the entry
// points: libFuzzer's, and the main of their builds without libFuzzer (tests/), which runs each
// file given as it is and with each of the target's fixed mutations, or writes the target's seeds.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_common.hpp"
#include "mica/mica.h"
#include "mica/mica_device.h"

namespace mica_fuzz {

using Bytes = std::vector<std::uint8_t>;

// What each file target defines.
namespace file_target {
// Runs one input; returns whether it was read whole (a seed this libmica does not read whole is
// stale).
bool run(const std::uint8_t* data, size_t size);
#ifdef MICA_FUZZ_REPLAY
std::vector<Bytes> mutations(const Bytes& input);  // the fixed mutations of an input
bool write_seeds(const std::string& dir);          // false when a seed cannot be written
#endif
}  // namespace file_target

// Aborts when a call building the scene fails: the seeds' scene must build.
void require_ok(const mica_world* w, mica_status s, const char* what);

// A status a reader of a file may return: a documented one but MICA_ERR_INTERNAL, and a failure
// leaves a message (on `w`, or on the thread when `w` is NULL).
void check_status(const mica_world* w, mica_status s, const char* what);

// The scene: one soft cube cell (8 nodes, 5 tets: a state of a few KB) fixed at its base, a sphere
// above its top, a grab of a top corner, and a simulated device driving a small box tool beside
// it (so that the state has a device's filter). The world's solver is one of kSolvers.
constexpr int kSolvers = 3;  // 0: MICA with the factored sweep, 1: MICA with Gauss-Seidel, 2: DIRECT
struct Scene {
  mica_world* world = nullptr;
  mica_body_id body = MICA_NULL_ID;
  mica_tool_id sphere = MICA_NULL_ID, box = MICA_NULL_ID;
  mica_lpc_id base = MICA_NULL_ID, grab = MICA_NULL_ID;
  mica_device_id device = MICA_NULL_ID;
};
mica_world* new_world(int solver);
Scene build_scene(mica_world* w);
// `steps` steps of 10 ms with the sphere 1 mm lower each (into the cell after two) and the grab
// lifted; the device polled four times before each.
void press(const Scene& s, int steps);

// Reads what a host reads of a world it did not build (mica_replay does): each object by its
// ids, the contacts, the statistics. Every call must succeed, but a body's velocities (a static
// body has none) and a device's poll (it may fail) must only return documented statuses.
void read_world(mica_world* w);

bool write_file(const std::string& path, const Bytes& bytes);
bool read_file(const std::string& path, Bytes& bytes);

}  // namespace mica_fuzz
