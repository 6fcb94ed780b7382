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
//   bodies   positions, velocities (now and at the last step's start), node forces, the rotations
//            and energy a step hands the next (BodyState::end), and what the solver keeps for the
//            body (its lagged factor: VelocitySolver::save_body)
//   tools    poses (now and at the last step), force, torque, contact count, stiffness
//   lpcs     prescribed velocity, reaction, handle (targets or grab offsets, pose, tool)
//   devices  the force filter (moving average) and the last force sent
// A restore reads and checks all of it before it changes anything; the solver's part (factoring the
// saved systems again) is the last step that can throw, and what follows only moves values in.
// Not saved, because they do not change a later step: timings aside from the counters, the per-step
// work arrays, and a linear body's assembled matrix (reassembled: the same bits).
#include <algorithm>
#include <cstddef>
#include <cstring>
#include <functional>
#include <type_traits>

#include "core/byte_stream.hpp"
#include "world/state_fields.hpp"
#include "world/recording.hpp"
#include "world/world.hpp"

namespace mica {

namespace {

constexpr char kMagic[8] = {'M', 'I', 'C', 'A', 'S', 'T', 'A', 'T'};
// 2: the contacts' curvature impulses; 3: v_previous; 4: solves, factorizations; 5: the step's
// work (contact impulses, start rotations, tool velocities) left out, the energy debt one number
constexpr uint32_t kFormatVersion = 5;

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
    uint8_t is_static, model;  // ElasticModel (0 and 1: the co-rotational flag before 0.8)
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
    if (a.is_static != b.is_static || a.model != b.model)
      return refuse + "its body " + std::to_string(k) + " is of another kind (static or dynamic, co-rotational, linear or neo-Hookean)";
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

// A state copies these structs as bytes: a padding byte would be uninitialised, and two saves of
// one state could differ in it. Each size is the sum of its fields'.
static_assert(sizeof(StateShape::BodyShape) == 2 * 4 + 4 * 1, "BodyShape has padding");
static_assert(sizeof(BodyPoint) == 6 * 4 + 3 * 8, "BodyPoint has padding");
static_assert(sizeof(Contact) == 8 + 2 * sizeof(BodyPoint) + 3 * sizeof(Vec3) + 2 * 8 + 4 * 4 + 8, "Contact has padding");
static_assert(sizeof(RowTerm) == 2 * 4 + 8, "RowTerm has padding");
static_assert(sizeof(StageStats) == 2 * 4 + 3 * 8, "StageStats has padding");
static_assert(sizeof(WorldStats) == 8 + kStageCount * sizeof(StageStats) + 2 * 8 + 4 + 2 * 1 + 2 * 1 + 2 * 4,
              "WorldStats has padding");

void require(bool ok, const std::string& message) {
  if (!ok) fail(Errc::Parse, message + ": corrupt state");
}

template <class T>
struct is_vector : std::false_type {};
template <class T, class A>
struct is_vector<std::vector<T, A>> : std::true_type {};

// Writes each field of the list (state_fields.hpp).
struct StateWriter {
  ByteWriter& out;

  template <class T>
  void operator()(const char*, const T& field, uint32_t) {
    if constexpr (is_vector<T>::value)
      out.put_vector(field);
    else
      out.put(field);
  }
  void operator()(const char*, const bool& field, uint32_t) { out.put(uint8_t(field)); }
  void operator()(const char* what, const std::unique_ptr<Handle>& handle, uint32_t flags) {
    (*this)(what, handle != nullptr, flags);
    if (!handle) return;
    out.put_vector(handle->offsets);
    out.put(handle->position);
    out.put(handle->orientation);
    out.put(handle->tool);
  }
};

// Reads each field of the list and checks it against the flags and the object it goes into (the
// body's node and tet counts, a handle's nodes and tool). In the check pass the values are read and
// dropped; in the apply pass, after every check passed, the same bytes are read into the fields.
struct StateReader {
  ByteReader in;
  bool apply = false;
  size_t nodes = 0, elements = 0;           // of the body whose fields are read
  const std::vector<int32_t>* lpc_nodes = nullptr;  // of the constraint whose handle is read
  std::function<bool(Id)> has_tool;         // for a handle's tool

