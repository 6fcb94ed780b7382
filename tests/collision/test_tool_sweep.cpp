// SPDX-License-Identifier: Apache-2.0
// Tool contacts of a tool that moved: a tool that went past part of a thin slab in one step keeps
// it on the side it was on at the step's start (the contacts' normals point there, and meeting
// them leaves the tool behind); a tool that moves a little keeps the nearest-point contacts.
#include "collision/contact.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

constexpr double kH = 0.01;  // s

// The slab of the stress scenario h: 10 x 0.4 x 10 cm, 1 cm cells.
struct Slab {
  Vec3List x;
  std::vector<Tri> surface;
  std::vector<int32_t> nodes;
  TriangleBvh bvh;
  SurfacePseudoNormals normals;

  Slab() {
    const TetMesh mesh = make_box_grid(Vec3(-0.05, -0.004, -0.05), Vec3(0.05, 0, 0.05), {10, 1, 10}, 5);
    x = mesh.nodes;
    surface = extract_surface(mesh);
    nodes = surface_nodes(surface);
    bvh.build(x, surface);
    normals.build(surface, x.size());
  }
  SurfaceView view() const { return {0, 1, &x, &surface, &nodes, &bvh, &normals, 0.002, 0.0}; }
};

// A tool moved from `from` to `to` in one step of kH (turned by `turn` about its origin).
Tool moved(Tool t, const Vec3& from, const Vec3& to, const Eigen::Quaterniond& turn = Eigen::Quaterniond::Identity()) {
  t.margin = 1e-3;
  t.previous_position = from;
  t.position = to;
  t.previous_orientation = t.orientation;
  t.orientation = turn * t.orientation;
  t.velocity = (to - from) / kH;
  const Eigen::AngleAxisd aa(turn);
  t.angular_velocity = aa.axis() * aa.angle() / kH;
  prepare_tool_shape(t);
  return t;
}

// Whether x's path relative to the tool (from where it was relative to the tool at the start to
// x, the tool at its new pose) meets the tool: marched finely, by the signed distance.
bool path_meets(const Tool& tool, const Vec3& x) {
  const Mat3 turn = (tool.orientation * tool.previous_orientation.conjugate()).toRotationMatrix();
  const Vec3 start = tool.position + turn * (x - tool.previous_position);
  for (int i = 0; i <= 2000; ++i)
    if (closest_surface_point(tool, start + (i / 2000.0) * (x - start)).distance <= 0) return true;
  return false;
}

struct Checked {
  int swept = 0;     // nodes whose path meets the tool
  int contacts = 0;  // of them with a contact
};

// Every node whose path meets the tool has a contact that pushes it the way the tool came from
// ahead of it (along the tool's motion at the point), and pushing the node onto the contact's
// plane puts it outside the tool at its new pose, on the side it started.
Checked check_swept_nodes(const Tool& tool, const Slab& slab, const std::vector<Contact>& contacts) {
  Checked c;
  for (int32_t node : slab.nodes) {
    if (!path_meets(tool, slab.x[node])) continue;
    ++c.swept;
    const Contact* found = nullptr;
    for (const Contact& k : contacts)
      if (k.a.count == 1 && k.a.nodes[0] == node) found = &k;
    if (!found) continue;
    ++c.contacts;
    const Vec3 u = tool.velocity + tool.angular_velocity.cross(slab.x[node] - tool.position);
    if (!(found->normal.dot(u) > 0))
      fail_msg("node %d: normal (%.3f, %.3f, %.3f) does not point along the tool's motion", node, found->normal.x(),
               found->normal.y(), found->normal.z());
    const Vec3 pushed = slab.x[node] + std::max(0.0, -found->gap) * found->normal;
    assert_true(closest_surface_point(tool, pushed).distance >= -1e-12);
  }
  return c;
}

}  // namespace

