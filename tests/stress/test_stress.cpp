// SPDX-License-Identifier: Apache-2.0
// The stress matrix: hard cases (mica-method.md section 6) across Young's modulus 1e2..1e9 Pa,
// Poisson ratio 0..0.499 and time steps 1e-4..5e-2 s, each run checked by stress::Monitor for
// finite results, energy growth beyond the work of the drivers, penetration, tunnelling, false
// body contacts, stale contact impulses, inverted elements after a release, and convergence:
// non-converged steps are counted (never failed), steps reported converged must be solved.
//
//   stress_test_stress                  the representative slice (ctest labels unit;stress)
//   stress_test_stress --full           the whole matrix (label stress-full)
//   --only abc                          only these scenarios (letters below)
//   --direct                            only the Direct-solver runs
//   --csv PATH                          one line per run (scripts/stability_table.py reads it)
//
// Scenarios: a fall onto a static slab, b sphere indent to half depth, c grasped face twisted
// 180 degrees and released, d inverted start, e sliver plate, f plane pressing 256 nodes,
// g projection and contact on the same nodes, h tool at 10 m/s through a thin slab, i two
// deformable bodies pressed together.
#include "stress/stress_harness.hpp"

using namespace mica;
using namespace stress;

namespace {

// ---------------------------------------------------------------- settings shared by the scenes

constexpr double kRho = 1000;  // kg/m^3
// Energy: the growth beyond the driving work and the recovery allowance, as a fraction of the
// run's energy scale (see Monitor). Backward Euler dissipates; 2 % absorbs round-off and the
// solver's tolerance with a wide margin (over the whole matrix the frozen-rotation balance of
// solved steps grew at most 9e-4 of the scale). Growth from the co-rotational rotation update
// beyond it is a failure (K1).
constexpr double kEnergyLimit = 0.02;
// Penetration: no node deeper than this fraction of the scene's reference length (the tool's
// radius, the slab's thickness, the element size) once contact has been made.
constexpr double kPenetrationLimit = 0.1;

WorldSettings world_settings(const Case& c, const Vec3& gravity) {
  WorldSettings ws;
  ws.solver = c.solver;
  ws.mica_sweep = c.sweep;
  ws.tolerance = c.tol;
  ws.max_iterations = c.max_iter;
  ws.gravity = gravity;
  return ws;
}

BodySettings material(const Case& c) {
  BodySettings bs;
  bs.material = {c.E, c.nu, kRho};
  return bs;
}

// Shear-wave crossing time of a length L: the time scale on which a body relaxes.
double wave_time(const Case& c, double L) {
  const double mu = c.E / (2 * (1 + c.nu));
  return L / std::sqrt(mu / kRho);
}

// Steps allowed for inverted elements to clear after a release: twenty shear-wave crossings of the
// body, at least `lo` steps. Nothing is damped: a very soft body released while squashed rings
// with strains of order one and its elements invert again and again for a while (the slowest
// measured, g at E = 1e2 Pa, nu = 0, h = 1e-4 s, first had none inverted after ten crossings).
int recovery_budget(const Case& c, double L, int lo) { return phase_steps(20 * wave_time(c, L), c.h, lo, 10000000); }

// After a release: at least `tail` steps, and on while elements are still inverted, up to the
// recovery budget (the Monitor fails the run if they outlast it).
bool run_free(Monitor& m, const Result& r, double h, int tail, int budget) {
  m.expect_recovery(budget);
  bool go = true;
  for (int k = 0; go; ++k) {
    const bool recovered = r.recovery_steps >= 0;
    if (k >= tail && (recovered || k >= budget)) break;
    go = m.step(h);
  }
  return go;
}

Id add_sphere(World& w, const Vec3& at, double radius) {
  Tool t;
  t.shape = ToolShape::Sphere;
  t.radius = radius;
  t.margin = 1e-3;
  t.position = at;
  return w.add_tool(t);
}

void move_tool(World& w, Id tool, const Vec3& p) { w.set_tool_pose(tool, p, Eigen::Quaterniond::Identity()); }

// Node penetration into a sphere tool at its current pose.
double sphere_node_penetration(const Body& b, const Tool& t, const std::vector<uint8_t>* exclude = nullptr) {
  return stress::sphere_node_penetration(b, t.position, t.radius, exclude);
}

void note_mismatch(Result& r, const Monitor& m) {
  if (m.contact_impulse_mismatch() > 0)
    r.notes += format(" stale Body::contact_impulse (up to %.3g N s);", m.contact_impulse_mismatch());
}

// ---------------------------------------------------------------- (a) fall onto a static slab

Result run_fall(const Case& c) {
  Result r;
  r.c = c;
  r.scene = "5 cm cube (162 tets) dropped at 0.3 m/s onto a static slab; gravity";
  World w(world_settings(c, Vec3(0, -9.81, 0)));
  BodySettings slab = material(c);
  slab.is_static = true;
  const double thickness = 0.02;
  const Id base = w.add_body(make_box_grid(Vec3(-0.05, -thickness, -0.05), Vec3(0.1, 0, 0.1), {3, 1, 3}, 5), slab,
                             Vec3::Zero(), Vec3::Zero());
  const Id cube = w.add_body(make_box_grid(Vec3(0, 0.002, 0), Vec3(0.05, 0.052, 0.05), {3, 3, 3}, 6), material(c),
                             Vec3::Zero(), Vec3(0, -0.3, 0));
  Monitor m(w, {cube}, r, kEnergyLimit);
  const Body& b = w.body(cube);
  const Body& s = w.body(base);
  m.set_penetration([&] { return body_penetration(b, s); }, thickness, kPenetrationLimit * thickness);
  m.phase("fall");
  const int n = phase_steps(0.3, c.h, 40, 300);
  for (int k = 0; k < n && m.step(c.h); ++k) {
  }
  m.finish();
  note_mismatch(r, m);
  return r;
}

// ---------------------------------------------------------------- (b) sphere to half depth

Result run_indent(const Case& c) {
  Result r;
  r.c = c;
  r.scene = "block 10x5x10 cm (450 tets), bottom fixed; sphere r 3 cm pressed 2.5 cm (half the depth), held, "
            "retracted";
  World w(world_settings(c, Vec3::Zero()));
  const double depth = 0.05, radius = 0.03;
  const Id body = w.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, depth, 0.1), {5, 3, 5}, 6), material(c),
                             Vec3::Zero(), Vec3::Zero());
  w.add_lpc(body, nodes_where(w.body(body), [](const Vec3& p) { return p.y() < 1e-9; }), LpcSpec{});
  const Vec3 up(0.054, depth + radius + 0.001, 0.047), down(0.054, depth + radius - 0.5 * depth, 0.047);
  const Id tool = add_sphere(w, up, radius);
  Monitor m(w, {body}, r, kEnergyLimit);
  const Body& b = w.body(body);
  m.set_penetration([&] { return sphere_node_penetration(b, w.tool(tool)); }, radius, kPenetrationLimit * radius);
  const int press = phase_steps(0.1, c.h, 10, 400), hold = phase_steps(0.05, c.h, 5, 100),
            tail = phase_steps(0.05, c.h, 10, 100);
  bool go = true;
  m.phase("press");
  for (int k = 1; go && k <= press; ++k) {
    move_tool(w, tool, up + (down - up) * double(k) / press);
    go = m.step(c.h);
  }
  m.phase("hold");
  for (int k = 0; go && k < hold; ++k) go = m.step(c.h);
  m.phase("retract");
  for (int k = 1; go && k <= press; ++k) {
    move_tool(w, tool, down + (up - down) * double(k) / press);
    go = m.step(c.h);
  }
  m.phase("free");
  if (go) run_free(m, r, c.h, tail, recovery_budget(c, 0.1, tail));
  m.finish();
  note_mismatch(r, m);
  return r;
}