  template <class T>
  void operator()(const char* what, T& field, uint32_t flags) {
    T value{};
    if constexpr (is_vector<T>::value) {
      in.get_vector(value, what);
      const size_t n = value.size();
      require(!(flags & kPerNode) || n == nodes, std::string(what) + " do not match the body's node count");
      require(!(flags & kPerNodeOrNone) || n == nodes || n == 0, std::string(what) + " do not match the body's node count");
      require(!(flags & kPerElement) || n == elements, std::string(what) + " do not match the body's tet count");
      if constexpr (std::is_same<T, Vec3List>::value)
        require(!(flags & kFinite) || flat(value).allFinite(), std::string(what) + " are not finite");
    } else {
      value = in.get<T>(what);
    }
    if (apply) field = std::move(value);  // a vector of the same size is copied in place (a positions view stays valid)
  }
  // The statistics' flags are bools: checked as bytes first (a bool holding 2 is undefined behaviour).
  void operator()(const char* what, WorldStats& field, uint32_t) {
    uint8_t raw[sizeof(WorldStats)];
    in.get_bytes(raw, sizeof raw, what);
    require(raw[offsetof(WorldStats, converged)] <= 1 && raw[offsetof(WorldStats, out_of_time)] <= 1,
            "the statistics' flags are not 0 or 1");
    if (apply) std::memcpy(static_cast<void*>(&field), raw, sizeof raw);
  }
  void operator()(const char* what, bool& field, uint32_t) {
    const bool value = in.get<uint8_t>(what) != 0;
    if (apply) field = value;
  }
  void operator()(const char* what, std::unique_ptr<Handle>& field, uint32_t) {
    if (!(in.get<uint8_t>(what) != 0)) {
      if (apply) field.reset();
      return;
    }
    auto h = std::make_unique<Handle>();
    in.get_vector(h->offsets, what);
    h->position = in.get<Vec3>(what);
    h->orientation = in.get<Eigen::Quaterniond>(what);
    h->tool = in.get<uint64_t>(what);
    require(h->offsets.size() == lpc_nodes->size(), "a constraint's handle does not match its node count");
    if (h->tool && !has_tool(h->tool))
      fail(Errc::InvalidArgument, "the state has a grab following a tool this world does not have (id " +
                                      std::to_string(h->tool) + ")");
    if (apply) field = std::move(h);
  }
};

// Hashes the fields marked kFingerprint, in the list's order.
struct StateHasher {
  uint64_t hash = fnv1a(nullptr, 0);

