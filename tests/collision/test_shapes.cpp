// SPDX-License-Identifier: Apache-2.0
// Tool shapes: signed distances and normals against closed forms in rotated and translated frames,
// the convex hull against the box and against a sampled surface, validation, and bounds.
#include "collision/tool.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

const Eigen::Quaterniond kTurn(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
const Vec3 kOrigin(0.3, -0.2, 0.5);

Tool posed(ToolShape shape) {
  Tool t;
  t.shape = shape;
  t.position = kOrigin;
  t.orientation = kTurn;
  return t;
}

Vec3 world(const Vec3& local) { return kOrigin + kTurn * local; }

// The tool's answer at `local` (tool frame) matches distance d and normal n (tool frame).
void expect_point(const Tool& t, const Vec3& local, double d, const Vec3& n) {
  const SurfacePoint s = closest_surface_point(t, world(local));
  assert_near(s.distance, d, 1e-14);
  assert_near((s.normal - kTurn * n.normalized()).norm(), 0.0, 1e-12);
}

Vec3List cube_corners(const Vec3& h) {
  Vec3List v;
  for (int i = 0; i < 8; ++i) v.emplace_back(i & 1 ? h.x() : -h.x(), i & 2 ? h.y() : -h.y(), i & 4 ? h.z() : -h.z());
  return v;
}

// Runs `f`, which must throw mica::Error with `code` and a message containing `text`.
template <class F>
void expect_error(F f, Errc code, const char* text) {
  try {
    f();
  } catch (const Error& e) {
    if (e.code() != code) fail_msg("error code %d, wanted %d: \"%s\"", int(e.code()), int(code), e.what());
    if (std::string(e.what()).find(text) == std::string::npos)
      fail_msg("message \"%s\" does not name \"%s\"", e.what(), text);
    return;
  }
  fail_msg("no mica::Error thrown; wanted one naming \"%s\"", text);
}

void expect_invalid(const Tool& t, const char* field) {
  Tool copy = t;
  expect_error([&] { prepare_tool_shape(copy); }, Errc::InvalidArgument, field);
}

}  // namespace

static void test_sphere(void**) {
  Tool t = posed(ToolShape::Sphere);
  t.radius = 0.02;
  prepare_tool_shape(t);
  expect_point(t, Vec3(0.03, 0.04, 0), 0.03, Vec3(0.6, 0.8, 0));     // outside
  expect_point(t, Vec3(0, 0, -0.005), -0.015, Vec3(0, 0, -1));       // inside
  expect_point(t, Vec3(0, 0.02, 0), 0.0, Vec3(0, 1, 0));             // on
  assert_near(closest_surface_point(t, kOrigin).distance, -0.02, 1e-15);  // centre: any normal
}

static void test_capsule(void**) {
  Tool t = posed(ToolShape::Capsule);
  t.radius = 0.01;
  t.half_length = 0.02;
  prepare_tool_shape(t);
  expect_point(t, Vec3(0.03, 0, 0.005), 0.02, Vec3(1, 0, 0));          // beside the segment
  expect_point(t, Vec3(0, -0.004, -0.01), -0.006, Vec3(0, -1, 0));     // inside, beside
  expect_point(t, Vec3(0, 0, 0.05), 0.02, Vec3(0, 0, 1));              // beyond the top cap
  expect_point(t, Vec3(0.01, 0, -0.03), std::sqrt(2.0) * 0.01 - 0.01, Vec3(1, 0, -1));  // around the bottom cap
  expect_point(t, Vec3(0, 0.01, 0.02), 0.0, Vec3(0, 1, 0));            // on the rim
  assert_near(closest_surface_point(t, world(Vec3(0, 0, 0.015))).distance, -0.01, 1e-15);  // on the axis
}

static void test_box(void**) {
  Tool t = posed(ToolShape::Box);
  t.half_extents = Vec3(0.01, 0.02, 0.03);
  prepare_tool_shape(t);
  expect_point(t, Vec3(0.015, 0.005, -0.01), 0.005, Vec3(1, 0, 0));             // facing a face
  expect_point(t, Vec3(0.013, 0.024, 0), 0.005, Vec3(0.6, 0.8, 0));             // facing an edge
  expect_point(t, Vec3(0.012, -0.022, 0.032), 0.002 * std::sqrt(3.0), Vec3(1, -1, 1));  // a corner
  expect_point(t, Vec3(0.008, 0, 0), -0.002, Vec3(1, 0, 0));                    // inside, nearest +x
  expect_point(t, Vec3(0, -0.015, 0.001), -0.005, Vec3(0, -1, 0));              // inside, nearest -y
  expect_point(t, Vec3(0.002, 0.001, -0.029), -0.001, Vec3(0, 0, -1));          // inside, nearest -z
  expect_point(t, Vec3(0.01, 0.003, 0.004), 0.0, Vec3(1, 0, 0));                // on a face
}

