// SPDX-License-Identifier: Apache-2.0
// Replaying a recording (replay.hpp).
#include "world/replay.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <memory>

#include "devices/null_device.hpp"

namespace mica {

namespace {

template <class... A>
void take_all(ByteReader& in, A&... values) {
  int unused[] = {0, (take(in, values), 0)...};
  (void)unused;
}

std::string hex(uint64_t v) {
  char text[24];
  std::snprintf(text, sizeof text, "0x%016llx", static_cast<unsigned long long>(v));
  return text;
}

}  // namespace

Replay::Replay(std::vector<uint8_t> bytes, std::string name) : bytes_(std::move(bytes)), name_(std::move(name)) {
  ByteReader in(bytes_.data(), bytes_.size(), "the recording");
  char magic[sizeof kRecordingMagic];
  in.get_bytes(magic, sizeof magic, "its header");
  if (std::memcmp(magic, kRecordingMagic, sizeof magic) != 0)
    fail(Errc::Parse, name_ + " is not a libmica recording (no MICAREC1 header)");
  const uint32_t version = in.get<uint32_t>("its header"), layout = in.get<uint32_t>("its header");
  if (version != kRecordingVersion || layout != kRecordingLayout)
    fail(Errc::Parse, name_ + " is of format " + std::to_string(version) + " (layout " + std::to_string(layout) +
                          "); this libmica replays format " + std::to_string(kRecordingVersion) +
                          " recorded on a machine like this one");
  take(in, settings_);
  validate(settings_);
  at_ = in.position();
}

Replay Replay::open(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) fail(Errc::Io, "cannot open the recording '" + path + "': " + std::strerror(errno));
  std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  if (file.bad()) fail(Errc::Io, "cannot read the recording '" + path + "'");
  return Replay(std::move(bytes), "'" + path + "'");
}

void Replay::diverged(const std::string& what) const {
  fail(Errc::Diverged, name_ + ", step " + std::to_string(steps_) + ": " + what);
}

bool Replay::next_step(World& world) {
  while (bytes_.size() - at_ >= sizeof(RecordEntryHeader)) {
    RecordEntryHeader head;
    std::memcpy(&head, bytes_.data() + at_, sizeof head);
    // A host that died mid-entry leaves a partial last entry: its replay ends at the last whole one.
    if (head.size > bytes_.size() - at_ - sizeof head) break;
    if (head.kind == 0 || head.kind > kLastRecordKind)
      fail(Errc::Parse, name_ + " is corrupt: an entry of unknown kind " + std::to_string(head.kind) + " at byte " +
                            std::to_string(at_));
    ByteReader in(bytes_.data() + at_ + sizeof head, size_t(head.size), "an entry of the recording");
    at_ += sizeof head + size_t(head.size);
    const auto kind = RecordKind(head.kind);
    if (kind != RecordKind::Step) {
      try {
        apply(world, kind, in);
      } catch (const Error& e) {
        if (e.code() == Errc::Parse || e.code() == Errc::Diverged) throw;
        diverged(std::string("a call that succeeded when recorded failed: ") + e.what());
      }
      continue;
    }
    double h = 0;
    bool ok = false;
    uint64_t fingerprint = 0;
    take_all(in, h, poses_, ok, fingerprint);
    ++steps_;
    try {
      world.step_replayed(h, poses_);
    } catch (const Error& e) {
      if (ok) diverged(std::string("the step failed, it did not when recorded: ") + e.what());
      throw;  // it failed then too
    }
    if (!ok) diverged("the recorded step failed, the replayed one did not");
    if (world.fingerprint() != fingerprint)
      diverged("the step's results differ from the recording's (fingerprint " + hex(world.fingerprint()) +
               " against " + hex(fingerprint) + "): another build or machine, a time budget, or a bug");
    return true;
  }
  return false;
}

void Replay::apply(World& world, RecordKind kind, ByteReader& in) {
  Id id = 0, other = 0, created = 0;
  Vec3 a, b;
  Eigen::Quaterniond q;
  double r = 0;
  std::vector<int32_t> nodes;
  Vec3List values;
  auto check_id = [&](Id got, const char* what) {
    if (got != created)
      diverged(std::string("the replayed ") + what + " got id " + hex(got) + ", the recorded one " + hex(created));
  };
  switch (kind) {
    case RecordKind::SetGravity: take_all(in, a); world.set_gravity(a); break;
    case RecordKind::AddBody: {
      TetMesh mesh;
      BodySettings settings;
      take_all(in, mesh, settings, a, b, created);
      check_id(world.add_body(mesh, settings, a, b), "body");
      break;
    }
    case RecordKind::RemoveBody: take_all(in, id); world.remove_body(id); break;
    case RecordKind::SetNodeForces: take_all(in, id, nodes, values); world.set_node_forces(id, nodes, values); break;
    case RecordKind::SetPositions: take_all(in, id, values); world.set_positions(id, values); break;
    case RecordKind::SetVelocities: take_all(in, id, values); world.set_velocities(id, values); break;
    case RecordKind::SetMaterials: {
      std::vector<Material> materials;
      take_all(in, id, materials);
      world.set_body_materials(id, materials);
      break;
    }
    case RecordKind::AddLpc: {
      LpcSpec spec;
      take_all(in, id, nodes, spec, created);
      check_id(world.add_lpc(id, nodes, spec), "constraint");
      break;
    }
    case RecordKind::RemoveLpc: take_all(in, id); world.remove_lpc(id); break;
    case RecordKind::SetLpcVelocity: take_all(in, id, a); world.set_lpc_velocity(id, a); break;
    case RecordKind::SetLpcTargets: take_all(in, id, values); world.set_lpc_targets(id, values); break;
    case RecordKind::Grab:
      take_all(in, id, a, r, other, created);
      check_id(world.grab(id, a, r, other), "grab");
      break;
    case RecordKind::SetHandlePose: take_all(in, id, a, q); world.set_handle_pose(id, a, q); break;
    case RecordKind::AddTool: {
      Tool tool;
      take_all(in, tool, created);
      check_id(world.add_tool(tool), "tool");
      break;
    }
    case RecordKind::RemoveTool: take_all(in, id); world.remove_tool(id); break;
    case RecordKind::SetToolPose: take_all(in, id, a, q); world.set_tool_pose(id, a, q); break;
    case RecordKind::TeleportTool: take_all(in, id, a, q); world.teleport_tool(id, a, q); break;
    case RecordKind::AddDevice: {
      DeviceSettings settings;
      take_all(in, settings, created);
      check_id(world.add_device(std::make_unique<NullDevice>(), settings), "device");
      break;
    }
    case RecordKind::RemoveDevice: take_all(in, id); world.remove_device(id); break;
    case RecordKind::RestoreState: {
      std::vector<uint8_t> state;
      take_all(in, state);
      world.restore_state(state.data(), state.size());
      break;
    }
    case RecordKind::Step: break;  // next_step's
  }
  if (in.remaining())
    fail(Errc::Parse, name_ + " is corrupt: an entry of kind " + std::to_string(uint32_t(kind)) + " has " +
                          std::to_string(in.remaining()) + " bytes too many");
}

}  // namespace mica