// ---------------------------------------------------------------- (c) twist 180 degrees, release

Result run_twist(const Case& c) {
  Result r;
  r.c = c;
  r.scene = "beam 10x3x3 cm (144 tets), one end fixed, the other grabbed and twisted 180 deg, held, released";
  World w(world_settings(c, Vec3::Zero()));
  const Id body = w.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.03, 0.03), {6, 2, 2}, 6), material(c),
                             Vec3::Zero(), Vec3::Zero());
  w.add_lpc(body, nodes_where(w.body(body), [](const Vec3& p) { return p.x() < 1e-9; }), LpcSpec{});
  // A handle on the beam's axis 2 cm beyond the free end: the sphere of 3 cm around it holds
  // the end face's nodes (at most 2.9 cm away) and none of the next layer (3.7 cm and more).
  const Vec3 axis_point(0.12, 0.015, 0.015);
  const Id grab = w.grab(body, axis_point, 0.03, 0);
  if (w.lpc(grab).nodes.size() != 9) r.failure(0, format("grabbed %zu nodes, not the 9 of the end face", w.lpc(grab).nodes.size()));
  Monitor m(w, {body}, r, kEnergyLimit);
  const int twist = phase_steps(0.5, c.h, 20, 400), hold = phase_steps(0.1, c.h, 5, 100),
            tail = phase_steps(0.2, c.h, 20, 200);
  bool go = true;
  m.phase("twist");
  for (int k = 1; go && k <= twist; ++k) {
    const double s = double(k) / twist, angle = M_PI * 0.5 * (1 - std::cos(M_PI * s));  // smooth 0 -> pi
    w.set_handle_pose(grab, axis_point, Eigen::Quaterniond(Eigen::AngleAxisd(angle, Vec3::UnitX())));
    go = m.step(c.h);
  }
  m.phase("hold");
  for (int k = 0; go && k < hold; ++k) go = m.step(c.h);
  w.remove_lpc(grab);
  m.phase("free");
  if (go) run_free(m, r, c.h, tail, recovery_budget(c, 0.1, tail));
  m.finish();
  return r;
}

