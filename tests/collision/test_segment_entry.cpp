// SPDX-License-Identifier: Apache-2.0
// Where a segment first enters a tool: closed forms for each shape, and for random segments the
// same answer as marching along the segment with the signed distance, in a rotated, shifted frame.
#include "collision/segment_entry.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

const Eigen::Quaterniond kTurn(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()));
const Vec3 kOrigin(0.3, -0.2, 0.5);

Vec3 world(const Vec3& local) { return kOrigin + kTurn * local; }

Tool posed(ToolShape shape) {
  Tool t;
  t.shape = shape;
  t.position = kOrigin;
  t.orientation = kTurn;
  t.radius = 0.01;
  t.half_length = 0.02;
  t.half_extents = Vec3(0.01, 0.02, 0.03);
  for (int i = 0; i < 8; ++i) t.hull_points.emplace_back(i & 1 ? 0.01 : -0.01, i & 2 ? 0.02 : -0.02, i & 4 ? 0.03 : -0.03);
  t.hull_points.emplace_back(0.0, 0.0, 0.045);  // a roof on the box: faces not along the axes
  prepare_tool_shape(t);
  return t;
}

// The segment (tool frame) enters at t with the outward normal n (tool frame).
void expect_entry(const Tool& tool, const Vec3& a, const Vec3& b, double t, const Vec3& n) {
  SegmentEntry e;
  if (!segment_entry(tool, world(a), world(b), e)) fail_msg("shape %d: no entry found", int(tool.shape));
  assert_near(e.t, t, 1e-12);
  assert_near((e.point - world(a + t * (b - a))).norm(), 0.0, 1e-12);
  assert_near((e.normal - kTurn * n.normalized()).norm(), 0.0, 1e-12);
}

void expect_miss(const Tool& tool, const Vec3& a, const Vec3& b) {
  SegmentEntry e;
  assert_false(segment_entry(tool, world(a), world(b), e));
}

}  // namespace

static void test_closed_forms(void**) {
  const Tool sphere = posed(ToolShape::Sphere);
  expect_entry(sphere, Vec3(0, 0, 0.05), Vec3(0, 0, -0.05), 0.4, Vec3(0, 0, 1));  // through the centre
  expect_entry(sphere, Vec3(0.006, 0.05, 0), Vec3(0.006, -0.05, 0), 0.42, Vec3(0.6, 0.8, 0));  // off-centre
  expect_miss(sphere, Vec3(0.011, 0.05, 0), Vec3(0.011, -0.05, 0));  // beside it
  expect_miss(sphere, Vec3(0, 0, 0.05), Vec3(0, 0, 0.02));           // stops short
  expect_miss(sphere, Vec3(0, 0, 0.02), Vec3(0, 0, 0.05));           // moves away

  const Tool capsule = posed(ToolShape::Capsule);
  expect_entry(capsule, Vec3(0.05, 0, 0.01), Vec3(-0.05, 0, 0.01), 0.4, Vec3(1, 0, 0));   // the side
  expect_entry(capsule, Vec3(0, 0, 0.07), Vec3(0, 0, -0.01), 0.5, Vec3(0, 0, 1));         // the top cap
  expect_entry(capsule, Vec3(0.006, 0, 0.07), Vec3(0.006, 0, -0.07), (0.05 - 0.008) / 0.14, Vec3(0.6, 0, 0.8));
  expect_miss(capsule, Vec3(0.011, 0, 0.07), Vec3(0.011, 0, -0.07));

  const Tool box = posed(ToolShape::Box);
  expect_entry(box, Vec3(0.05, 0.01, 0), Vec3(-0.05, 0.01, 0), 0.4, Vec3(1, 0, 0));
  expect_entry(box, Vec3(0.005, 0.04, 0), Vec3(-0.005, -0.04, 0), 0.25, Vec3(0, 1, 0));  // the +y face
  expect_miss(box, Vec3(0.02, 0.04, 0), Vec3(0.02, -0.04, 0));   // beside the +x face
  expect_miss(box, Vec3(0.05, 0, 0), Vec3(0.011, 0, 0));          // stops short

  const Tool hull = posed(ToolShape::ConvexHull);  // the box with a roof rising to z = 0.045
  expect_entry(hull, Vec3(0.05, 0.01, 0), Vec3(-0.05, 0.01, 0), 0.4, Vec3(1, 0, 0));
  // The roof face over the +x edge: the plane through (0.01, +-0.02, 0.03) and (0, 0, 0.045).
  const Vec3 roof = Vec3(0.015, 0, 0.01).normalized();
  const double offset = roof.dot(Vec3(0.01, 0, 0.03));
  const Vec3 a(0.005, 0, 0.1), b(0.005, 0, 0.0);
  expect_entry(hull, a, b, (roof.dot(a) - offset) / roof.dot(a - b), roof);

  expect_miss(posed(ToolShape::Plane), Vec3(0, 0, 0.05), Vec3(0, 0, -0.05));  // a plane has no far side
}

