// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: mica_world_restore_state on a saved state from someone else, mutated.
//
// The input: a byte choosing the world's solver (fuzz_files.hpp's scene, of the seeds' shape),
// then the state. Before each run the state's header gets its true size and checksum (FNV-1a of
// the bytes after the header, world/state_io.cpp), so that the mutations reach what the checksum
// guards. The world is made anew for each input and pressed two steps (contacts, a factor).
//
// Oracles (a failure aborts: libFuzzer saves the input):
//  - no sanitizer report; the status is a documented one, not MICA_ERR_INTERNAL, with a message;
//  - a failed restore leaves the world exactly as it was: its saved state is the same bytes;
//  - after a restore that succeeded, the world reads (contacts, positions, forces, reactions,
//    statistics), steps (any documented status) and saves.
//
// Built with fuzz_files.cpp. Seeds: fuzz/corpus/state, written by the build without libFuzzer
// (tests/: fuzz_state_replay --write-seeds fuzz/corpus/state), which also runs them with fixed
// mutations in the test suite (fuzz/state_corpus): cuts, flipped bytes and 8-byte words set to all
// ones (a count blown up).
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/byte_stream.hpp"
#include "fuzz_files.hpp"

namespace {

using mica_fuzz::Bytes;

// world/state_io.cpp's header: magic (8), version (4), layout (4), size (8), checksum (8).
constexpr size_t kHeaderBytes = 32, kSizeAt = 16, kChecksumAt = 24;

Bytes save(mica_world* w) {
  size_t n = 0;
  mica_fuzz::require_ok(w, mica_world_state_size(w, &n), "mica_world_state_size");
  Bytes state(n);
  mica_fuzz::require_ok(w, mica_world_save_state(w, state.data(), n), "mica_world_save_state");
  return state;
}

}  // namespace

namespace mica_fuzz::file_target {

// Read whole: restored.
bool run(const std::uint8_t* data, size_t size) {
  if (size == 0) return false;
  Bytes state(data + 1, data + size);
  if (state.size() >= kHeaderBytes) {
    const std::uint64_t bytes = state.size(), sum = mica::fnv1a(state.data() + kHeaderBytes, state.size() - kHeaderBytes);
    std::memcpy(&state[kSizeAt], &bytes, sizeof bytes);
    std::memcpy(&state[kChecksumAt], &sum, sizeof sum);
  }
  const mica_fuzz::Scene s = mica_fuzz::build_scene(mica_fuzz::new_world(data[0] % mica_fuzz::kSolvers));
  mica_fuzz::press(s, 2);
  const Bytes before = save(s.world);
  const mica_status status = mica_world_restore_state(s.world, state.data(), state.size());
  mica_fuzz::check_status(s.world, status, "mica_world_restore_state");
  if (status < 0) {
    if (save(s.world) != before)
      mica_fuzz::bug(std::string("a failed restore changed the world: ") + mica_world_last_error(s.world));
  } else {
    mica_fuzz::read_world(s.world);
    mica_fuzz::check_status(s.world, mica_step(s.world, 0.01), "mica_step after a restore");
    save(s.world);
  }
  mica_world_destroy(s.world);
  return status >= 0;
}

#ifdef MICA_FUZZ_REPLAY
// The fixed mutations of an input (a solver byte, then a state): cuts, and at 64 places a flipped
// byte and an 8-byte word of all ones.
std::vector<Bytes> mutations(const Bytes& input) {
  std::vector<Bytes> out;
  for (size_t cut : {size_t(1), size_t(1 + 16), size_t(kHeaderBytes), size_t(1 + kHeaderBytes), input.size() / 2,
                     input.size() - 1})
    if (cut < input.size()) out.emplace_back(input.begin(), input.begin() + std::ptrdiff_t(cut));
  const size_t stride = input.size() / 64 + 1;
  for (size_t at = 1 + kHeaderBytes; at < input.size(); at += stride) {
    out.push_back(input);
    out.back()[at] ^= 0x5a;
    if (at + 8 > input.size()) continue;
    out.push_back(input);
    std::memset(&out.back()[at], 0xff, 8);
  }
  return out;
}

// A state of each solver's world, pressed into the cell, and one at rest (no contacts).
bool write_seeds(const std::string& dir) {
  bool ok = true;
  for (int solver = 0; solver < mica_fuzz::kSolvers; ++solver) {
    const mica_fuzz::Scene s = mica_fuzz::build_scene(mica_fuzz::new_world(solver));
    const auto write = [&](const char* name) {
      Bytes seed = save(s.world);
      seed.insert(seed.begin(), std::uint8_t(solver));
      ok = mica_fuzz::write_file(dir + "/solver" + std::to_string(solver) + name, seed) && ok;
    };
    write("_rest");
    mica_fuzz::press(s, 4);
    write("_pressed");
    mica_world_destroy(s.world);
  }
  return ok;
}
#endif

}  // namespace mica_fuzz::file_target