// ---------------------------------------------------------------- (d) inverted start

Result run_inverted(const Case& c) {
  Result r;
  r.c = c;
  r.scene = "free 5 cm cube (162 tets), top node layer pushed through the layer below (54 elements inverted)";
  World w(world_settings(c, Vec3::Zero()));
  const double L = 0.05;
  const Id body = w.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(L, L, L), {3, 3, 3}, 6), material(c), Vec3::Zero(),
                             Vec3::Zero());
  Body& b = w.body(body);
  // The top layer (y = L) goes to y = L/2: through the layer at 2L/3, half a cell beyond it.
  for (int32_t i : nodes_where(b, [&](const Vec3& p) { return p.y() > L - 1e-9; })) b.x[i].y() = 0.5 * L;
  Monitor m(w, {body}, r, kEnergyLimit);
  if (r.inverted_start == 0) r.failure(0, "the flip inverted no element");
  // Inverted elements must be gone within the recovery budget.
  m.phase("free");
  run_free(m, r, c.h, phase_steps(0.05, c.h, 10, 100), recovery_budget(c, L, 10));
  m.finish();
  return r;
}

// ---------------------------------------------------------------- (e) slivers

Result run_sliver(const Case& c) {
  Result r;
  r.c = c;
  World w(world_settings(c, Vec3(0, -9.81, 0)));
  // A 4 x 1 x 4 grid of 1.25 cm cubes squashed 1e-3 in y: a 5 x 5 cm plate 12.5 um thick.
  TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(0.05, 0.0125, 0.05), {4, 1, 4}, 6);
  for (Vec3& p : mesh.nodes) p.y() *= 1e-3;
  const Id body = w.add_body(mesh, material(c), Vec3::Zero(), Vec3::Zero());
  const Body& b = w.body(body);
  r.scene = format("plate 5x5 cm, 12.5 um thick (96 slivers, worst aspect %.0f), clamped along one edge; gravity",
                   b.fem.quality.worst_aspect);
  w.add_lpc(body, nodes_where(b, [](const Vec3& p) { return p.x() < 1e-9; }), LpcSpec{});
  Monitor m(w, {body}, r, kEnergyLimit);
  m.phase("sag");
  const int n = phase_steps(0.3, c.h, 20, 300);
  for (int k = 0; k < n && m.step(c.h); ++k) {
  }
  m.finish();
  return r;
}

// ---------------------------------------------------------------- (f) 256 simultaneous contacts