// Random segments against every shape: the entry is the first point of the segment with a
// signed distance <= 0 (found by marching), lies on the surface, and its normal supports the
// tool (the whole tool is behind the tangent plane there: what a contact built on it relies on).
static void test_random_segments_against_marching(void**) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.06, 0.06);
  for (ToolShape shape : {ToolShape::Sphere, ToolShape::Capsule, ToolShape::Box, ToolShape::ConvexHull}) {
    const Tool tool = posed(shape);
    // Points that span the tool (its core, for the rounded shapes) for the supporting-plane test.
    Vec3List core;
    double rounding = 0;
    if (shape == ToolShape::Sphere) core = {world(Vec3::Zero())}, rounding = tool.radius;
    if (shape == ToolShape::Capsule) core = {world(Vec3(0, 0, 0.02)), world(Vec3(0, 0, -0.02))}, rounding = tool.radius;
    if (shape == ToolShape::Box || shape == ToolShape::ConvexHull)
      for (const Vec3& v : tool.hull_points) core.push_back(world(v));
    if (shape == ToolShape::Box) core.pop_back();  // the roof point belongs to the hull only
    int hits = 0, misses = 0;
    for (int k = 0; k < 400; ++k) {
      // From anywhere around the tool to near the opposite side: about as many hits as misses.
      const Vec3 la(u(rng), u(rng), u(rng));
      const Vec3 a = world(la), b = world(-la + 0.5 * Vec3(u(rng), u(rng), u(rng)));
      if (closest_surface_point(tool, a).distance <= 0) continue;  // starts inside: not its case
      const int N = 4000;
      int first = -1;
      for (int i = 0; i <= N && first < 0; ++i)
        if (closest_surface_point(tool, a + (double(i) / N) * (b - a)).distance <= 0) first = i;
      SegmentEntry e;
      const bool found = segment_entry(tool, a, b, e);
      if (first < 0) {
        // Marching can step over a grazing pass: then the entry, if any, is a near tangent.
        if (found) assert_le(closest_surface_point(tool, a + (e.t + 1.0 / N) * (b - a)).distance, 1e-4);
        misses += !found;
        continue;
      }
      if (!found) fail_msg("shape %d, segment %d: marching enters at %d/%d, segment_entry finds nothing", int(shape), k,
                           first, N);
      ++hits;
      assert_true(e.t <= double(first) / N + 1e-12 && e.t >= double(first - 1) / N - 1e-12);
      assert_near((e.point - (a + e.t * (b - a))).norm(), 0.0, 1e-12);
      assert_near(closest_surface_point(tool, e.point).distance, 0.0, 1e-12);
      assert_near(e.normal.norm(), 1.0, 1e-12);
      assert_true(e.normal.dot(b - a) < 0);  // entering
      for (const Vec3& c : core) assert_le(e.normal.dot(c - e.point), -rounding + 1e-12);
    }
    print_message("shape %d: %d entries, %d misses\n", int(shape), hits, misses);
    assert_true(hits > 50 && misses > 10);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_closed_forms),
      cmocka_unit_test(test_random_segments_against_marching),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
