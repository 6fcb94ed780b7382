// SPDX-License-Identifier: Apache-2.0
// Tool against one triangle: closed-form sphere and plane contacts, MPR for boxes, hulls and
// capsules against known depths, all in a rotated and translated scene.
#include "collision/triangle_contact.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

// The scene is built in local coordinates (triangles mostly in z = 0, tools above) and then
// rotated and shifted as a whole: answers must not depend on the axes.
const Mat3 kQ = Eigen::AngleAxisd(0.9, Vec3(-1, 2, 0.5).normalized()).matrix();
const Vec3 kShift(0.4, -0.3, 0.25);

Vec3 W(const Vec3& local) { return kShift + kQ * local; }
Vec3 Wdir(const Vec3& local) { return kQ * local.normalized(); }

Tool tool_at(ToolShape shape, const Vec3& centre, const Mat3& turn = Mat3::Identity()) {
  Tool t;
  t.shape = shape;
  t.position = W(centre);
  t.orientation = Eigen::Quaterniond(kQ * turn);
  return t;
}

Tool box_at(const Vec3& centre, const Vec3& h, const Mat3& turn) {
  Tool t = tool_at(ToolShape::Box, centre, turn);
  t.half_extents = h;
  prepare_tool_shape(t);
  return t;
}

Tool hull_box_at(const Vec3& centre, const Vec3& h, const Mat3& turn) {
  Tool t = tool_at(ToolShape::ConvexHull, centre, turn);
  for (int i = 0; i < 8; ++i) t.hull_points.emplace_back(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z());
  prepare_tool_shape(t);
  return t;
}

struct Triangle {
  Vec3 a, b, c;  // world
};
Triangle triangle(const Vec3& a, const Vec3& b, const Vec3& c) { return {W(a), W(b), W(c)}; }
const Triangle kSmall = triangle(Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0, 0.1, 0));
const Triangle kLarge = triangle(Vec3(-0.2, -0.2, 0), Vec3(0.3, -0.2, 0), Vec3(0, 0.3, 0));

// Collides and checks what every hit must satisfy: weights in [0, 1] summing to 1 that give the
// point, and a unit normal.
bool collide(const Tool& tool, const Triangle& t, double margin, TriangleHit& hit) {
  if (!collide_triangle(tool, t.a, t.b, t.c, margin, hit)) return false;
  assert_near(hit.weights.sum(), 1.0, 1e-12);
  for (int k = 0; k < 3; ++k) {
    assert_true(hit.weights[k] >= 0);
    assert_true(hit.weights[k] <= 1);
  }
  assert_near((hit.point - (hit.weights[0] * t.a + hit.weights[1] * t.b + hit.weights[2] * t.c)).norm(), 0.0, 1e-12);
  assert_near(hit.normal.norm(), 1.0, 1e-12);
  return true;
}

void expect_vec(const Vec3& got, const Vec3& want, double tol) { assert_near((got - want).norm(), 0.0, tol); }

}  // namespace

static void test_sphere_over_interior(void**) {
  Tool s = tool_at(ToolShape::Sphere, Vec3(0.02, 0.03, 0.015));
  s.radius = 0.01;
  TriangleHit hit;
  assert_true(collide(s, kSmall, 0.01, hit));
  assert_near(hit.gap, 0.005, 1e-15);
  expect_vec(hit.weights, Vec3(0.5, 0.2, 0.3), 1e-12);  // barycentric of the projected centre
  expect_vec(hit.point, W(Vec3(0.02, 0.03, 0)), 1e-15);
  expect_vec(hit.normal, Wdir(Vec3(0, 0, -1)), 1e-12);  // the triangle is pushed down, away from the tool

  s.position = W(Vec3(0.02, 0.03, 0.004));  // penetrating
  assert_true(collide(s, kSmall, 0.0, hit));
  assert_near(hit.gap, -0.006, 1e-15);
  expect_vec(hit.normal, Wdir(Vec3(0, 0, -1)), 1e-12);
}