Result run_many_contacts(const Case& c) {
  Result r;
  r.c = c;
  r.scene = "slab 10x2x10 cm (1125 tets), bottom fixed; a plane presses its 256 top nodes 2 mm, holds, lifts";
  World w(world_settings(c, Vec3::Zero()));
  const double thickness = 0.02;
  const Id body = w.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, thickness, 0.1), {15, 1, 15}, 5), material(c),
                             Vec3::Zero(), Vec3::Zero());
  w.add_lpc(body, nodes_where(w.body(body), [](const Vec3& p) { return p.y() < 1e-9; }), LpcSpec{});
  Tool plane;
  plane.shape = ToolShape::Plane;
  plane.plane_normal = Vec3(0, -1, 0);  // the body stays below
  plane.margin = 1e-3;
  const Vec3 up(0, thickness + 5e-4, 0), down(0, thickness - 2e-3, 0);
  plane.position = up;
  const Id tool = w.add_tool(plane);
  Monitor m(w, {body}, r, kEnergyLimit);
  const Body& b = w.body(body);
  m.set_penetration([&] { return plane_penetration(b, w.tool(tool).position, Vec3(0, -1, 0)); }, thickness,
                    kPenetrationLimit * thickness);
  const int press = phase_steps(0.05, c.h, 10, 200), hold = phase_steps(0.05, c.h, 10, 100),
            tail = phase_steps(0.05, c.h, 10, 100);
  bool go = true;
  m.phase("press");
  for (int k = 1; go && k <= press; ++k) {
    move_tool(w, tool, up + (down - up) * double(k) / press);
    go = m.step(c.h);
  }
  m.phase("hold");
  for (int k = 0; go && k < hold; ++k) go = m.step(c.h);
  m.phase("retract");
  for (int k = 1; go && k <= press; ++k) {
    move_tool(w, tool, down + (up - down) * double(k) / press);
    go = m.step(c.h);
  }
  m.phase("free");
  if (go) run_free(m, r, c.h, tail, recovery_budget(c, 0.1, tail));
  m.finish();
  // Every top node is in the solve at once (whether each carries an impulse depends on the
  // material: a locking, nearly incompressible layer leaves some of them unloaded).
  if (r.max_rows < 200) r.failure(r.steps, format("only %d simultaneous contact rows (want >= 200)", r.max_rows));
  note_mismatch(r, m);
  return r;
}

// ---------------------------------------------------------------- (g) projection + contact

Result run_lpc_contact(const Case& c) {
  Result r;
  r.c = c;
  r.scene = "block 10x5x10 cm, bottom fixed, top nodes slide only in y-z (plane LPC), one of them fixed; "
            "sphere r 3 cm pressed on them 1.25 cm, held, removed";
  World w(world_settings(c, Vec3::Zero()));
  const double depth = 0.05, radius = 0.03;
  const Id body = w.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, depth, 0.1), {5, 3, 5}, 6), material(c),
                             Vec3::Zero(), Vec3::Zero());
  const Body& b = w.body(body);
  w.add_lpc(body, nodes_where(b, [](const Vec3& p) { return p.y() < 1e-9; }), LpcSpec{});
  LpcSpec slide;
  slide.kind = LpcKind::Plane;
  slide.directions[0] = Vec3::UnitX();
  w.add_lpc(body, nodes_where(b, [&](const Vec3& p) { return p.y() > depth - 1e-9; }), slide);
  const std::vector<int32_t> pinned =
      nodes_where(b, [&](const Vec3& p) { return (p - Vec3(0.06, depth, 0.06)).norm() < 1e-9; });
  w.add_lpc(body, pinned, LpcSpec{});
  // The pinned node cannot leave the sphere: LPC wins by design, its row carries no impulse.
  // It is left out of the penetration check; every other node must stay out.
  std::vector<uint8_t> exclude(b.x.size(), 0);
  for (int32_t i : pinned) exclude[i] = 1;
  const Vec3 up(0.056, depth + radius + 0.001, 0.053), down(0.056, depth + radius - 0.25 * depth, 0.053);
  const Id tool = add_sphere(w, up, radius);
  bool tool_gone = false;
  Monitor m(w, {body}, r, kEnergyLimit);
  m.set_penetration([&] { return tool_gone ? 0.0 : sphere_node_penetration(b, w.tool(tool), &exclude); }, radius,
                    kPenetrationLimit * radius);
  const int press = phase_steps(0.1, c.h, 10, 300), hold = phase_steps(0.05, c.h, 5, 100),
            tail = phase_steps(0.05, c.h, 10, 100);
  bool go = true;
  double pinned_impulse = 0;
  auto check_pinned_rows = [&] {
    // Rows acting on the pinned node alone must carry no impulse.
    const ContactRows& rows = w.contact_rows();
    for (size_t q = 0; q < rows.size(); ++q)
      if (rows.start[q + 1] - rows.start[q] == 1 && exclude[rows.terms[rows.start[q]].node])
        pinned_impulse = std::max(pinned_impulse, std::fabs(w.impulses()[q]));
  };
  m.phase("press");
  for (int k = 1; go && k <= press; ++k) {
    move_tool(w, tool, up + (down - up) * double(k) / press);
    go = m.step(c.h);
    check_pinned_rows();
  }
  m.phase("hold");
  for (int k = 0; go && k < hold; ++k) {
    go = m.step(c.h);
    check_pinned_rows();
  }
  // The tool is taken away while it presses: the steps after have no contact at all, and what
  // the body reports (Body::contact_impulse, which the LPC reactions use) must say so.
  w.remove_tool(tool);
  tool_gone = true;
  m.phase("free");
  if (go) run_free(m, r, c.h, tail, recovery_budget(c, 0.1, tail));
  m.finish();
  if (pinned_impulse != 0) r.failure(r.steps, format("a row on the fixed node carried %.3g N s", pinned_impulse));
  // The slide constraint held: top nodes kept x.
  for (int32_t i : nodes_where(b, [&](const Vec3& p) { return p.y() > depth - 1e-9; }))
    if (std::fabs(b.x[i].x() - b.fem.rest[i].x()) > 1e-9) {
      r.failure(r.steps, format("top node %d left its plane by %.3g m", i, b.x[i].x() - b.fem.rest[i].x()));
      break;
    }
  note_mismatch(r, m);
  return r;
}

