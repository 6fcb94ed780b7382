// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: mica_replay_open and mica_replay_step on a recording from someone else,
// mutated: bytes flipped, the file cut, an entry's size blown up.
//
// The input is the file. Before each run the recorded settings are made cheap to step (at most
// 100 iterations and 10 contact sweeps a solve, 4 re-linearisations, one thread: a recording may
// ask for 2^31 iterations, which is slow, not a bug); the bytes are then written to a file, which
// is opened and replayed to its end. Besides libFuzzer's mutations, a custom mutator knows the
// entries: it cuts the file at or inside an entry, blows an entry's size up or shrinks it, or
// changes its kind.
//
// Oracles (a failure aborts: libFuzzer saves the input):
//  - no sanitizer report; every status is a documented one, not MICA_ERR_INTERNAL, with a message;
//  - the replay ends: each mica_replay_step takes at least one entry or fails (a corrupt entry,
//    a cut file: then every later call fails alike);
//  - the world it built reads: ids, positions, forces, reactions, contacts, statistics.
//
// Built with fuzz_files.cpp. Seeds: fuzz/corpus/recording, written by the build without libFuzzer
// (tests/: fuzz_recording_replay --write-seeds fuzz/corpus/recording), which also runs them with
// the custom mutator's mutations at every entry in the test suite (fuzz/recording_corpus).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include "fuzz_files.hpp"
#include "world/recording.hpp"

#ifndef MICA_FUZZ_REPLAY
extern "C" size_t LLVMFuzzerMutate(std::uint8_t* data, size_t size, size_t max_size);  // libFuzzer's
#endif

namespace {

using mica_fuzz::Bytes;

// Where the recorded settings start (after the magic, the format version and the layout marker),
// and where the entries do.
constexpr size_t kSettingsAt = sizeof mica::kRecordingMagic + 8;
size_t entries_at() {
  mica::ByteWriter settings;
  mica::put(settings, mica::WorldSettings{});
  return kSettingsAt + settings.bytes().size();
}

// Where each entry starts, as far as the entries chain (a cut or corrupt one ends the chain).
std::vector<size_t> entries(const Bytes& b) {
  std::vector<size_t> at;
  for (size_t k = entries_at(); k + sizeof(mica::RecordEntryHeader) <= b.size();) {
    mica::RecordEntryHeader head;
    std::memcpy(&head, &b[k], sizeof head);
    if (head.size > b.size() - k - sizeof head) break;
    at.push_back(k);
    k += sizeof head + size_t(head.size);
  }
  return at;
}

// One mutation of the entry starting at `at`: `what` picks a cut at the entry or inside it, its
// size blown up (to the largest values, or one byte past the file) or shrunk, or its kind changed;
// `value` picks where or what.
void mutate_entry(Bytes& b, size_t at, unsigned what, std::uint64_t value) {
  mica::RecordEntryHeader head;
  std::memcpy(&head, &b[at], sizeof head);
  const std::uint64_t past = b.size() - at - sizeof head + 1;
  switch (what % 6) {
    case 0: b.resize(at); return;
    case 1: b.resize(at + 1 + size_t(value % (sizeof head + head.size))); return;
    case 2: head.size = value % 2 ? ~std::uint64_t(0) : std::uint64_t(1) << 63; break;
    case 3: head.size = past; break;
    case 4: head.size = head.size ? value % head.size : 0; break;
    case 5: head.kind = std::uint32_t(value % (mica::kLastRecordKind + 2)); break;
  }
  std::memcpy(&b[at], &head, sizeof head);
}

// A recording may ask for any number of iterations a step: cheap settings keep each run short.
void cap_settings(Bytes& b) {
  if (b.size() < entries_at()) return;
  mica::ByteReader in(b.data() + kSettingsAt, b.size() - kSettingsAt, "the recording");
  mica::WorldSettings s;
  mica::take(in, s);
  s.max_iterations = std::min(s.max_iterations, 100);
  s.pgs_sweeps = std::min(s.pgs_sweeps, 10);
  s.relinearise_max = std::min(s.relinearise_max, 4);
  s.threads = 1;
  mica::ByteWriter out;
  mica::put(out, s);
  std::memcpy(b.data() + kSettingsAt, out.bytes().data(), out.bytes().size());
}

const std::string& scratch_file() {
  static const std::string path = std::string(std::getenv("TMPDIR") ? std::getenv("TMPDIR") : "/tmp") +
                                  "/mica_fuzz_recording_" + std::to_string(getpid()) + ".micarec";
  return path;
}

}  // namespace