  template <class T>
  void operator()(const char*, const T& field, uint32_t flags) {
    if (!(flags & kFingerprint)) return;
    if constexpr (is_vector<T>::value)
      hash = fnv1a(field.data(), field.size() * sizeof(typename T::value_type), hash);
    else
      hash = fnv1a(&field, sizeof field, hash);
  }
};

// What the contacts readout dereferences must be in range: the last step's results of a state
// about to be restored.
void check_results(const StepResults& r, const std::function<const Body*(Id)>& find_body,
                   const std::function<bool(Id)>& has_tool) {
  const ContactRows& rows = r.rows;
  const size_t nr = rows.direction.size();
  // Before the first step the rows have no start offsets at all.
  require((rows.start.size() == nr + 1 || (nr == 0 && rows.start.empty())) && rows.bias.size() == nr && rows.normal_of.size() == nr && rows.mu.size() == nr &&
              rows.contact.size() == nr && rows.key.size() == nr && r.lambda.size() == nr,
          "the contact rows disagree in length");
  require(r.curvature_impulse.size() == r.contacts.size(), "the contacts disagree in length");
  for (Id id : r.bodies) require(find_body(id) && find_body(id)->is_dynamic(), "a step body is not in this world");
  for (Id id : r.tools) require(has_tool(id), "a step tool is not in this world");
  for (size_t k = 0; k < nr; ++k)
    require(rows.contact[k] >= 0 && size_t(rows.contact[k]) < r.contacts.size() && rows.start[k] <= rows.start[k + 1] &&
                size_t(rows.start[k + 1]) <= rows.terms.size() && rows.normal_of[k] < int32_t(k),
            "a contact row is out of range");
  auto point_ok = [&](const BodyPoint& p) {
    if (p.count == 0) return true;
    if (p.count < 0 || p.count > 3 || p.body < 0 || size_t(p.body) >= r.bodies.size()) return false;
    const int32_t n = find_body(r.bodies[size_t(p.body)])->fem.node_count();
    for (int k = 0; k < p.count; ++k)
      if (p.nodes[k] < 0 || p.nodes[k] >= n) return false;
    return true;
  };
  for (const Contact& c : r.contacts)
    require(point_ok(c.a) && c.a.count > 0 && point_ok(c.b) && c.tool < int32_t(r.tools.size()),
            "a contact names a body, node or tool out of range");
  for (const RowTerm& t : rows.terms)
    require(t.body >= 0 && size_t(t.body) < r.bodies.size() && t.node >= 0 &&
                t.node < find_body(r.bodies[size_t(t.body)])->fem.node_count(),
            "a contact row names a body or node out of range");
}

void check_filter(const DeviceLink::FilterState& f, int32_t window) {
  require(f.average.samples.size() == size_t(window) && f.average.next >= 0 && f.average.next < window &&
              f.average.count >= 0 && f.average.count <= window && f.average.since_resum >= 0,
          "a device's filter does not match its window");
}

}  // namespace

void World::state_shape(StateShape& s) const {
  std::vector<Id> body_ids;
  bodies_.for_each([&](Id id, const Body& b) {
    body_ids.push_back(id);
    s.bodies.push_back({b.fem.node_count(), int32_t(b.tets.size()), uint8_t(b.settings.is_static),
                        uint8_t(b.settings.model)});
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

// The list in its order: the world's part, then per body, tool, constraint and device. The
// visitor is called with each object's fields (const_cast: a writer or hasher visits a const
// world and changes nothing). `body_extra(v, body)` adds what the solver keeps for the body.
template <class V, class BodyExtra>
void World::visit_world_state(V& v, BodyExtra&& body_extra) const {
  World& w = const_cast<World&>(*this);
  visit_state(v, w.last_);
  v("the warm-start impulses", w.warm_start_list_, kPlain);
  v("the overlapping bodies", w.overlapping_, kPlain);
  w.bodies_.for_each([&](Id, Body& b) {
    visit_state(v, static_cast<BodyState&>(b));
    body_extra(v, b);
  });
  w.tools_.for_each([&](Id, Tool& t) { visit_state(v, static_cast<ToolState&>(t)); });
  w.lpcs_.for_each([&](Id, Lpc& c) { visit_state(v, c); });
  w.devices_.for_each([&](Id, DeviceLink& link) {
    DeviceLink::FilterState f = link.filter_state();
    visit_state(v, f);
  });
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

  // The warm starts in key order: a map's order is not the same from one world to another.
  warm_start_list_.assign(warm_start_.begin(), warm_start_.end());
  std::sort(warm_start_list_.begin(), warm_start_list_.end());
  StateWriter writer{out};
  visit_world_state(writer, [&](StateWriter& v, const Body& b) {
    ByteWriter solver;
    solver_->save_body(b.key, solver);
    v("a body's solver state", solver.bytes(), kPlain);
  });

  std::vector<uint8_t>& bytes = out.bytes();
  Header header{};
  std::memcpy(header.magic, kMagic, sizeof kMagic);
  header.version = kFormatVersion;
  header.layout = kByteLayout;
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
  if (header.version != kFormatVersion || header.layout != kByteLayout)
    fail(Errc::Parse, "the state is of format " + std::to_string(header.version) + " (layout " +
                          std::to_string(header.layout) + "); this libmica reads format " +
                          std::to_string(kFormatVersion) + " written on a machine like this one");
  if (header.size != size)
    fail(Errc::Parse, "the state's header says " + std::to_string(header.size) + " bytes, the buffer has " +
                          std::to_string(size) + (size < header.size ? ": truncated" : ""));
  if (fnv1a(data + kHeaderSize, size - kHeaderSize) != header.checksum)
    fail(Errc::Parse, "the state's checksum does not match its contents: corrupt");
  devices_.for_each([&](Id, const DeviceLink& link) {
    if (link.servo_running())
      fail(Errc::WrongState, "a device's servo loop is running: stop it (mica_device_stop) before restoring a state");
  });

  // The shape.
  ByteReader shape_in(data + kHeaderSize, size - kHeaderSize);
  Shape saved;
  saved.read(shape_in);
  Shape here;
  state_shape(here);
  const std::string difference = shape_difference(saved, here);
  if (!difference.empty()) fail(Errc::InvalidArgument, difference);
  const size_t fields_at = kHeaderSize + shape_in.position();

  // The check pass: every field read and checked, nothing changed; the world's part and the
  // solver's data kept for the checks that need them whole.
  StepResults results;
  std::vector<std::vector<uint8_t>> solver_data;
  std::vector<VelocitySolver::SavedBody> solver_bodies;
  std::vector<DeviceLink::FilterState> filters;
  auto has_tool = [&](Id id) { return tools_.find(id) != nullptr; };
  auto read_pass = [&](StateReader& r) {
    const bool apply = r.apply;
    // What the checks need whole (or what goes in by a call) is read into locals in both passes.
    auto into_locals = [&](auto&& read) {
      r.apply = true;
      read();
      r.apply = apply;
    };
    if (apply) {
      visit_state(r, last_);
    } else {
      into_locals([&] { visit_state(r, results); });
      check_results(results, [&](Id id) { return bodies_.find(id); }, has_tool);
    }
    r("the warm-start impulses", warm_start_list_, kPlain);
    r("the overlapping bodies", overlapping_, kPlain);
    size_t k = 0;
    bodies_.for_each([&](Id, Body& b) {
      r.nodes = size_t(b.fem.node_count());
      r.elements = b.fem.elements.size();
      visit_state(r, static_cast<BodyState&>(b));
      if (!apply) solver_data.emplace_back();
      into_locals([&] { r("a body's solver state", solver_data[k++], kPlain); });
    });
    tools_.for_each([&](Id, Tool& t) { visit_state(r, static_cast<ToolState&>(t)); });
    lpcs_.for_each([&](Id, Lpc& c) {
      r.lpc_nodes = &c.nodes;
      visit_state(r, c);
    });
    k = 0;
    devices_.for_each([&](Id, DeviceLink& link) {
      if (!apply) filters.emplace_back();
      into_locals([&] { visit_state(r, filters[k]); });
      check_filter(filters[k++], link.settings().filter_window);
    });
    if (r.in.remaining())
      fail(Errc::Parse, "the state has " + std::to_string(r.in.remaining()) + " bytes past its end: corrupt");
  };
  StateReader check{ByteReader(data + fields_at, size - fields_at), false, 0, 0, nullptr, has_tool};
  read_pass(check);  // reads into locals, or checks and drops

  // The solver's part: factors the saved systems (the last step that may throw).
  size_t k = 0;
  bodies_.for_each([&](Id, const Body& b) {
    solver_bodies.push_back({b.key, &b.fem, solver_data[k].data(), solver_data[k].size()});
    ++k;
  });
  solver_->restore_bodies(solver_bodies);

  // The apply pass: the same bytes into the fields (nothing throws: every check passed).
  StateReader apply{ByteReader(data + fields_at, size - fields_at), true, 0, 0, nullptr, has_tool};
  read_pass(apply);
  warm_start_.clear();
  for (const auto& [key, impulse] : warm_start_list_) warm_start_[key] = impulse;
  k = 0;
  devices_.for_each([&](Id, DeviceLink& link) { link.set_filter_state(filters[k++]); });
  bodies_.for_each([&](Id, Body& b) {
    b.bvh.refit(b.x);
    // The solvers' factors of the current matrix are redone (the same matrix: the same bits).
    b.matrix_current = false;
    ++b.matrix_version;
  });
  publish_force_models();  // the servo path renders the restored step's force model, not the last one run
  if (recorder_) recorder_->write(RecordKind::RestoreState, std::vector<uint8_t>(data, data + size));
}

uint64_t World::fingerprint() const {
  StateHasher hasher;
  visit_world_state(hasher, [](StateHasher&, const Body&) {});
  return hasher.hash;
}

}  // namespace mica