// ---------------------------------------------------------------- (h) 10 m/s through a thin slab

Result run_fast_tool(const Case& c) {
  Result r;
  r.c = c;
  r.scene = "slab 10x0.4x10 cm (500 tets), rim fixed; sphere r 1 cm driven down at 10 m/s for 4.2 cm, held";
  World w(world_settings(c, Vec3::Zero()));
  const double thickness = 0.004, radius = 0.01, speed = 10, travel = 0.042;
  const Id body = w.add_body(make_box_grid(Vec3(-0.05, -thickness, -0.05), Vec3(0.05, 0, 0.05), {10, 1, 10}, 5),
                             material(c), Vec3::Zero(), Vec3::Zero());
  const Body& b = w.body(body);
  w.add_lpc(body, nodes_where(b, [](const Vec3& p) { return std::fabs(p.x()) > 0.05 - 1e-9 || std::fabs(p.z()) > 0.05 - 1e-9; }),
            LpcSpec{});
  const Vec3 start(0.003, 0.002 + radius, 0.002);
  const Id tool = add_sphere(w, start, radius);
  Monitor m(w, {body}, r, kEnergyLimit);
  m.set_penetration([&] { return sphere_node_penetration(b, w.tool(tool)); }, radius, kPenetrationLimit * radius);
  // Tunnelling: a node that was ahead of the sphere (below its centre) and lies in its shadow
  // (closer to its axis than r) must never be behind it (above the centre); and the centre must
  // never be inside an element of the slab.
  std::vector<uint8_t> ahead(b.x.size(), 0);
  for (size_t i = 0; i < b.x.size(); ++i) ahead[i] = b.x[i].y() < start.y();
  const int move = int(std::ceil(travel / (speed * c.h) - 1e-9)), hold = phase_steps(0.05, c.h, 10, 100);
  bool go = true, tunnelled = false;
  for (int k = 1; go && k <= move + hold; ++k) {
    m.phase(k <= move ? "drive" : "hold");
    move_tool(w, tool, start - Vec3(0, std::min(speed * c.h * k, travel), 0));
    go = m.step(c.h);
    const Vec3 centre = w.tool(tool).position;
    for (size_t i = 0; go && !tunnelled && i < b.x.size(); ++i) {
      const Vec3 d = b.x[i] - centre;
      if (ahead[i] && std::hypot(d.x(), d.z()) < radius && d.y() > 0) {
        tunnelled = true;
        r.failure(k, format("tunnelling: node %zu passed through the tool (now %.3g m above its centre, %.3g m "
                            "from its axis)",
                            i, d.y(), std::hypot(d.x(), d.z())));
      }
    }
    for (const Tet& t : b.tets)
      if (go && !tunnelled && point_in_tet(centre, b.x[t[0]], b.x[t[1]], b.x[t[2]], b.x[t[3]])) {
        tunnelled = true;
        r.failure(k, "tunnelling: the tool's centre is inside the slab");
      }
  }
  m.finish();
  r.notes += format(" tool moved %.3g m per step;", speed * c.h);
  note_mismatch(r, m);
  return r;
}

// ---------------------------------------------------------------- (i) two deformable bodies