static void test_plane(void**) {
  Tool t = posed(ToolShape::Plane);
  t.plane_normal = Vec3(0, 0, 2);  // prepare normalises it
  prepare_tool_shape(t);
  assert_near(t.plane_normal.norm(), 1.0, 1e-15);
  expect_point(t, Vec3(0.1, 0.2, 0.03), 0.03, Vec3(0, 0, 1));
  expect_point(t, Vec3(-5, 7, -0.25), -0.25, Vec3(0, 0, 1));
  expect_point(t, Vec3(3, -1, 0), 0.0, Vec3(0, 0, 1));
}

static void test_hull_of_cube_is_the_box(void**) {
  const Vec3 h(0.01, 0.02, 0.03);
  Tool box = posed(ToolShape::Box);
  box.half_extents = h;
  Tool hull = posed(ToolShape::ConvexHull);
  hull.hull_points = cube_corners(h);
  // Points on faces, on edges, inside and repeated change nothing.
  hull.hull_points.push_back(Vec3(0, 0, 0.03));
  hull.hull_points.push_back(Vec3(0.01, 0.005, -0.01));
  hull.hull_points.push_back(Vec3(0.01, 0.02, 0));
  hull.hull_points.push_back(Vec3(0.001, -0.002, 0.003));
  hull.hull_points.push_back(h);
  prepare_tool_shape(box);
  prepare_tool_shape(hull);
  assert_int_equal(hull.hull->faces.size(), 6);
  assert_int_equal(hull.hull->vertices.size(), 8);
  for (const HullFace& f : hull.hull->faces) assert_int_equal(f.polygon.size(), 4);

  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  int inside = 0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3 p = world(Vec3(u(rng), u(rng), u(rng)));
    const SurfacePoint a = closest_surface_point(box, p), b = closest_surface_point(hull, p);
    assert_near(b.distance, a.distance, 1e-12);
    assert_near((b.normal - a.normal).norm(), 0.0, 1e-12);
    inside += a.distance < 0;
  }
  assert_true(inside > 20);  // both branches were exercised
}

// The hull of random points against an independent brute force: its faces are the triples of
// points with every point on one side, sampled on a barycentric grid.
static void test_hull_against_sampled_surface(void**) {
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0, 1);
  Tool t = posed(ToolShape::ConvexHull);
  for (int i = 0; i < 24; ++i) {
    const Vec3 d(g(rng), g(rng), g(rng));
    t.hull_points.push_back(0.05 * d.normalized() * (0.6 + 0.4 * std::abs(g(rng)) / 3));
  }
  prepare_tool_shape(t);

  const Vec3List& p = t.hull_points;
  Vec3List samples;
  std::vector<std::pair<Vec3, double>> planes;  // outward normal, offset
  const int N = 40;
  double longest = 0;
  for (size_t i = 0; i < p.size(); ++i)
    for (size_t j = i + 1; j < p.size(); ++j)
      for (size_t k = j + 1; k < p.size(); ++k) {
        Vec3 n = (p[j] - p[i]).cross(p[k] - p[i]).normalized();
        int above = 0, below = 0;
        for (const Vec3& x : p) {
          const double s = n.dot(x - p[i]);
          above += s > 1e-12;
          below += s < -1e-12;
        }
        if (above && below) continue;
        if (above) n = -n;
        planes.emplace_back(kTurn * n, n.dot(p[i]));
        longest = std::max({longest, (p[j] - p[i]).norm(), (p[k] - p[j]).norm(), (p[i] - p[k]).norm()});
        for (int a = 0; a <= N; ++a)
          for (int b = 0; a + b <= N; ++b)
            samples.push_back(world((double(N - a - b) * p[i] + double(a) * p[j] + double(b) * p[k]) / N));
      }
  assert_true(planes.size() >= 4);

  std::uniform_real_distribution<double> u(-0.07, 0.07);
  int inside = 0;
  for (int q = 0; q < 300; ++q) {
    const Vec3 x = world(Vec3(u(rng), u(rng), u(rng)));
    const SurfacePoint s = closest_surface_point(t, x);
    double nearest = HUGE_VAL;
    for (const Vec3& y : samples) nearest = std::min(nearest, (x - y).norm());
    bool in = true;
    for (const auto& [n, offset] : planes) in = in && n.dot(x - kOrigin) <= offset;
    assert_true((s.distance < 0) == in);
    inside += in;
    // The samples are never nearer than the surface, and at most one grid step farther.
    assert_le(std::abs(s.distance), nearest + 1e-12);
    assert_le(nearest, std::abs(s.distance) + longest / N);
    // Going back along the normal by the distance lands on the surface.
    assert_near(s.normal.norm(), 1.0, 1e-12);
    assert_near(closest_surface_point(t, x - s.distance * s.normal).distance, 0.0, 1e-12);
  }
  assert_true(inside > 10 && inside < 290);
}

