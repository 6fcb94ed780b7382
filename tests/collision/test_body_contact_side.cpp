// SPDX-License-Identifier: Apache-2.0
// Body against body (collide_bodies): a node outside the other body, beside one of its edges or
// corners, is outside with a positive gap, whichever of the triangles sharing that edge the search
// meets first; a node inside is inside.
#include "collision/contact.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

// Body b: a 10 cm box sheared by x += y / 2, so that its top-right and bottom-left edges (along z)
// are sharp (63 degrees): there a node beside the side face lies above the top face's plane.
struct Obstacle {
  Vec3List x;
  std::vector<Tri> surface;
  std::vector<int32_t> nodes;
  TriangleBvh bvh;
  SurfacePseudoNormals normals;

  Obstacle() {
    const TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), {2, 2, 2}, 6);
    x = mesh.nodes;
    for (Vec3& p : x) p.x() += 0.5 * p.y();
    surface = extract_surface(mesh);
    nodes = surface_nodes(surface);
    bvh.build(x, surface);
    normals.build(surface, x.size());
  }
  SurfaceView view() const { return {-1, 2, &x, &surface, &nodes, &bvh, &normals, 0.05, 0.0}; }
};

const Vec3 kTop(0, 1, 0), kBottom(0, -1, 0), kBack(0, 0, -1);
const Vec3 kRight = Vec3(1, -0.5, 0).normalized(), kLeft = Vec3(-1, 0.5, 0).normalized();

// Nodes at distance s from a feature point q of the obstacle, in directions of its normal cone
// (non-negative mixes of the normals of the faces meeting there): q is their nearest point.
void add_around(const Vec3& q, const std::vector<Vec3>& faces, double s, Vec3List& x, std::vector<Vec3>& directions) {
  std::mt19937 rng(uint32_t(x.size()) + 3);
  std::uniform_real_distribution<double> weight(0.0, 1.0);
  for (int k = 0; k < 40; ++k) {
    Vec3 m = Vec3::Zero();
    for (const Vec3& n : faces) m += weight(rng) * n;
    m.normalize();
    x.push_back(q + s * m);
    directions.push_back(m);
  }
}

}  // namespace

static void test_nodes_beside_sharp_edges_and_corners_are_outside(void**) {
  const Obstacle b;
  Vec3List x;
  std::vector<Vec3> directions;
  const double s = 0.01;
  for (double z : {0.013, 0.05, 0.081}) {
    add_around(Vec3(0.15, 0.1, z), {kTop, kRight}, s, x, directions);   // sharp top-right edge
    add_around(Vec3(0.0, 0.0, z), {kBottom, kLeft}, s, x, directions);  // sharp bottom-left edge
  }
  add_around(Vec3(0.15, 0.1, 0), {kTop, kRight, kBack}, s, x, directions);  // a corner
  std::vector<int32_t> nodes(x.size());
  for (size_t i = 0; i < x.size(); ++i) nodes[i] = int32_t(i);
  const SurfaceView a{0, 1, &x, nullptr, &nodes, nullptr, nullptr, 0.01, 0.0};

  std::vector<Contact> contacts;
  collide_bodies(a, b.view(), 0.05, 0.0, contacts);
  assert_int_equal(contacts.size(), x.size());  // every node is within the margin
  int wrong = 0;
  for (const Contact& c : contacts) {
    const int32_t i = c.a.nodes[0];
    if (!(std::fabs(c.gap - s) < 1e-12 && (c.normal - directions[i]).norm() < 1e-9)) {
      if (wrong++ < 5)
        print_message("node %d at (%.4f, %.4f, %.4f), %g m outside: gap %.4g, normal (%.3f, %.3f, %.3f)\n", i,
                      x[i].x(), x[i].y(), x[i].z(), s, c.gap, c.normal.x(), c.normal.y(), c.normal.z());
    }
  }
  assert_int_equal(wrong, 0);
}

// The same places mirrored inside the box (q - s m, m in the normal cone of a sharp edge) are
// inside, as deep as their distance to the surface.
static void test_nodes_inside_near_edges_are_inside(void**) {
  const Obstacle b;
  Vec3List x;
  for (double z : {0.03, 0.05, 0.07})
    for (double t : {0.2, 0.5, 0.8}) {
      const Vec3 m = ((1 - t) * kTop + t * kRight).normalized();
      x.push_back(Vec3(0.15, 0.1, z) - 0.004 * m);
    }
  std::vector<int32_t> nodes(x.size());
  for (size_t i = 0; i < x.size(); ++i) nodes[i] = int32_t(i);
  const SurfaceView a{0, 1, &x, nullptr, &nodes, nullptr, nullptr, 0.01, 0.0};
  std::vector<Contact> contacts;
  collide_bodies(a, b.view(), 0.001, 0.0, contacts);
  assert_int_equal(contacts.size(), x.size());
  for (const Contact& c : contacts) {
    // Inside: the distance to the nearer of the two faces.
    const Vec3& p = x[c.a.nodes[0]];
    const double depth = std::min(0.1 - p.y(), -kRight.dot(p - Vec3(0.15, 0.1, 0)));
    assert_near(c.gap, -depth, 1e-12);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_nodes_beside_sharp_edges_and_corners_are_outside),
      cmocka_unit_test(test_nodes_inside_near_edges_are_inside),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