Result run_two_bodies(const Case& c) {
  Result r;
  r.c = c;
  r.scene = "block 10x5x10 cm (192 tets, bottom fixed) and a 6x4x6 cm block (108 tets) pushed 8 mm into it by "
            "its top face, held, released";
  World w(world_settings(c, Vec3::Zero()));
  const Id lower = w.add_body(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.05, 0.1), {4, 2, 4}, 6), material(c),
                              Vec3::Zero(), Vec3::Zero());
  w.add_lpc(lower, nodes_where(w.body(lower), [](const Vec3& p) { return p.y() < 1e-9; }), LpcSpec{});
  const Id upper = w.add_body(make_box_grid(Vec3(0.02, 0.052, 0.02), Vec3(0.08, 0.092, 0.08), {3, 2, 3}, 6),
                              material(c), Vec3::Zero(), Vec3::Zero());
  const Id push = w.add_lpc(upper, nodes_where(w.body(upper), [](const Vec3& p) { return p.y() > 0.092 - 1e-9; }),
                            LpcSpec{});
  Monitor m(w, {lower, upper}, r, kEnergyLimit);
  const Body& a = w.body(lower);
  const Body& u = w.body(upper);
  const double cell = 0.02;
  m.set_penetration([&] { return std::max(body_penetration(u, a), body_penetration(a, u)); }, cell,
                    kPenetrationLimit * cell);
  const int press = phase_steps(0.05, c.h, 10, 300), hold = phase_steps(0.05, c.h, 5, 100),
            tail = phase_steps(0.1, c.h, 20, 200);
  w.set_lpc_velocity(push, Vec3(0, -0.01 / (press * c.h), 0));  // 2 mm gap + 8 mm press
  bool go = true;
  m.phase("press");
  for (int k = 0; go && k < press; ++k) go = m.step(c.h);
  w.set_lpc_velocity(push, Vec3::Zero());
  m.phase("hold");
  for (int k = 0; go && k < hold; ++k) go = m.step(c.h);
  w.remove_lpc(push);
  m.phase("free");
  if (go) run_free(m, r, c.h, tail, recovery_budget(c, 0.1, tail));
  m.finish();
  note_mismatch(r, m);
  return r;
}

// ---------------------------------------------------------------- known library issues
//
// A run whose every failure matches a known issue of its scenario is reported "known" (and
// counted, not failed); any other failure fails the test. MICA_STRESS_STRICT=1 makes known
// failures fail too: what whoever fixes one of these runs. Each entry names a failure message
// the checks above produce, so the checks themselves stay as strict as they are.
struct KnownIssue {
  const char* id;
  const char* scenarios;  // letters it applies to
  const char* signature;  // a substring of the failure message
  const char* what;
};

const KnownIssue kKnownIssues[] = {
    {"K8", "g", "(press): penetration",
     "the contact's geometric stiffness (0.5) couples a triangle's nodes strongly, and MICA's Gauss-Seidel sweep "
     "converges more slowly with it: g, mica, E = 1e6 Pa, nu = 0, h = 0.05, cap 300 ends the press 4.8 mm deep "
     "(limit 3 mm) with its steps not converged; the factored sweep and the exact solver pass (docs/stability.md, K8)"},
    {"K7", "g", "still inverted",
     "the co-rotational energy with inverted elements' rotations flipped has static equilibria with inverted elements "
     "when nu -> 0.5: singular values like (1.9, 1.3, -0.16) keep the signed trace at 3, so the dominant volumetric "
     "term does not push them back (g, Direct, E = 1e2, nu = 0.499, h = 0.05: 18 elements stay inverted, forces balanced "
     "to 1e-14 N; with MICA also E = 1e3 since contact rows on triangles at the pinned node push its neighbours harder); "
     "before K1 was fixed, the rotation update's spurious energy shook them loose"},
    {"K2", "h", "tunnelling",
     "what the swept contacts leave of K2 (16 of 172 runs): a node ends in the sphere's shadow behind its centre, "
     "outside the sphere (most started beside its path). Soft slabs (E <= 1e4 Pa) at h = 1e-3 s, where the tool moves "
     "its own radius per step: one step's tangent-plane contacts leave millimetres of penetration, recovered at "
     "max_recovery_speed, and nodes slide round the sphere or are drawn in behind it (2 to 8 mm above its centre). "
     "In the hold, the slab wrapped round the sphere: E = 1e2 Pa, a node 3 cm above its centre (the slab's edges cut "
     "across it: at the tool's new pose edges are left to their nodes); nu = 0.499 with Direct, 3 mm above"},
};