// The stress scenario h at h = 0.01 s: a 1 cm sphere 2 mm above the slab driven 4.2 cm down in
// one step, to 2.6 cm below the slab. Before the sweep the nodes under it were left above its
// centre with positive gaps (nothing held them) or pushed up through it.
static void test_sphere_through_a_slab_keeps_every_node_ahead(void**) {
  const Slab slab;
  Tool sphere;
  sphere.radius = 0.01;
  const Vec3 from(0.003, 0.012, 0.002), to = from - Vec3(0, 0.042, 0);
  const Tool tool = moved(sphere, from, to);
  std::vector<Contact> contacts;
  collide_tool(tool, 0, 7, slab.view(), kH, contacts);
  const Checked c = check_swept_nodes(tool, slab, contacts);
  print_message("%d nodes in the sphere's path, %d with a contact; %zu contacts in all\n", c.swept, c.contacts,
                contacts.size());
  assert_int_equal(c.swept, 6);  // three top nodes within 1 cm of its path, and the three below them
  assert_int_equal(c.contacts, c.swept);
  // Every point a contact holds (nodes, and the points of faces and edges the sphere went
  // through), pushed onto its plane, is out of the sphere's shadow behind it: below its centre,
  // or farther from its path than its radius. Nothing is pushed up.
  for (const Contact& k : contacts) {
    if (!(k.gap < 0)) continue;
    Vec3 p = Vec3::Zero();
    for (int j = 0; j < k.a.count; ++j) p += k.a.weights[j] * slab.x[k.a.nodes[j]];
    const Vec3 pushed = p - k.gap * k.normal;
    assert_true(k.normal.y() <= 0);
    assert_true(pushed.y() < to.y() || std::hypot(pushed.x() - to.x(), pushed.z() - to.z()) >= sphere.radius - 1e-9);
  }
  // Triangle and edge contacts too: the sphere went through faces between the nodes.
  int between = 0;
  for (const Contact& k : contacts) between += k.a.count > 1 && k.gap < 0;
  assert_true(between > 0);
}

// Capsule, box and convex hull, turned in the slab's frame and turning a little as they go:
// every node in the swept path is kept ahead.
static void test_other_shapes_keep_swept_nodes_ahead(void**) {
  const Slab slab;
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.5, Vec3(1, 0, 1).normalized()));
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(0.1, Vec3(0, 1, 0)));
  Tool capsule, box, hull;
  capsule.shape = ToolShape::Capsule;
  capsule.radius = 0.006;
  capsule.half_length = 0.01;
  box.shape = ToolShape::Box;
  box.half_extents = Vec3(0.012, 0.006, 0.009);
  hull.shape = ToolShape::ConvexHull;
  hull.hull_points = {Vec3(0.012, 0, 0), Vec3(-0.01, 0.008, 0), Vec3(-0.01, -0.008, 0.004), Vec3(0, 0, 0.015),
                      Vec3(0.002, 0.003, -0.012)};
  for (Tool* t : {&capsule, &box, &hull}) {
    t->orientation = tilt;
    const Vec3 from(0.004, 0.022, -0.003), to = from - Vec3(0, 0.05, 0);
    const Tool tool = moved(*t, from, to, turn);
    std::vector<Contact> contacts;
    collide_tool(tool, 0, 7, slab.view(), kH, contacts);
    const Checked c = check_swept_nodes(tool, slab, contacts);
    print_message("shape %d: %d nodes in the path, %d with a contact\n", int(tool.shape), c.swept, c.contacts);
    assert_true(c.swept >= 4);
    assert_int_equal(c.contacts, c.swept);
  }
}

// A tool that moves 1 mm into the slab: the sweep changes nothing; the contacts are those of
// the nearest points at the new pose.
static void test_slow_tool_keeps_nearest_point_contacts(void**) {
  const Slab slab;
  Tool sphere;
  sphere.radius = 0.01;
  const Vec3 from(0.003, 0.0105, 0.002), to = from - Vec3(0, 0.001, 0);
  const Tool tool = moved(sphere, from, to);
  std::vector<Contact> contacts;
  collide_tool(tool, 0, 7, slab.view(), kH, contacts);
  int nodes = 0;
  for (const Contact& k : contacts) {
    // Every contact (node, edge or face point) is its point's nearest-point contact at the new pose.
    const SurfacePoint p = closest_surface_point(tool, k.point);
    assert_near(k.gap, p.distance, 1e-15);
    assert_near((k.normal - p.normal).norm(), 0.0, 1e-12);
    if (k.a.count != 1) continue;
    ++nodes;
    const SurfacePoint s = closest_surface_point(tool, slab.x[k.a.nodes[0]]);
    assert_near(k.gap, s.distance, 1e-15);
    assert_near((k.normal - s.normal).norm(), 0.0, 1e-15);
  }
  assert_true(nodes > 0);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_sphere_through_a_slab_keeps_every_node_ahead),
      cmocka_unit_test(test_other_shapes_keep_swept_nodes_ahead),
      cmocka_unit_test(test_slow_tool_keeps_nearest_point_contacts),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