static void test_prepare_rejects_bad_shapes(void**) {
  Tool t;
  t.radius = -0.01;
  expect_invalid(t, "radius");
  t.radius = NAN;
  expect_invalid(t, "radius");
  t.shape = ToolShape::Capsule;
  t.radius = 0.01;
  t.half_length = 0;
  expect_invalid(t, "half_length");
  t.half_length = HUGE_VAL;
  expect_invalid(t, "half_length");
  t.shape = ToolShape::Box;
  t.half_extents = Vec3(0.01, 0, 0.01);
  expect_invalid(t, "half_extents[1]");
  t.shape = ToolShape::Plane;
  t.plane_normal = Vec3::Zero();
  expect_invalid(t, "plane_normal");
  t.plane_normal = Vec3(0, NAN, 1);
  expect_invalid(t, "plane_normal");

  t.shape = ToolShape::ConvexHull;
  t.hull_points = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  expect_invalid(t, "hull_points");  // too few
  t.hull_points.push_back(Vec3(1, 1, 0));
  expect_invalid(t, "hull_points");  // coplanar
  t.hull_points.push_back(Vec3(0.5, 0.5, 1e-9));
  expect_invalid(t, "hull_points");  // nearly coplanar
  t.hull_points.back() = Vec3(0.5, 0.5, NAN);
  expect_invalid(t, "hull_points[4]");
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  t.hull_points.clear();
  for (size_t i = 0; i < kMaxHullPoints; ++i) t.hull_points.emplace_back(u(rng), u(rng), u(rng));
  Tool ok = t;
  prepare_tool_shape(ok);  // the largest allowed hull
  assert_non_null(ok.hull.get());
  t.hull_points.emplace_back(0, 0, 0);
  expect_invalid(t, "hull_points");  // one too many

  // A hull that was never prepared is refused rather than guessed.
  Tool raw = posed(ToolShape::ConvexHull);
  raw.hull_points = cube_corners(Vec3(1, 1, 1));
  expect_error([&] { closest_surface_point(raw, Vec3::Zero()); }, Errc::WrongState, "prepare_tool_shape");
  // Other shapes drop stale hull data.
  ok.shape = ToolShape::Sphere;
  prepare_tool_shape(ok);
  assert_null(ok.hull.get());
}

static void test_bounds(void**) {
  auto expect_box = [](const Aabb& b, const Vec3& lo, const Vec3& hi) {
    assert_near((b.lo - lo).norm(), 0.0, 1e-14);
    assert_near((b.hi - hi).norm(), 0.0, 1e-14);
  };
  const double m = 0.001;
  Tool s = posed(ToolShape::Sphere);
  s.radius = 0.02;
  expect_box(tool_bounds(s, m), kOrigin - Vec3::Constant(0.021), kOrigin + Vec3::Constant(0.021));

  Tool c = posed(ToolShape::Capsule);
  c.radius = 0.01;
  c.half_length = 0.03;
  const Vec3 e1 = world(Vec3(0, 0, 0.03)), e2 = world(Vec3(0, 0, -0.03));
  expect_box(tool_bounds(c, m), e1.cwiseMin(e2) - Vec3::Constant(0.011), e1.cwiseMax(e2) + Vec3::Constant(0.011));

  // A rotated box and the hull of its corners are bounded by the corners.
  const Vec3 h(0.01, 0.02, 0.03);
  Aabb corners;
  for (const Vec3& v : cube_corners(h)) corners.add(world(v));
  Tool b = posed(ToolShape::Box);
  b.half_extents = h;
  expect_box(tool_bounds(b, m), corners.lo - Vec3::Constant(m), corners.hi + Vec3::Constant(m));
  Tool hull = posed(ToolShape::ConvexHull);
  hull.hull_points = cube_corners(h);
  expect_box(tool_bounds(hull, m), corners.lo - Vec3::Constant(m), corners.hi + Vec3::Constant(m));

  const Aabb plane = tool_bounds(posed(ToolShape::Plane), m);
  assert_true(plane.contains(Vec3(1e6, -1e6, 1e6)));
  assert_true(plane.overlaps(corners));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_sphere),
      cmocka_unit_test(test_capsule),
      cmocka_unit_test(test_box),
      cmocka_unit_test(test_plane),
      cmocka_unit_test(test_hull_of_cube_is_the_box),
      cmocka_unit_test(test_hull_against_sampled_surface),
      cmocka_unit_test(test_prepare_rejects_bad_shapes),
      cmocka_unit_test(test_bounds),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