bool strict_mode() {
  const char* v = getenv("MICA_STRESS_STRICT");
  return v && *v && std::string(v) != "0";
}

// Sets r.status: ok, known (the ids go into the notes) or FAIL.
void classify(Result& r) {
  if (r.failures.empty()) {
    r.status = "ok";
    return;
  }
  std::string ids;
  bool all_known = !strict_mode();
  for (const std::string& f : r.failures) {
    const KnownIssue* match = nullptr;
    for (const KnownIssue& k : kKnownIssues)
      if (std::strchr(k.scenarios, r.c.scenario) && f.find(k.signature) != std::string::npos) match = &k;
    if (!match) {
      all_known = false;
    } else if (ids.find(match->id) == std::string::npos) {
      ids += std::string(ids.empty() ? "" : " ") + match->id;
    }
  }
  r.status = all_known ? "known" : "FAIL";
  if (!ids.empty()) r.notes += " known issues: " + ids + ";";
}

// ---------------------------------------------------------------- the matrix

struct Options {
  bool full = false;
  bool direct_only = false;
  std::string only;  // scenario letters; empty: all
  std::string csv;
} g_options;
Csv g_csv;

using Runner = Result (*)(const Case&);

struct Scenario {
  char letter;
  Runner run;
  int max_iter;       // MICA's cap for this scene (its size and stiffness decide what one step may cost)
  bool few_direct;    // the exact solver costs one solve per contact row: fewer reference runs
};

const Scenario kScenarios[] = {
    {'a', run_fall, 300, false},        {'b', run_indent, 300, false},   {'c', run_twist, 300, false},
    {'d', run_inverted, 300, false},    {'e', run_sliver, 300, false},   {'f', run_many_contacts, 150, true},
    {'g', run_lpc_contact, 300, false}, {'h', run_fast_tool, 300, false}, {'i', run_two_bodies, 300, false},
};

const double kYoungs[] = {1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};
const double kPoisson[] = {0, 0.3, 0.45, 0.49, 0.499};
const double kSteps[] = {1e-4, 1e-3, 1e-2, 5e-2};

std::vector<Case> cases_for(const Scenario& s) {
  std::vector<Case> out;
  auto add = [&](double E, double nu, double h, SolverKind solver, MicaSweep sweep = MicaSweep::GaussSeidel) {
    Case c;
    c.scenario = s.letter;
    c.E = E;
    c.nu = nu;
    c.h = h;
    c.solver = solver;
    c.sweep = sweep;
    c.tol = 1e-6;
    c.max_iter = solver == SolverKind::Mica ? s.max_iter : 1;
    if (g_options.direct_only && solver != SolverKind::Direct) return;
    out.push_back(c);
  };
  if (g_options.full) {
    for (double E : kYoungs)
      for (double nu : kPoisson)
        for (double h : kSteps) add(E, nu, h, SolverKind::Mica);
    // The exact reference on the corners of the matrix (256 contact rows: two of them).
    for (double E : {1e2, 1e5, 1e9})
      for (double nu : {0.3, 0.499})
        for (double h : {1e-3, 5e-2})
          if (!s.few_direct || (E == 1e5 && h == 5e-2)) add(E, nu, h, SolverKind::Direct);
  } else {
    add(1e4, 0.3, 1e-2, SolverKind::Mica);    // soft tissue at a haptic rate
    add(1e9, 0.499, 5e-2, SolverKind::Mica);  // stiffest, nearly incompressible, longest step
    add(1e2, 0.45, 1e-3, SolverKind::Mica);   // softest, small step
    add(1e6, 0, 5e-2, SolverKind::Mica);      // stiff, compressible, long step
    add(1e3, 0.49, 1e-4, SolverKind::Mica);   // soft, nearly incompressible, the smallest step
    add(1e6, 0.49, 1e-2, SolverKind::Direct); // the exact reference
    // MICA's factored sweep (with its refactor on demand) at both ends of the stiffness range.
    add(1e4, 0.3, 1e-2, SolverKind::Mica, MicaSweep::Factored);
    add(1e9, 0.499, 5e-2, SolverKind::Mica, MicaSweep::Factored);
  }
  return out;
}

