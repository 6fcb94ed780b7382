// SPDX-License-Identifier: Apache-2.0
// A recording of what the host fed a world, and how each thing is written and read back.
// The file: a header (magic "MICAREC1", format version, layout marker, the world's settings),
// then entries in call order, each a kind, its payload's size and the payload. Creations carry the
// id they returned (a replay checks it gets the same one); a step carries its time step, the poses
// its devices' tools took at its start, whether it failed, and a fingerprint of its results (the
// replay checks its own step against it). Stopping the recording writes an end entry with the
// number of steps (format 2; format 1, libmica 0.6's, has none): a file without it was cut short.
// Write and read of each type sit side by side below, so that the two cannot drift apart.
#pragma once
#include <cstdio>
#include <string>
#include <vector>

#include "core/byte_stream.hpp"
#include "world/world.hpp"

namespace mica {

enum class RecordKind : uint32_t {
  SetGravity = 1, AddBody, RemoveBody, SetNodeForces, SetPositions, SetVelocities, SetMaterials,
  AddLpc, RemoveLpc, SetLpcVelocity, SetLpcTargets, Grab, SetHandlePose,
  AddTool, RemoveTool, SetToolPose, AddDevice, RemoveDevice, RestoreState, Step, End,
  TeleportTool, RemoveTets, Cut, SetCuttingResistance, SetBlade
};
constexpr uint32_t kLastRecordKind = uint32_t(RecordKind::SetBlade);

constexpr char kRecordingMagic[8] = {'M', 'I', 'C', 'A', 'R', 'E', 'C', '1'};
constexpr uint32_t kRecordingVersion = 2;            // 2: the end entry, tool teleports, tet removals, cuts
constexpr uint32_t kRecordingVersionWithoutEnd = 1;  // libmica 0.6's, still replayed

// What precedes each entry's payload in the file.
struct RecordEntryHeader {
  uint32_t kind;      // RecordKind
  uint32_t reserved;  // zero
  uint64_t size;      // bytes of the payload that follows
};

// Writes the entries to a file. A write that fails is kept as the recording's error and ends the
// recording (the world's calls go on succeeding; no end entry follows); stop() reports it.
class Recorder {
 public:
  // Opens (truncates) `path` and writes the header; throws Error(Io) naming the path.
  Recorder(const std::string& path, const WorldSettings& settings);
  // Ends the recording as stop() does, reporting nothing.
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Appends an entry. Never throws: the call that made it has already changed the world.
  template <class... A>
  void write(RecordKind kind, const A&... args) noexcept {
    try {
      ByteWriter payload;
      int unused[] = {0, (put(payload, args), 0)...};
      (void)unused;
      append(kind, payload.bytes());
    } catch (...) {
      if (error_.empty()) error_ = "out of memory while recording";
    }
  }
  // Writes the end entry, flushes and closes; throws Error(Io) when a write failed since the start.
  void stop();

