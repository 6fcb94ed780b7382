// SPDX-License-Identifier: Apache-2.0
// Saving and restoring a world's dynamic state (World::save_state, restore_state): everything a
// later step depends on beyond what the host built, so that restoring and stepping reproduces the
// original run bit for bit. The layout:
//   header   magic "MICASTAT", format version, layout marker (byte order and double size),
//            total size, FNV-1a checksum of what follows the header
//   shape    the world's shape: per body its node and tet counts and kind, per tool its shape, per
//            constraint its body and node count, per device its filter window, the solver
//   world    step statistics (the step counter), the re-linearisation's energy debt, the warm-start
//            impulses by row key, the last step's contacts, rows and impulses (the contacts readout),
//            pairs of bodies created overlapping
//   bodies   positions, velocities (now and at the last step's start), node forces, contact
//            impulses, the rotations a step hands the next, and what the solver keeps for the body
//            (its lagged factor: VelocitySolver::save_body)
//   tools    poses (now and at the last step), velocities, force, torque, contact count, stiffness
//   lpcs     prescribed velocity, reaction, handle (targets or grab offsets, pose, tool)
//   devices  the force filter (moving average) and the last force sent
// A restore reads and checks all of it before it changes anything; the solver's part (factoring the
// saved systems again) is the last step that can throw, and what follows only moves values in.
// Not saved, because they do not change a later step: timings aside from the counters, the per-step
// work arrays, and a linear body's assembled matrix (reassembled: the same bits).
#include <algorithm>
#include <cstddef>
#include <cstring>

#include "core/byte_stream.hpp"
#include "world/recording.hpp"
#include "world/world.hpp"

namespace mica {

namespace {

constexpr char kMagic[8] = {'M', 'I', 'C', 'A', 'S', 'T', 'A', 'T'};
constexpr uint32_t kFormatVersion = 4;  // 2: the contacts' curvature impulses; 3: v_previous; 4: solves, factorizations
// Byte order and the size of a double: a state is read back only where it was written.
constexpr uint32_t kLayout = 0x01020304u ^ uint32_t(sizeof(double) << 24);

struct Header {
  char magic[8];
  uint32_t version;
  uint32_t layout;
  uint64_t size;      // bytes, header included
  uint64_t checksum;  // FNV-1a of the bytes after the header
};
constexpr size_t kHeaderSize = sizeof(Header);

}  // namespace

// The world's shape: what a state must match to be restored.
struct StateShape {
  struct BodyShape {
    int32_t nodes, tets;
    uint8_t is_static, corotational;
    uint8_t unused[2] = {};
  };
  std::vector<BodyShape> bodies;
  std::vector<int32_t> tools;                       // ToolShape
  std::vector<std::pair<int32_t, int32_t>> lpcs;    // body (order), node count
  std::vector<int32_t> devices;                     // filter window
  int32_t solver = 0, sweep = 0;