void run_scenario(char letter) {
  const Scenario* s = nullptr;
  for (const Scenario& x : kScenarios)
    if (x.letter == letter) s = &x;
  assert_non_null(s);
  int failed = 0, known = 0, runs = 0, nonconverged_runs = 0;
  double cpu = 0;
  std::vector<std::string> lines;
  for (const Case& c : cases_for(*s)) {
    Result r = s->run(c);
    classify(r);
    g_csv.write(r);
    ++runs;
    cpu += r.cpu_s;
    nonconverged_runs += r.nonconverged > 0;
    known += r.status == "known";
    if (r.status == "FAIL") ++failed;
    for (const std::string& f : r.failures) lines.push_back(std::string(r.status == "known" ? "known: " : "FAIL: ") + f);
    if (getenv("MICA_STRESS_TRACE"))
      print_message("%s steps %d nonconv %d hidden %d res %.2g it/step %.1f energy %.3g (solver %.3g all %.3g) rec %.3g pen %.3g nc %.3g "
                    "limit %.3g contacts %d/%d inv %d/%d recovery %d/%d vmax %.3g %.2fs %s%s\n",
                    c.label().c_str(), r.steps, r.nonconverged, r.hidden_nonconverged, r.residual, r.steps ? double(r.iterations) / r.steps : 0.0,
                    r.energy_ratio, r.energy_ratio_solver, r.energy_ratio_all, r.recovery_ratio, r.penetration,
                    r.penetration_nonconverged, r.penetration_limit, r.max_contacts, r.max_rows,
                    r.inverted_start, r.max_inverted, r.recovery_steps, r.recovery_budget, r.max_speed, r.cpu_s,
                    r.status.c_str(), r.notes.c_str());
  }
  print_message("scenario %c: %d runs in %.1f s of CPU, %d with non-converged steps, %d failed, %d known failures%s\n",
                letter, runs, cpu, nonconverged_runs, failed, known, strict_mode() ? " (strict)" : "");
  for (const std::string& l : lines) print_message("  %s\n", l.c_str());
  if (failed) fail_msg("scenario %c: %d of %d runs failed", letter, failed, runs);
}

}  // namespace

static void test_a_fall_on_static_slab(void**) { run_scenario('a'); }
static void test_b_sphere_indent_half_depth(void**) { run_scenario('b'); }
static void test_c_twist_and_release(void**) { run_scenario('c'); }
static void test_d_inverted_start(void**) { run_scenario('d'); }
static void test_e_sliver_elements(void**) { run_scenario('e'); }
static void test_f_many_contacts(void**) { run_scenario('f'); }
static void test_g_projection_and_contact(void**) { run_scenario('g'); }
static void test_h_fast_tool_thin_slab(void**) { run_scenario('h'); }
static void test_i_two_bodies_pressed(void**) { run_scenario('i'); }

int main(int argc, char** argv) {
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    if (a == "--full") {
      g_options.full = true;
    } else if (a == "--direct") {
      g_options.direct_only = true;
    } else if (a == "--only" && k + 1 < argc) {
      g_options.only = argv[++k];
    } else if (a == "--csv" && k + 1 < argc) {
      g_options.csv = argv[++k];
    } else {
      std::fprintf(stderr, "usage: %s [--full] [--direct] [--only LETTERS] [--csv PATH]\n", argv[0]);
      return 2;
    }
  }
  g_csv.open(g_options.csv);
  const struct CMUnitTest all[] = {
      cmocka_unit_test(test_a_fall_on_static_slab),   cmocka_unit_test(test_b_sphere_indent_half_depth),
      cmocka_unit_test(test_c_twist_and_release),     cmocka_unit_test(test_d_inverted_start),
      cmocka_unit_test(test_e_sliver_elements),       cmocka_unit_test(test_f_many_contacts),
      cmocka_unit_test(test_g_projection_and_contact), cmocka_unit_test(test_h_fast_tool_thin_slab),
      cmocka_unit_test(test_i_two_bodies_pressed),
  };
  std::vector<CMUnitTest> chosen;
  for (size_t k = 0; k < sizeof all / sizeof all[0]; ++k) {
    const char letter = all[k].name[5];  // "test_<letter>_..."
    if (g_options.only.empty() || g_options.only.find(letter) != std::string::npos) chosen.push_back(all[k]);
  }
  return _cmocka_run_group_tests(g_options.full ? "stress (full matrix)" : "stress (slice)", chosen.data(),
                                 chosen.size(), nullptr, nullptr);
}