static void test_sphere_on_edge_and_vertex(void**) {
  Tool s = tool_at(ToolShape::Sphere, Vec3(0.04, -0.006, 0.008));  // 0.01 from the edge point (0.04, 0, 0)
  s.radius = 0.0105;
  TriangleHit hit;
  assert_true(collide(s, kSmall, 0.0, hit));
  assert_near(hit.gap, -0.0005, 1e-15);
  expect_vec(hit.weights, Vec3(0.6, 0.4, 0), 1e-12);
  expect_vec(hit.normal, Wdir(Vec3(0, 0.6, -0.8)), 1e-12);

  s.position = W(Vec3(-0.006, -0.008, 0));  // beside vertex a, in the triangle's plane
  assert_true(collide(s, kSmall, 0.0, hit));
  assert_near(hit.gap, -0.0005, 1e-15);
  expect_vec(hit.weights, Vec3(1, 0, 0), 0);
  expect_vec(hit.normal, Wdir(Vec3(0.6, 0.8, 0)), 1e-12);
}

static void test_sphere_beyond_margin(void**) {
  Tool s = tool_at(ToolShape::Sphere, Vec3(0.02, 0.03, 0.0252));
  s.radius = 0.01;
  TriangleHit hit{Vec3(7, 7, 7), Vec3(7, 7, 7), Vec3(7, 7, 7), 7};
  assert_false(collide(s, kSmall, 0.015, hit));
  assert_near(hit.gap, 7, 0);  // untouched
  assert_true(collide(s, kSmall, 0.0153, hit));
  assert_near(hit.gap, 0.0152, 1e-15);
}

static void test_plane(void**) {
  Tool p = tool_at(ToolShape::Plane, Vec3::Zero());
  prepare_tool_shape(p);
  TriangleHit hit;
  const Triangle tilted = triangle(Vec3(0, 0, 0.01), Vec3(0.1, 0, 0.03), Vec3(0, 0.1, -0.004));
  assert_true(collide(p, tilted, 0.0, hit));
  assert_near(hit.gap, -0.004, 1e-15);
  expect_vec(hit.weights, Vec3(0, 0, 1), 0);  // the deepest vertex
  expect_vec(hit.normal, Wdir(Vec3(0, 0, 1)), 1e-12);

  const Triangle flat = triangle(Vec3(0, 0, 0.002), Vec3(0.1, 0, 0.002), Vec3(0, 0.1, 0.002));
  assert_true(collide(p, flat, 0.005, hit));
  assert_near(hit.gap, 0.002, 1e-15);
  expect_vec(hit.weights, Vec3::Constant(1.0 / 3), 1e-15);  // level: the centroid
  assert_false(collide(p, flat, 0.0019, hit));

  const Triangle edge_down = triangle(Vec3(0, 0, -0.003), Vec3(0.1, 0, -0.003), Vec3(0, 0.1, 0.01));
  assert_true(collide(p, edge_down, 0.0, hit));
  assert_near(hit.gap, -0.003, 1e-15);
  expect_vec(hit.weights, Vec3(0.5, 0.5, 0), 1e-15);
}

static void test_box_face_into_triangle(void**) {
  const Vec3 h(0.02, 0.03, 0.01);
  const Mat3 turn = Eigen::AngleAxisd(0.3, Vec3::UnitZ()).matrix();
  const double depth = 0.002;
  const Vec3 centre(0.01, 0.02, h.z() - depth);
  for (const Tool& box : {box_at(centre, h, turn), hull_box_at(centre, h, turn)}) {
    for (double margin : {0.0, 0.001}) {
      TriangleHit hit;
      assert_true(collide(box, kLarge, margin, hit));
      assert_near(hit.gap, -depth, 1e-6 * depth);
      expect_vec(hit.normal, Wdir(Vec3(0, 0, -1)), 1e-6);
      // The contact point is under the box.
      const Vec3 local = kQ.transpose() * (hit.point - kShift);
      assert_near(local.z(), 0.0, 1e-12);
      assert_le((local - Vec3(centre.x(), centre.y(), 0)).norm(), h.head<2>().norm() + margin);
    }
  }
}