  void write(ByteWriter& out) const {
    out.put_vector(bodies);
    out.put_vector(tools);
    out.put_vector(lpcs);
    out.put_vector(devices);
    out.put(solver);
    out.put(sweep);
  }
  void read(ByteReader& in) {
    in.get_vector(bodies, "the world's shape");
    in.get_vector(tools, "the world's shape");
    in.get_vector(lpcs, "the world's shape");
    in.get_vector(devices, "the world's shape");
    solver = in.get<int32_t>("the world's shape");
    sweep = in.get<int32_t>("the world's shape");
  }
};

namespace {

using Shape = StateShape;

std::string count_text(size_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

// Why a state of shape `saved` cannot go into a world of shape `here` (empty: it can).
std::string shape_difference(const Shape& saved, const Shape& here) {
  const std::string refuse = "the state was saved from a world of another shape: ";
  if (saved.bodies.size() != here.bodies.size())
    return refuse + "it has " + count_text(saved.bodies.size(), "body", "bodies") + ", this world " +
           count_text(here.bodies.size(), "body", "bodies");
  for (size_t k = 0; k < saved.bodies.size(); ++k) {
    const Shape::BodyShape &a = saved.bodies[k], &b = here.bodies[k];
    if (a.nodes != b.nodes || a.tets != b.tets)
      return refuse + "its body " + std::to_string(k) + " (in creation order) has " + std::to_string(a.nodes) +
             " nodes and " + std::to_string(a.tets) + " tets, this world's " + std::to_string(b.nodes) + " and " +
             std::to_string(b.tets);
    if (a.is_static != b.is_static || a.corotational != b.corotational)
      return refuse + "its body " + std::to_string(k) + " is of another kind (static or dynamic, co-rotational or linear)";
  }
  if (saved.tools != here.tools)
    return refuse + "it has " + count_text(saved.tools.size(), "tool", "tools") + ", this world " +
           count_text(here.tools.size(), "tool", "tools") + (saved.tools.size() == here.tools.size() ? " of other shapes" : "");
  if (saved.lpcs != here.lpcs)
    return refuse + "it has " + count_text(saved.lpcs.size(), "constraint", "constraints") + ", this world " +
           count_text(here.lpcs.size(), "constraint", "constraints") +
           (saved.lpcs.size() == here.lpcs.size() ? " on other bodies or node counts" : "");
  if (saved.devices != here.devices)
    return refuse + "it has " + count_text(saved.devices.size(), "device", "devices") + ", this world " +
           count_text(here.devices.size(), "device", "devices") +
           (saved.devices.size() == here.devices.size() ? " with other filter windows" : "");
  if (saved.solver != here.solver || saved.sweep != here.sweep)
    return refuse + "it was saved with another velocity solver (solver " + std::to_string(saved.solver) + ", sweep " +
           std::to_string(saved.sweep) + "; this world: " + std::to_string(here.solver) + ", " +
           std::to_string(here.sweep) + ")";
  return {};
}

// What a restore reads for a body before it changes anything.
struct BodyData {
  Vec3List x, v, v_previous, node_forces, contact_impulse, x_end;
  uint8_t has_node_forces = 0;
  std::vector<Mat3> R, R_end;
  double u_start = 0, k_start = 0, u_end = 0;
  uint8_t u_start_known = 0;
  std::vector<uint8_t> solver;
};

struct ToolData {
  Vec3 position, previous_position, velocity, angular_velocity, force, torque;
  Eigen::Quaterniond orientation, previous_orientation;
  Mat3 stiffness;
  int32_t contact_count;
  int32_t unused = 0;
};

// A state copies these structs as bytes: a padding byte would be uninitialised, and two saves of
// one state could differ in it. Each size is the sum of its fields'.
static_assert(sizeof(StateShape::BodyShape) == 2 * 4 + 4 * 1, "BodyShape has padding");
static_assert(sizeof(ToolData) == 6 * sizeof(Vec3) + 2 * sizeof(Eigen::Quaterniond) + sizeof(Mat3) + 2 * 4,
              "ToolData has padding");
static_assert(sizeof(BodyPoint) == 6 * 4 + 3 * 8, "BodyPoint has padding");
static_assert(sizeof(Contact) == 8 + 2 * sizeof(BodyPoint) + 3 * sizeof(Vec3) + 2 * 8 + 4 * 4 + 8, "Contact has padding");
static_assert(sizeof(RowTerm) == 2 * 4 + 8, "RowTerm has padding");
static_assert(sizeof(StageStats) == 2 * 4 + 3 * 8, "StageStats has padding");
static_assert(sizeof(WorldStats) == 8 + kStageCount * sizeof(StageStats) + 2 * 8 + 4 + 2 * 1 + 2 * 1 + 2 * 4,
              "WorldStats has padding");

struct LpcData {
  Vec3 velocity, reaction;
  uint8_t has_handle = 0;
  std::unique_ptr<Handle> handle;  // made while reading: putting it in place cannot fail
};

void require(bool ok, const std::string& message) {
  if (!ok) fail(Errc::Parse, message + ": corrupt state");
}

}  // namespace

void World::state_shape(StateShape& s) const {
  std::vector<Id> body_ids;
  bodies_.for_each([&](Id id, const Body& b) {
    body_ids.push_back(id);
    s.bodies.push_back({b.fem.node_count(), int32_t(b.tets.size()), uint8_t(b.settings.is_static),
                        uint8_t(b.settings.corotational)});
  });
  tools_.for_each([&](Id, const Tool& t) { s.tools.push_back(int32_t(t.shape)); });
  lpcs_.for_each([&](Id, const Lpc& c) {
    const int32_t body = int32_t(std::find(body_ids.begin(), body_ids.end(), c.body) - body_ids.begin());
    s.lpcs.emplace_back(body, int32_t(c.nodes.size()));
  });
  devices_.for_each([&](Id, const DeviceLink& link) { s.devices.push_back(link.settings().filter_window); });
  s.solver = int32_t(settings_.solver);
  s.sweep = int32_t(settings_.mica_sweep);
}

std::vector<uint8_t> World::save_state() const {
  devices_.for_each([&](Id, const DeviceLink& link) {
    if (link.servo_running())
      fail(Errc::WrongState, "a device's servo loop is running: stop it (mica_device_stop) before saving the state");
  });
  ByteWriter out;
  out.put_bytes(std::string(kHeaderSize, '\0').data(), kHeaderSize);  // filled in at the end

  StateShape shape;
  state_shape(shape);
  shape.write(out);

  // The world.
  out.put(stats_);
  out.put(debt_);
  std::vector<std::pair<uint64_t, double>> warm(warm_start_.begin(), warm_start_.end());
  std::sort(warm.begin(), warm.end());
  out.put_vector(warm);
  out.put_vector(contacts_);
  out.put_vector(rows_.start);
  out.put_vector(rows_.terms);
  out.put_vector(rows_.direction);
  out.put_vector(rows_.bias);
  out.put_vector(rows_.normal_of);
  out.put_vector(rows_.mu);
  out.put_vector(rows_.contact);
  out.put_vector(rows_.key);
  out.put_vector(lambda_);
  out.put_vector(curvature_impulse_);
  out.put_vector(step_bodies_);
  out.put_vector(step_tools_);
  out.put_vector(overlapping_);

  bodies_.for_each([&](Id, const Body& b) {
    out.put_vector(b.x);
    out.put_vector(b.v);
    out.put_vector(b.v_previous);
    out.put_vector(b.node_forces);
    out.put(uint8_t(b.has_node_forces));
    out.put_vector(b.contact_impulse);
    out.put_vector(b.R);
    out.put_vector(b.R_end);
    out.put_vector(b.x_end);
    out.put(b.relin.u_start);
    out.put(b.relin.k_start);
    out.put(b.relin.u_end);
    out.put(uint8_t(b.relin.u_start_known));
    ByteWriter solver;
    solver_->save_body(b.key, solver);
    out.put_vector(solver.bytes());
  });
  tools_.for_each([&](Id, const Tool& t) {
    out.put(ToolData{t.position, t.previous_position, t.velocity, t.angular_velocity, t.force, t.torque,
                     t.orientation, t.previous_orientation, t.stiffness, t.contact_count});
  });
  lpcs_.for_each([&](Id, const Lpc& c) {
    out.put(c.velocity);
    out.put(c.reaction);
    out.put(uint8_t(c.handle != nullptr));
    if (!c.handle) return;
    out.put_vector(c.handle->offsets);
    out.put(c.handle->position);
    out.put(c.handle->orientation);
    out.put(c.handle->tool);
  });
  devices_.for_each([&](Id, const DeviceLink& link) {
    const DeviceLink::FilterState f = link.filter_state();
    out.put_vector(f.average.samples);
    out.put(f.average.next);
    out.put(f.average.count);
    out.put(f.average.since_resum);
    out.put(f.average.sum);
    out.put(uint8_t(f.average.in_contact));
    out.put(f.previous_force);
  });

  std::vector<uint8_t>& bytes = out.bytes();
  Header header{};
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  header.version = kFormatVersion;
  header.layout = kLayout;
  header.size = bytes.size();
  header.checksum = fnv1a(bytes.data() + kHeaderSize, bytes.size() - kHeaderSize);
  std::memcpy(bytes.data(), &header, kHeaderSize);
  return std::move(bytes);
}

void World::restore_state(const uint8_t* data, size_t size) {
  // The header.
  if (size < kHeaderSize)
    fail(Errc::Parse, "the state is " + std::to_string(size) + " bytes, shorter than its " +
                          std::to_string(kHeaderSize) + "-byte header: truncated");
  Header header;
  std::memcpy(&header, data, kHeaderSize);
  if (std::memcmp(header.magic, kMagic, sizeof kMagic) != 0)
    fail(Errc::Parse, "the buffer is not a saved libmica state (no MICASTAT header)");
  if (header.version != kFormatVersion || header.layout != kLayout)
    fail(Errc::Parse, "the state is of format " + std::to_string(header.version) + " (layout " +
                          std::to_string(header.layout) + "); this libmica reads format " +
                          std::to_string(kFormatVersion) + " written on a machine like this one");
  if (header.size != size)
    fail(Errc::Parse, "the state's header says " + std::to_string(header.size) + " bytes, the buffer has " +
                          std::to_string(size) + (size < header.size ? ": truncated" : ""));
  if (fnv1a(data + kHeaderSize, size - kHeaderSize) != header.checksum)
    fail(Errc::Parse, "the state's checksum does not match its contents: corrupt");
  ByteReader in(data + kHeaderSize, size - kHeaderSize);

  // The shape.
  Shape saved;
  saved.read(in);
  Shape here;
  state_shape(here);
  std::vector<const Body*> bodies;
  bodies_.for_each([&](Id, const Body& b) { bodies.push_back(&b); });
  devices_.for_each([&](Id, const DeviceLink& link) {
    if (link.servo_running())
      fail(Errc::WrongState, "a device's servo loop is running: stop it (mica_device_stop) before restoring a state");
  });
  const std::string difference = shape_difference(saved, here);
  if (!difference.empty()) fail(Errc::InvalidArgument, difference);

  // The world.
  // The statistics' flags are bools: checked as bytes first (a bool holding 2 is undefined behaviour).
  uint8_t raw[sizeof(WorldStats)];
  in.get_bytes(raw, sizeof raw, "the statistics");
  require(raw[offsetof(WorldStats, converged)] <= 1 && raw[offsetof(WorldStats, out_of_time)] <= 1,
          "the statistics' flags are not 0 or 1");
  WorldStats stats;
  std::memcpy(static_cast<void*>(&stats), raw, sizeof raw);
  const decltype(debt_) debt = in.get<decltype(debt_)>("the energy debt");
  std::vector<std::pair<uint64_t, double>> warm;
  in.get_vector(warm, "the warm-start impulses");
  std::vector<Contact> contacts;
  ContactRows rows;
  std::vector<double> lambda;
  Vec3List curvature_impulse;
  std::vector<Id> step_bodies, step_tools;
  std::vector<std::pair<Id, Id>> overlapping;
  in.get_vector(contacts, "the contacts");
  in.get_vector(rows.start, "the contact rows");
  in.get_vector(rows.terms, "the contact rows");
  in.get_vector(rows.direction, "the contact rows");
  in.get_vector(rows.bias, "the contact rows");
  in.get_vector(rows.normal_of, "the contact rows");
  in.get_vector(rows.mu, "the contact rows");
  in.get_vector(rows.contact, "the contact rows");
  in.get_vector(rows.key, "the contact rows");
  in.get_vector(lambda, "the contact impulses");
  in.get_vector(curvature_impulse, "the contact impulses");
  in.get_vector(step_bodies, "the step's bodies");
  in.get_vector(step_tools, "the step's tools");
  in.get_vector(overlapping, "the overlapping bodies");
  // What the contacts readout dereferences must be in range.
  const size_t nr = rows.direction.size();
  // Before the first step the rows have no start offsets at all.
  require((rows.start.size() == nr + 1 || (nr == 0 && rows.start.empty())) && rows.bias.size() == nr && rows.normal_of.size() == nr && rows.mu.size() == nr &&
              rows.contact.size() == nr && rows.key.size() == nr && lambda.size() == nr,
          "the contact rows disagree in length");
  require(curvature_impulse.size() == contacts.size(), "the contacts disagree in length");
  for (Id id : step_bodies) require(bodies_.find(id) && bodies_.find(id)->is_dynamic(), "a step body is not in this world");
  for (Id id : step_tools) require(tools_.find(id) != nullptr, "a step tool is not in this world");
  for (size_t r = 0; r < nr; ++r)
    require(rows.contact[r] >= 0 && size_t(rows.contact[r]) < contacts.size() && rows.start[r] <= rows.start[r + 1] &&
                size_t(rows.start[r + 1]) <= rows.terms.size() && rows.normal_of[r] < int32_t(r),
            "a contact row is out of range");
  auto point_ok = [&](const BodyPoint& p) {
    if (p.count == 0) return true;
    if (p.count < 0 || p.count > 3 || p.body < 0 || size_t(p.body) >= step_bodies.size()) return false;
    const int32_t n = bodies_.find(step_bodies[size_t(p.body)])->fem.node_count();
    for (int k = 0; k < p.count; ++k)
      if (p.nodes[k] < 0 || p.nodes[k] >= n) return false;
    return true;
  };
  for (const Contact& c : contacts)
    require(point_ok(c.a) && c.a.count > 0 && point_ok(c.b) && c.tool < int32_t(step_tools.size()),
            "a contact names a body, node or tool out of range");
  for (const RowTerm& t : rows.terms)
    require(t.body >= 0 && size_t(t.body) < step_bodies.size() && t.node >= 0 &&
                t.node < bodies_.find(step_bodies[size_t(t.body)])->fem.node_count(),
            "a contact row names a body or node out of range");

  // The bodies.
  std::vector<BodyData> body_data(bodies.size());
  std::vector<VelocitySolver::SavedBody> solver_bodies;
  for (size_t k = 0; k < bodies.size(); ++k) {
    const Body& b = *bodies[k];
    BodyData& d = body_data[k];
    const size_t n = size_t(b.fem.node_count()), e = b.R.size();
    in.get_vector(d.x, "a body's positions");
    in.get_vector(d.v, "a body's velocities");
    in.get_vector(d.v_previous, "a body's last velocities");
    in.get_vector(d.node_forces, "a body's node forces");
    d.has_node_forces = in.get<uint8_t>("a body's node forces");
    in.get_vector(d.contact_impulse, "a body's contact impulses");
    in.get_vector(d.R, "a body's rotations");
    in.get_vector(d.R_end, "a body's rotations");
    in.get_vector(d.x_end, "a body's end positions");
    d.u_start = in.get<double>("a body's energies");
    d.k_start = in.get<double>("a body's energies");
    d.u_end = in.get<double>("a body's energies");
    d.u_start_known = in.get<uint8_t>("a body's energies");
    in.get_vector(d.solver, "a body's solver state");
    require(d.x.size() == n && d.v.size() == n && d.v_previous.size() == n && d.node_forces.size() == n &&
                d.contact_impulse.size() == n && d.R.size() == e && d.R_end.size() == e && (d.x_end.empty() || d.x_end.size() == n),
            "a body's arrays do not match its node or tet count");
    require(flat(d.x).allFinite() && flat(d.v).allFinite() && flat(d.v_previous).allFinite() &&
                flat(d.node_forces).allFinite(),
            "a body's positions, velocities or forces are not finite");
    solver_bodies.push_back({b.key, &b.fem, d.solver.data(), d.solver.size()});
  }
  std::vector<ToolData> tool_data;
  tools_.for_each([&](Id, const Tool&) { tool_data.push_back(in.get<ToolData>("a tool's state")); });
  std::vector<LpcData> lpc_data;
  lpcs_.for_each([&](Id, const Lpc& c) {
    LpcData d;
    d.velocity = in.get<Vec3>("a constraint's state");
    d.reaction = in.get<Vec3>("a constraint's state");
    d.has_handle = in.get<uint8_t>("a constraint's state");
    if (d.has_handle) {
      d.handle = std::make_unique<Handle>();
      Handle& h = *d.handle;
      in.get_vector(h.offsets, "a constraint's handle");
      h.position = in.get<Vec3>("a constraint's handle");
      h.orientation = in.get<Eigen::Quaterniond>("a constraint's handle");
      h.tool = in.get<uint64_t>("a constraint's handle");
      require(h.offsets.size() == c.nodes.size(), "a constraint's handle does not match its node count");
      if (h.tool && !tools_.find(h.tool))
        fail(Errc::InvalidArgument, "the state has a grab following a tool this world does not have (id " +
                                        std::to_string(h.tool) + ")");
    }
    lpc_data.push_back(std::move(d));
  });
  std::vector<DeviceLink::FilterState> device_data;
  devices_.for_each([&](Id, const DeviceLink& link) {
    DeviceLink::FilterState f;
    in.get_vector(f.average.samples, "a device's filter");
    f.average.next = in.get<int32_t>("a device's filter");
    f.average.count = in.get<int32_t>("a device's filter");
    f.average.since_resum = in.get<int32_t>("a device's filter");
    f.average.sum = in.get<Vec3>("a device's filter");
    f.average.in_contact = in.get<uint8_t>("a device's filter") != 0;
    f.previous_force = in.get<Vec3>("a device's filter");
    const int32_t n = link.settings().filter_window;
    require(f.average.samples.size() == size_t(n) && f.average.next >= 0 && f.average.next < n &&
                f.average.count >= 0 && f.average.count <= n && f.average.since_resum >= 0,
            "a device's filter does not match its window");
    device_data.push_back(std::move(f));
  });
  if (in.remaining()) fail(Errc::Parse, "the state has " + std::to_string(in.remaining()) + " bytes past its end: corrupt");

  // The solver's part: factors the saved systems (the last step that may throw).
  solver_->restore_bodies(solver_bodies);

  // Nothing throws from here on: values move in.
  stats_ = stats;
  debt_ = debt;
  warm_start_.clear();
  for (const auto& [key, impulse] : warm) warm_start_[key] = impulse;
  contacts_.swap(contacts);
  rows_ = std::move(rows);
  lambda_.swap(lambda);
  curvature_impulse_.swap(curvature_impulse);
  step_bodies_.swap(step_bodies);
  step_tools_.swap(step_tools);
  overlapping_.swap(overlapping);
  size_t k = 0;
  bodies_.for_each([&](Id, Body& b) {
    BodyData& d = body_data[k++];
    b.x = d.x;  // the same size: copied in place (no allocation; a positions view stays valid)
    b.v = d.v;
    b.v_previous = d.v_previous;
    b.node_forces.swap(d.node_forces);
    b.has_node_forces = d.has_node_forces != 0;
    b.contact_impulse.swap(d.contact_impulse);
    b.R.swap(d.R);
    b.R_end.swap(d.R_end);
    b.x_end.swap(d.x_end);
    b.relin.u_start = d.u_start;
    b.relin.k_start = d.k_start;
    b.relin.u_end = d.u_end;
    b.relin.u_start_known = d.u_start_known != 0;
    b.bvh.refit(b.x);
    // The solvers' factors of the current matrix are redone (the same matrix: the same bits).
    b.matrix_current = false;
    ++b.matrix_version;
  });
  k = 0;
  tools_.for_each([&](Id, Tool& t) {
    const ToolData& d = tool_data[k++];
    t.position = d.position;
    t.orientation = d.orientation;
    t.previous_position = d.previous_position;
    t.previous_orientation = d.previous_orientation;
    t.velocity = d.velocity;
    t.angular_velocity = d.angular_velocity;
    t.force = d.force;
    t.torque = d.torque;
    t.contact_count = d.contact_count;
    t.stiffness = d.stiffness;
  });
  k = 0;
  lpcs_.for_each([&](Id, Lpc& c) {
    LpcData& d = lpc_data[k++];
    c.velocity = d.velocity;
    c.reaction = d.reaction;
    c.handle = std::move(d.handle);
  });
  k = 0;
  devices_.for_each([&](Id, DeviceLink& link) { link.set_filter_state(device_data[k++]); });
  publish_force_models();  // the servo path renders the restored step's force model, not the last one run
  if (recorder_) recorder_->write(RecordKind::RestoreState, std::vector<uint8_t>(data, data + size));
}

uint64_t World::fingerprint() const {
  uint64_t h = fnv1a(nullptr, 0);
  bodies_.for_each([&](Id, const Body& b) {
    h = fnv1a(b.x.data(), b.x.size() * sizeof(Vec3), h);
    h = fnv1a(b.v.data(), b.v.size() * sizeof(Vec3), h);
  });
  tools_.for_each([&](Id, const Tool& t) {
    h = fnv1a(t.force.data(), sizeof(Vec3), h);
    h = fnv1a(t.torque.data(), sizeof(Vec3), h);
  });
  lpcs_.for_each([&](Id, const Lpc& c) { h = fnv1a(c.reaction.data(), sizeof(Vec3), h); });
  return h;
}

}  // namespace mica