 private:
  void append(RecordKind kind, const std::vector<uint8_t>& payload);
  bool close() noexcept;  // writes the end entry and closes the file; false when fclose failed
  std::string path_;
  std::FILE* file_ = nullptr;
  std::string error_;  // the first write error
  int64_t steps_ = 0;  // step entries written
};

// --- How each value is written (put) and read (take). -------------------------------------------
template <class T>
void put(ByteWriter& out, const T& value) { out.put(value); }
template <class T>
void take(ByteReader& in, T& value) { value = in.get<T>("an entry"); }

inline void put(ByteWriter& out, bool value) { out.put(uint8_t(value)); }
inline void take(ByteReader& in, bool& value) { value = in.get<uint8_t>("an entry") != 0; }

template <class T, class A>
void put(ByteWriter& out, const std::vector<T, A>& items) { out.put_vector(items); }
template <class T, class A>
void take(ByteReader& in, std::vector<T, A>& items) { in.get_vector(items, "an entry"); }

inline void put(ByteWriter& out, const TetMesh& m) {
  put(out, m.nodes), put(out, m.tets), put(out, m.regions);
}
inline void take(ByteReader& in, TetMesh& m) { take(in, m.nodes), take(in, m.tets), take(in, m.regions); }

inline void put(ByteWriter& out, const BodySettings& s) {
  put(out, s.material), put(out, s.rayleigh_alpha), put(out, s.rayleigh_beta), put(out, int32_t(s.mass));
  put(out, uint8_t(s.model)), put(out, s.is_static);
}
inline void take(ByteReader& in, BodySettings& s) {
  int32_t mass = 0;
  take(in, s.material), take(in, s.rayleigh_alpha), take(in, s.rayleigh_beta), take(in, mass);
  uint8_t model = 0;  // 0 linear, 1 co-rotational (the flag before 0.8), 2 neo-Hookean
  take(in, model), take(in, s.is_static);
  s.mass = MassKind(mass);
  s.model = model == 2 ? ElasticModel::NeoHookean : model ? ElasticModel::Corotational : ElasticModel::Linear;
}

inline void put(ByteWriter& out, const LpcSpec& s) {
  put(out, int32_t(s.kind)), put(out, s.directions[0]), put(out, s.directions[1]), put(out, s.velocity);
}
inline void take(ByteReader& in, LpcSpec& s) {
  int32_t kind = 0;
  take(in, kind), take(in, s.directions[0]), take(in, s.directions[1]), take(in, s.velocity);
  s.kind = LpcKind(kind);
}

// A tool as the host made it: its model and its pose (prepare_tool_shape derives the rest again).
inline void put(ByteWriter& out, const Tool& t) {
  put(out, int32_t(t.shape)), put(out, t.radius), put(out, t.half_length), put(out, t.half_extents);
  put(out, t.plane_normal), put(out, t.hull_points), put(out, t.margin), put(out, t.friction);
  put(out, t.position), put(out, t.orientation);
}
inline void take(ByteReader& in, Tool& t) {
  int32_t shape = 0;
  take(in, shape), take(in, t.radius), take(in, t.half_length), take(in, t.half_extents);
  take(in, t.plane_normal), take(in, t.hull_points), take(in, t.margin), take(in, t.friction);
  take(in, t.position), take(in, t.orientation);
  t.shape = ToolShape(shape);
}

inline void put(ByteWriter& out, const DeviceSettings& s) {
  put(out, s.tool), put(out, s.lpc), put(out, s.scale), put(out, s.offset), put(out, s.rotation), put(out, int32_t(s.mode));
  put(out, s.filter_window), put(out, s.filter_restart_on_contact), put(out, s.safety);
  put(out, s.coupling_stiffness), put(out, s.coupling_damping);
}
inline void take(ByteReader& in, DeviceSettings& s) {
  int32_t mode = 0;
  take(in, s.tool), take(in, s.lpc), take(in, s.scale), take(in, s.offset), take(in, s.rotation), take(in, mode);
  take(in, s.filter_window), take(in, s.filter_restart_on_contact), take(in, s.safety);
  take(in, s.coupling_stiffness), take(in, s.coupling_damping);
  s.mode = ForceMode(mode);
}

inline void put(ByteWriter& out, const AdoptedPose& p) { put(out, p.target), put(out, p.position), put(out, p.orientation); }
inline void take(ByteReader& in, AdoptedPose& p) { take(in, p.target), take(in, p.position), take(in, p.orientation); }
inline void put(ByteWriter& out, const std::vector<AdoptedPose>& poses) {
  put(out, uint64_t(poses.size()));
  for (const AdoptedPose& p : poses) put(out, p);
}
inline void take(ByteReader& in, std::vector<AdoptedPose>& poses) {
  const uint64_t n = in.get<uint64_t>("an entry");
  if (n > in.remaining()) fail(Errc::Parse, "the recording is corrupt: " + std::to_string(n) + " device poses in one step");
  poses.resize(size_t(n));
  for (AdoptedPose& p : poses) take(in, p);
}

// Every setting a step depends on (the log callback is the host's, not the world's).
inline void put(ByteWriter& out, const WorldSettings& s) {
  put(out, s.tolerance), put(out, s.max_iterations), put(out, s.warm_start), put(out, s.pgs_sweeps);
  put(out, s.paper_norm), put(out, s.relaxation), put(out, s.refactor_interval), put(out, s.refactor_after);
  put(out, s.active_set), put(out, s.gravity), put(out, int32_t(s.solver)), put(out, int32_t(s.mica_sweep));
  put(out, s.plan_all_stages), put(out, s.max_recovery_speed), put(out, s.time_budget_ms);
  put(out, s.body_contact), put(out, s.body_margin), put(out, s.body_friction), put(out, s.threads);
  put(out, s.relinearise_tolerance), put(out, s.relinearise_max);
}
inline void take(ByteReader& in, WorldSettings& s) {
  int32_t solver = 0, sweep = 0;
  take(in, s.tolerance), take(in, s.max_iterations), take(in, s.warm_start), take(in, s.pgs_sweeps);
  take(in, s.paper_norm), take(in, s.relaxation), take(in, s.refactor_interval), take(in, s.refactor_after);
  take(in, s.active_set), take(in, s.gravity), take(in, solver), take(in, sweep);
  take(in, s.plan_all_stages), take(in, s.max_recovery_speed), take(in, s.time_budget_ms);
  take(in, s.body_contact), take(in, s.body_margin), take(in, s.body_friction), take(in, s.threads);
  take(in, s.relinearise_tolerance), take(in, s.relinearise_max);
  s.solver = SolverKind(solver);
  s.mica_sweep = MicaSweep(sweep);
}
// A setting added to these structs must be added above too: their sizes are pinned here.
static_assert(sizeof(void*) != 8 || sizeof(SolverSettings) == 48, "a new solver setting: record it above");
static_assert(sizeof(void*) != 8 || sizeof(BodySettings) == 48, "a new body setting: record it above");
static_assert(sizeof(void*) != 8 || sizeof(LpcSpec) == 80, "a new constraint setting: record it above");
static_assert(sizeof(void*) != 8 || sizeof(DeviceSettings) == 144, "a new device setting: record it above");
// ToolModel::blade is recorded as its own entry (SetBlade), so that 0.7 recordings still read.
static_assert(sizeof(void*) != 8 || sizeof(ToolModel) == 160, "a new tool field: record it above");

}  // namespace mica