static void test_box_near_and_beyond_margin(void**) {
  const Vec3 h(0.02, 0.03, 0.01);
  const Mat3 turn = Eigen::AngleAxisd(-0.4, Vec3::UnitZ()).matrix();
  TriangleHit hit;
  for (const Tool& box : {box_at(Vec3(0.0, 0.01, h.z() + 0.0007), h, turn), hull_box_at(Vec3(0.0, 0.01, h.z() + 0.0007), h, turn)}) {
    assert_true(collide(box, kLarge, 0.001, hit));  // 0.7 mm apart: inside the 1 mm margin
    assert_near(hit.gap, 0.0007, 1e-6 * 0.0007);
    expect_vec(hit.normal, Wdir(Vec3(0, 0, -1)), 1e-6);
    assert_false(collide(box, kLarge, 0.0005, hit));
    assert_false(collide(box, kLarge, 0.0, hit));
  }
  // Far to the side of the triangle.
  assert_false(collide(box_at(Vec3(0.5, 0.5, 0), h, turn), kLarge, 0.01, hit));
}

static void test_box_corner_into_triangle(void**) {
  const Vec3 h = Vec3::Constant(0.01);
  // Corner (1, 1, 1) h points straight down.
  const Mat3 turn = Eigen::Quaterniond::FromTwoVectors(Vec3(1, 1, 1), Vec3(0, 0, -1)).matrix();
  const double depth = 0.001;
  const Vec3 centre(0.02, -0.05, h.norm() - depth);
  for (const Tool& box : {box_at(centre, h, turn), hull_box_at(centre, h, turn)}) {
    TriangleHit hit;
    assert_true(collide(box, kLarge, 0.0, hit));
    assert_near(hit.gap, -depth, 1e-6 * depth);
    expect_vec(hit.normal, Wdir(Vec3(0, 0, -1)), 1e-6);
    // The point is where the corner pierces the triangle (within the small cross-section there).
    assert_le((hit.point - W(Vec3(centre.x(), centre.y(), 0))).norm(), 3 * depth);
  }
}

static void test_capsule(void**) {
  const double r = 0.01, depth = 0.001;
  // Lying along local x.
  Tool lying = tool_at(ToolShape::Capsule, Vec3(0.02, 0.02, r - depth), Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()).matrix());
  lying.radius = r;
  lying.half_length = 0.03;
  prepare_tool_shape(lying);
  TriangleHit hit;
  assert_true(collide(lying, kLarge, 0.0, hit));
  assert_near(hit.gap, -depth, 1e-6 * depth);
  expect_vec(hit.normal, Wdir(Vec3(0, 0, -1)), 1e-6);

  // Standing on its cap: a curved contact, so MPR converges to its tolerance.
  Tool standing = tool_at(ToolShape::Capsule, Vec3(0.05, -0.02, 0.03 + r - depth));
  standing.radius = r;
  standing.half_length = 0.03;
  prepare_tool_shape(standing);
  assert_true(collide(standing, kLarge, 0.0, hit));
  assert_near(hit.gap, -depth, 1e-6 * depth);
  expect_vec(hit.normal, Wdir(Vec3(0, 0, -1)), 1e-6);
  expect_vec(hit.point, W(Vec3(0.05, -0.02, 0)), 3 * depth);

  // Beside the triangle's edge but within the margin.
  standing.position = W(Vec3(0.05, -0.2 - r - 0.0004, 0.0));
  assert_true(collide(standing, kLarge, 0.001, hit));
  assert_near(hit.gap, 0.0004, 1e-6 * 0.0004);
  expect_vec(hit.normal, Wdir(Vec3(0, 1, 0)), 1e-6);
  assert_false(collide(standing, kLarge, 0.0003, hit));
}

