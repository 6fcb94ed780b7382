// SPDX-License-Identifier: Apache-2.0
// GJK's distance and closest points between convex polytopes against closed forms: boxes apart
// along an axis and across an edge, a point and a box, a segment and a triangle, touching and
// overlapping shapes; each case also turned and shifted (the distance must not change).
#include "collision/gjk.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

// A convex polytope as its corners; its support is the farthest corner.
struct Polytope {
  std::vector<Vec3> corners;
  Vec3 operator()(const Vec3& d) const {
    Vec3 best = corners[0];
    for (const Vec3& c : corners)
      if (c.dot(d) > best.dot(d)) best = c;
    return best;
  }
  Polytope moved(const Eigen::Quaterniond& q, const Vec3& t) const {
    Polytope p;
    for (const Vec3& c : corners) p.corners.push_back(q * c + t);
    return p;
  }
};

Polytope box(const Vec3& centre, const Vec3& half) {
  Polytope p;
  for (int i = 0; i < 8; ++i)
    p.corners.push_back(centre + Vec3(i & 1 ? half.x() : -half.x(), i & 2 ? half.y() : -half.y(), i & 4 ? half.z() : -half.z()));
  return p;
}

struct Case {
  const char* name;
  Polytope a, b;
  double distance;  // m; 0: intersecting
};

}  // namespace

static void test_distances_match_closed_forms(void**) {
  const Vec3 half(0.5, 0.5, 0.5);
  const Case cases[] = {
      {"boxes 1 m apart along x", box(Vec3::Zero(), half), box(Vec3(2, 0, 0), half), 1.0},
      {"boxes apart across an edge", box(Vec3::Zero(), half), box(Vec3(2, 2, 0), half), std::sqrt(2.0)},
      {"boxes apart across a corner", box(Vec3::Zero(), half), box(Vec3(2, 2, 2), half), std::sqrt(3.0)},
      {"a point above a box's face", Polytope{{Vec3(0.1, 0.2, 3)}}, box(Vec3::Zero(), half), 2.5},
      {"a segment over a triangle", Polytope{{Vec3(-1, 0.2, 0.7), Vec3(1, 0.2, 0.7)}},
       Polytope{{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}}, 0.7},
      {"boxes touching face to face", box(Vec3::Zero(), half), box(Vec3(1, 0.3, 0), half), 0.0},
      {"boxes overlapping", box(Vec3::Zero(), half), box(Vec3(0.4, 0.1, -0.2), half), 0.0},
  };
  const Eigen::Quaterniond turns[] = {Eigen::Quaterniond::Identity(),
                                      Eigen::Quaterniond(Eigen::AngleAxisd(0.9, Vec3(1, -2, 0.5).normalized()))};
  for (const Case& c : cases)
    for (const Eigen::Quaterniond& q : turns) {
      const Vec3 shift(0.3, -1.7, 2.2);
      const Polytope a = c.a.moved(q, shift), b = c.b.moved(q, shift);
      const GjkResult g = gjk_distance(a, b, Vec3(1, 0.1, 0.2), 1e-12);
      print_message("%s: distance %.17g (expected %.17g), intersecting %d\n", c.name, g.distance, c.distance,
                    int(g.intersecting));
      if (c.distance == 0) {
        assert_true(g.intersecting);
        continue;
      }
      assert_false(g.intersecting);
      assert_near(g.distance, c.distance, 1e-12);
      // The closest points lie on the shapes' hulls and are `distance` apart.
      assert_near((g.point_a - g.point_b).norm(), c.distance, 1e-12);
      // ... and nothing of B is nearer to A's point along their line: the separation is tight.
      const Vec3 n = (g.point_a - g.point_b) / g.distance;
      assert_near(n.dot(b(n) - g.point_b), 0.0, 1e-12);
      assert_near(n.dot(a(-n) - g.point_a), 0.0, 1e-12);
    }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_distances_match_closed_forms),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