namespace mica_fuzz::file_target {

// Read whole: replayed to its end (divergences allowed: a seed replays bit for bit only on the
// build that recorded it).
bool run(const std::uint8_t* data, size_t size) {
  Bytes b(data, data + size);
  cap_settings(b);
  if (!mica_fuzz::write_file(scratch_file(), b)) mica_fuzz::bug("cannot write " + scratch_file());
  mica_replay* replay = nullptr;
  const mica_status opened = mica_replay_open(scratch_file().c_str(), &replay);
  std::remove(scratch_file().c_str());
  mica_fuzz::check_status(nullptr, opened, "mica_replay_open");
  if (opened < 0) {
    if (replay) mica_fuzz::bug("a failed mica_replay_open returned a replay");
    return false;
  }
  mica_world* w = mica_replay_world(replay);
  mica_status status = MICA_OK;
  int32_t stepped = 1;
  // Each call takes at least one entry (16 bytes of header) or ends the replay.
  for (size_t calls = 0;; ++calls) {
    if (calls > size / sizeof(mica::RecordEntryHeader) + 1) mica_fuzz::bug("the replay does not end");
    status = mica_replay_step(replay, &stepped);
    mica_fuzz::check_status(w, status, "mica_replay_step");
    if (status == MICA_ERR_TRUNCATED) {  // the file ends: every later call says so again
      if (stepped || mica_replay_step(replay, &stepped) != status) mica_fuzz::bug("a cut file read on");
      break;
    }
    if (status == MICA_ERR_PARSE || (status >= 0 && !stepped)) break;  // a corrupt entry, or the end
  }
  mica_fuzz::read_world(w);
  mica_replay_close(replay);
  return status >= 0;
}

#ifdef MICA_FUZZ_REPLAY
// The fixed mutations of a recording: cuts in its header, each of mutate_entry's at every entry,
// and 32 flipped bytes.
std::vector<Bytes> mutations(const Bytes& input) {
  std::vector<Bytes> out;
  for (size_t cut : {size_t(4), kSettingsAt, entries_at() - 1})
    if (cut < input.size()) out.emplace_back(input.begin(), input.begin() + std::ptrdiff_t(cut));
  for (size_t at : entries(input))
    for (unsigned what = 0; what < 6; ++what)
      for (std::uint64_t value : {0u, 7u}) {
        out.push_back(input);
        mutate_entry(out.back(), at, what, value);
      }
  const size_t stride = input.size() / 32 + 1;
  for (size_t at = 0; at < input.size(); at += stride) {
    out.push_back(input);
    out.back()[at] ^= 0x5a;
  }
  return out;
}

// Records a session into `path`: `session` makes the calls on the scene.
template <class Session>
bool record(const std::string& path, int solver, Session session) {
  mica_world* w = mica_fuzz::new_world(solver);
  mica_fuzz::require_ok(w, mica_world_record_start(w, path.c_str()), "mica_world_record_start");
  session(mica_fuzz::build_scene(w));
  const bool ok = mica_world_record_stop(w) == MICA_OK;
  mica_world_destroy(w);
  return ok;
}

// The scene pressed (each solver), a session making each recorded call once, and the pressed one
// as libmica 0.6 wrote it (format 1: no end entry).
bool write_seeds(const std::string& dir) {
  bool ok = true;
  for (int solver = 0; solver < mica_fuzz::kSolvers; ++solver)
    ok = record(dir + "/press_solver" + std::to_string(solver), solver,
                [](const mica_fuzz::Scene& s) { mica_fuzz::press(s, 6); }) && ok;
  ok = record(dir + "/every_call", 1, [](const mica_fuzz::Scene& s) {
    mica_world* w = s.world;
    const double g[3] = {0, -5, 0}, q[4] = {1, 0, 0, 0}, up[3] = {0, 0.1, 0};
    mica_fuzz::require_ok(w, mica_world_set_gravity(w, g), "mica_world_set_gravity");
    double x[8 * 3], e[5] = {2e4, 2e4, 2e4, 2e4, 2e4};
    int32_t n = 0;
    const int32_t top[2] = {6, 7};
    mica_fuzz::require_ok(w, mica_body_get_positions(w, s.body, x, 8, &n), "mica_body_get_positions");
    mica_fuzz::require_ok(w, mica_body_set_positions(w, s.body, x, 8), "mica_body_set_positions");
    std::fill(x, x + 24, 0.0);
    mica_fuzz::require_ok(w, mica_body_set_velocities(w, s.body, x, 8), "mica_body_set_velocities");
    mica_fuzz::require_ok(w, mica_body_set_node_forces(w, s.body, top, up, 1), "mica_body_set_node_forces");
    mica_fuzz::require_ok(w, mica_body_set_materials(w, s.body, e, nullptr, nullptr, 5), "mica_body_set_materials");
    mica_lpc_def plane = mica_lpc_def_default();
    plane.kind = MICA_LPC_PLANE;
    mica_lpc_id slide;
    mica_fuzz::require_ok(w, mica_add_lpc(w, s.body, top, 2, &plane, &slide), "mica_add_lpc");
    mica_fuzz::require_ok(w, mica_lpc_set_velocity(w, slide, up), "mica_lpc_set_velocity");
    mica_fuzz::press(s, 1);
    mica_fuzz::require_ok(w, mica_lpc_remove(w, slide), "mica_lpc_remove");
    mica_fuzz::require_ok(w, mica_body_get_positions(w, s.body, x, 8, &n), "mica_body_get_positions");
    mica_fuzz::require_ok(w, mica_lpc_set_targets(w, s.base, x, 4), "mica_lpc_set_targets");
    size_t bytes = 0;
    mica_fuzz::require_ok(w, mica_world_state_size(w, &bytes), "mica_world_state_size");
    Bytes state(bytes);
    mica_fuzz::require_ok(w, mica_world_save_state(w, state.data(), bytes), "mica_world_save_state");
    mica_fuzz::press(s, 1);
    mica_fuzz::require_ok(w, mica_world_restore_state(w, state.data(), bytes), "mica_world_restore_state");
    mica_tool_def capsule = mica_tool_def_default();
    capsule.shape = MICA_TOOL_CAPSULE;
    capsule.position[1] = 0.2;
    mica_tool_id tool;
    mica_fuzz::require_ok(w, mica_tool_create(w, &capsule, &tool), "mica_tool_create");
    mica_fuzz::require_ok(w, mica_tool_set_pose(w, tool, up, q), "mica_tool_set_pose");
    mica_fuzz::press(s, 1);
    mica_fuzz::require_ok(w, mica_tool_destroy(w, tool), "mica_tool_destroy");
    mica_fuzz::require_ok(w, mica_device_destroy(w, s.device), "mica_device_destroy");
    const int32_t corner_tet = 0;
    mica_fuzz::require_ok(w, mica_body_remove_tets(w, s.body, &corner_tet, 1, nullptr), "mica_body_remove_tets");
    mica_fuzz::require_ok(w, mica_step(w, 0.01), "mica_step");
    mica_fuzz::require_ok(w, mica_body_destroy(w, s.body), "mica_body_destroy");
    mica_fuzz::require_ok(w, mica_step(w, 0.01), "mica_step");
  }) && ok;
  // Format 1: the end entry (a header and the step count) cut off, the version set to 1.
  Bytes old;
  ok = mica_fuzz::read_file(dir + "/press_solver0", old) && ok;
  if (old.size() > entries_at() + sizeof(mica::RecordEntryHeader) + 8) {
    old.resize(old.size() - sizeof(mica::RecordEntryHeader) - 8);
    std::memcpy(&old[sizeof mica::kRecordingMagic], &mica::kRecordingVersionWithoutEnd, 4);
    ok = mica_fuzz::write_file(dir + "/press_format1", old) && ok;
  }
  return ok;
}
#endif

}  // namespace mica_fuzz::file_target

#ifndef MICA_FUZZ_REPLAY
// One in three mutations is mutate_entry's at a random entry; the others are libFuzzer's.
extern "C" size_t LLVMFuzzerCustomMutator(std::uint8_t* data, size_t size, size_t max_size, unsigned seed) {
  std::minstd_rand random(seed);
  Bytes b(data, data + size);
  const std::vector<size_t> at = entries(b);
  if (random() % 3 != 0 || at.empty()) return LLVMFuzzerMutate(data, size, max_size);
  mutate_entry(b, at[random() % at.size()], unsigned(random()), random());
  size = std::min(b.size(), max_size);
  std::memcpy(data, b.data(), size);
  return size;
}
#endif