// Random tools near random triangles, against brute force: a miss means every sampled triangle
// point is at least the margin away; a near hit has the sampled distance; a penetration is the
// least translation (moving the triangle by it along the normal separates, by a little less along
// the normal or any other direction does not).
static void test_random_contacts(void**) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1, 1);
  auto shift = [](const Triangle& t, const Vec3& d) { return Triangle{t.a + d, t.b + d, t.c + d}; };
  const double margin = 0.002;
  for (ToolShape shape : {ToolShape::Capsule, ToolShape::Box, ToolShape::ConvexHull}) {
    int misses = 0, near = 0, deep = 0;
    for (int trial = 0; trial < 300; ++trial) {
      Tool t;
      t.shape = shape;
      t.radius = 0.01;
      t.half_length = 0.02;
      t.half_extents = Vec3(0.01, 0.02, 0.015);
      for (int i = 0; shape == ToolShape::ConvexHull && i < 12; ++i)
        t.hull_points.emplace_back(0.02 * u(rng), 0.02 * u(rng), 0.02 * u(rng));
      t.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(3 * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()));
      prepare_tool_shape(t);
      const Triangle tri{0.05 * Vec3(u(rng), u(rng), u(rng)), 0.05 * Vec3(u(rng), u(rng), u(rng)),
                         0.05 * Vec3(u(rng), u(rng), u(rng))};
      t.position = (tri.a + tri.b + tri.c) / 3 + 0.03 * Vec3(u(rng), u(rng), u(rng));

      const int N = 40;
      const double step = std::max({(tri.b - tri.a).norm(), (tri.c - tri.b).norm(), (tri.a - tri.c).norm()}) / N;
      double sampled = HUGE_VAL;
      for (int i = 0; i <= N; ++i)
        for (int j = 0; i + j <= N; ++j)
          sampled = std::min(sampled, closest_surface_point(t, (double(N - i - j) * tri.a + double(i) * tri.b + double(j) * tri.c) / N).distance);

      TriangleHit hit, moved;
      if (!collide(t, tri, margin, hit)) {
        ++misses;
        assert_le(margin, sampled + 1e-12);
      } else if (hit.gap >= 0) {
        ++near;
        assert_le(hit.gap, sampled + 1e-12);
        assert_le(sampled, hit.gap + step);
        assert_near(closest_surface_point(t, hit.point).distance, hit.gap, 1e-12);
        // Closing the gap along the normal makes them touch.
        assert_true(collide(t, shift(tri, -(1 + 1e-6) * hit.gap * hit.normal), 0.0, moved));
        assert_false(collide(t, shift(tri, -(1 - 1e-6) * hit.gap * hit.normal), 0.0, moved));
      } else {
        ++deep;
        const double depth = -hit.gap;
        assert_false(collide(t, shift(tri, (1 + 1e-6) * depth * hit.normal), 0.0, moved));
        assert_true(collide(t, shift(tri, (1 - 1e-6) * depth * hit.normal), 0.0, moved));
        for (int k = 0; k < 20; ++k) {
          const Vec3 d = Vec3(u(rng), u(rng), u(rng)).normalized();
          assert_true(collide(t, shift(tri, (1 - 1e-6) * depth * d), 0.0, moved));
        }
      }
    }
    assert_true(misses > 20 && near > 5 && deep > 20);  // every case was exercised
  }
}

// A triangle of a body blown up by a grab handle posed 1e64 m away (fuzz/corpus/recording/
// found_mpr_cycling_body_at_1e73_m), under a 1 cm box: libccd's MPR cycled in its portal
// discovery, which has no iteration cap, and the step never returned. With its support calls
// counted the query returns, and a pair MPR cannot settle gives no contact.
static void test_degenerate_triangle_returns(void**) {
  Tool box;
  box.shape = ToolShape::Box;
  box.half_extents = Vec3::Constant(0.01);
  box.position = Vec3(0.10015, 0, 0);
  prepare_tool_shape(box);
  const Vec3 a(1.4877236944454553e+72, -1.1624127265189352e+73, -3.5724952235689926e+72);
  const Vec3 b(-0.049960000000000018, -0.10000000000000001, 0.050000000000000003);
  const Vec3 c(0.050040000000000001, 2.6735502617500154e+64, 0.050000000000000003);
  TriangleHit hit;
  assert_false(collide_triangle(box, a, b, c, 4.003999999999837e-05, hit));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_sphere_over_interior),
      cmocka_unit_test(test_sphere_on_edge_and_vertex),
      cmocka_unit_test(test_sphere_beyond_margin),
      cmocka_unit_test(test_plane),
      cmocka_unit_test(test_box_face_into_triangle),
      cmocka_unit_test(test_box_near_and_beyond_margin),
      cmocka_unit_test(test_box_corner_into_triangle),
      cmocka_unit_test(test_capsule),
      cmocka_unit_test(test_random_contacts),
      cmocka_unit_test(test_degenerate_triangle_returns),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
