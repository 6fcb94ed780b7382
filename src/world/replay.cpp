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
  if (bytes_.size() < sizeof kRecordingMagic || std::memcmp(bytes_.data(), kRecordingMagic, sizeof kRecordingMagic) != 0)
    fail(Errc::Parse, name_ + " is not a libmica recording (no MICAREC1 header)");
  ByteReader in(bytes_.data() + sizeof kRecordingMagic, bytes_.size() - sizeof kRecordingMagic, "the recording");
  const auto header = [&](auto& value) {
    if (in.remaining() < sizeof value) cut_short("inside its header");
    take(in, value);
  };
  uint32_t layout = 0;
  header(version_);
  header(layout);
  if ((version_ != kRecordingVersion && version_ != kRecordingVersionWithoutEnd) || layout != kByteLayout)
    fail(Errc::Parse, name_ + " is of format " + std::to_string(version_) + " (layout " + std::to_string(layout) +
                          "); this libmica replays formats " + std::to_string(kRecordingVersionWithoutEnd) + " to " +
                          std::to_string(kRecordingVersion) + " recorded on a machine like this one");
  try {
    take(in, settings_);
  } catch (const Error&) {
    cut_short("inside its header");  // reading plain values fails only where the bytes end
  }
  validate(settings_);
  at_ = sizeof kRecordingMagic + in.position();
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

void Replay::cut_short(const std::string& where) const {
  fail(Errc::Truncated, name_ + " was cut short after " + std::to_string(steps_) + " steps: it ends at byte " +
                            std::to_string(bytes_.size()) + ", " + where +
                            ", without the end entry that stopping a recording writes");
}

bool Replay::next_step(World& world) {
  while (!ended_) {
    const size_t left = bytes_.size() - at_;
    RecordEntryHeader head{};
    if (left >= sizeof head) std::memcpy(&head, bytes_.data() + at_, sizeof head);
    if (left < sizeof head || head.size > left - sizeof head) {
      // The file ends inside an entry (a host that died mid-entry) or, when left is 0, between two.
      if (version_ == kRecordingVersionWithoutEnd) return false;  // 0.6's end: the file's
      cut_short(left == 0 ? "after a whole entry" : "inside an entry");
    }
    if (head.kind == 0 || head.kind > kLastRecordKind)
      fail(Errc::Parse, name_ + " is corrupt: an entry of unknown kind " + std::to_string(head.kind) + " at byte " +
                            std::to_string(at_));
    ByteReader in(bytes_.data() + at_ + sizeof head, size_t(head.size), "an entry of the recording");
    at_ += sizeof head + size_t(head.size);
    const auto kind = RecordKind(head.kind);
    if (kind == RecordKind::End) {
      end(in);
      return false;
    }
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

void Replay::end(ByteReader& in) {
  int64_t steps = 0;
  take(in, steps);
  if (in.remaining() || steps != steps_)
    fail(Errc::Parse, name_ + " is corrupt: its end entry " +
                          (in.remaining() ? "is " + std::to_string(in.remaining()) + " bytes too long"
                                          : "counts " + std::to_string(steps) + " steps, " + std::to_string(steps_) +
                                                " were replayed"));
  if (at_ != bytes_.size())
    fail(Errc::Parse, name_ + " is corrupt: " + std::to_string(bytes_.size() - at_) + " bytes follow its end entry");
  ended_ = true;
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
    case RecordKind::RemoveTets: take_all(in, id, nodes); world.remove_tets(id, nodes); break;
    case RecordKind::Cut: take_all(in, id, values); world.cut(id, values); break;
    case RecordKind::SetCuttingResistance: {
      std::vector<double> resistance;
      take_all(in, id, resistance);
      world.set_cutting_resistance(id, resistance);
      break;
    }
    case RecordKind::SetBlade: {
      bool blade = false;
      take_all(in, id, blade);
      world.set_tool_blade(id, blade);
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
    case RecordKind::Step:
    case RecordKind::End: break;  // next_step's
  }
  if (in.remaining())
    fail(Errc::Parse, name_ + " is corrupt: an entry of kind " + std::to_string(uint32_t(kind)) + " has " +
                          std::to_string(in.remaining()) + " bytes too many");
}

}  // namespace mica
