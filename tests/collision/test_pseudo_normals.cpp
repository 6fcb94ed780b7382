// SPDX-License-Identifier: Apache-2.0
// Angle-weighted pseudo-normals tell inside from outside at every nearest point of a closed
// surface, faces, edges and corners alike, where one face normal does not.
#include <map>
#include <random>

#include "collision/closest_point.hpp"
#include "collision/pseudo_normals.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

// A 10 cm box grid sheared so that its faces x = lo and x = hi lean over by half their height:
// the edges along z on one side are sharp (dihedral angle 63 degrees) and obtuse on the other.
struct ShearedBox {
  Vec3List x;
  std::vector<Tri> surface;
  static constexpr double kShear = 0.5;

  ShearedBox() {
    const TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), {2, 2, 2}, 6);
    surface = extract_surface(mesh);
    x = mesh.nodes;
    for (Vec3& p : x) p.x() += kShear * p.y();
  }
  // Inside the sheared box (analytic).
  static bool contains(const Vec3& p) {
    const double u = p.x() - kShear * p.y();
    return u > 0 && u < 0.1 && p.y() > 0 && p.y() < 0.1 && p.z() > 0 && p.z() < 0.1;
  }
};

struct Nearest {
  int32_t tri;
  TrianglePoint point;
};

Nearest nearest(const Vec3List& x, const std::vector<Tri>& surface, const Vec3& p) {
  Nearest best{-1, {}};
  double d = HUGE_VAL;
  for (size_t f = 0; f < surface.size(); ++f) {
    const Tri& t = surface[f];
    const TrianglePoint q = closest_on_triangle(p, x[t[0]], x[t[1]], x[t[2]]);
    if ((p - q.point).norm() < d) {
      d = (p - q.point).norm();
      best = {int32_t(f), q};
    }
  }
  return best;
}

Vec3 face_normal(const Vec3List& x, const Tri& t) { return (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]).normalized(); }

struct SignCheck {
  int checked = 0, wrong = 0, face_wrong = 0, on_edges = 0;
};

// Random points around the box (inside(p): the analytic test at its current pose), none within
// 0.1 mm of its surface: how often the pseudo-normal's sign and the nearest face's sign are wrong.
template <class Inside>
SignCheck check_signs(const ShearedBox& box, const SurfacePseudoNormals& normals, Inside inside, uint32_t seed) {
  std::mt19937 rng(seed);
  Vec3 lo = Vec3::Constant(HUGE_VAL), hi = Vec3::Constant(-HUGE_VAL);
  for (const Vec3& p : box.x) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  std::uniform_real_distribution<double> u(-0.3, 1.3);
  SignCheck c;
  for (int k = 0; k < 20000; ++k) {
    const Vec3 p = lo + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(hi - lo);
    const Nearest n = nearest(box.x, box.surface, p);
    if ((p - n.point.point).norm() < 1e-4) continue;
    const Tri& t = box.surface[n.tri];
    const Vec3 face = face_normal(box.x, t);
    const Vec3 d = p - n.point.point;
    c.wrong += (d.dot(normals.at(n.tri, n.point.weights, face, box.x, box.surface)) > 0) == inside(p);
    c.face_wrong += (d.dot(face) > 0) == inside(p);
    c.on_edges += (n.point.weights.array() == 0).any();
    ++c.checked;
  }
  print_message("%d points, %d nearest on an edge or corner; sign wrong: pseudo-normal %d, face normal %d\n",
                c.checked, c.on_edges, c.wrong, c.face_wrong);
  return c;
}

}  // namespace

// The pseudo-normal's sign agrees with the analytic inside test for every point; the nearest
// face's normal does not (near the sharp edges).
static void test_sign_matches_inside_everywhere(void**) {
  const ShearedBox box;
  SurfacePseudoNormals normals;
  normals.build(box.surface, box.x.size());
  const SignCheck c = check_signs(box, normals, [](const Vec3& p) { return ShearedBox::contains(p); }, 7);
  assert_int_equal(c.wrong, 0);
  assert_true(c.on_edges > 1000);
  assert_true(c.face_wrong > 0);  // the case the pseudo-normals exist for does occur here
}

// The pseudo-normals of a moved surface are those of its new pose (nothing of the old one kept).
static void test_normals_follow_the_surface(void**) {
  ShearedBox box;
  SurfacePseudoNormals normals;
  normals.build(box.surface, box.x.size());
  const Mat3 turn = Eigen::AngleAxisd(2.0, Vec3(1, -2, 3).normalized()).matrix();
  const Vec3 shift(0.3, -0.1, 0.2);
  for (Vec3& p : box.x) p = turn * p + shift;
  const SignCheck c = check_signs(
      box, normals, [&](const Vec3& p) { return ShearedBox::contains(turn.transpose() * (p - shift)); }, 8);
  assert_int_equal(c.wrong, 0);
  assert_true(c.face_wrong > 0);
}

// Against their definition summed by one pass over the whole surface (Baerentzen and Aanaes: a
// corner's normal is the sum over its faces of the face's angle there times its unit normal, an
// edge's the sum of its two faces' unit normals), on a jittered box: every corner and edge of
// every triangle, to the bit (the same terms in the same triangle order).
static void test_matches_a_pass_over_the_surface(void**) {
  ShearedBox box;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.004, 0.004);
  for (Vec3& p : box.x) p += Vec3(jitter(rng), jitter(rng), jitter(rng));
  SurfacePseudoNormals normals;
  normals.build(box.surface, box.x.size());
  Vec3List corner(box.x.size(), Vec3::Zero());
  std::map<std::pair<int32_t, int32_t>, Vec3> edge;
  for (const Tri& t : box.surface) {
    const Vec3 unit = face_normal(box.x, t);
    for (int k = 0; k < 3; ++k) {
      const Vec3 u = box.x[t[(k + 1) % 3]] - box.x[t[k]], v = box.x[t[(k + 2) % 3]] - box.x[t[k]];
      corner[t[k]] += std::atan2(u.cross(v).norm(), u.dot(v)) * unit;
      const auto key = std::minmax(t[k], t[(k + 1) % 3]);
      edge.emplace(key, Vec3::Zero()).first->second += unit;
    }
  }
  int checked = 0;
  for (size_t f = 0; f < box.surface.size(); ++f) {
    const Tri& t = box.surface[f];
    const Vec3 face = face_normal(box.x, t);
    assert_true(normals.at(int32_t(f), Vec3(0.2, 0.3, 0.5), face, box.x, box.surface) == face);
    for (int k = 0; k < 3; ++k) {
      Vec3 at_corner = Vec3::Zero(), on_edge = Vec3::Constant(0.5);
      at_corner[k] = 1;
      on_edge[(k + 2) % 3] = 0;  // the edge from corner k to k + 1
      assert_true(normals.at(int32_t(f), at_corner, face, box.x, box.surface) == corner[t[k]]);
      const Vec3 e = edge.at(std::minmax(t[k], t[(k + 1) % 3]));
      assert_true(normals.at(int32_t(f), on_edge, face, box.x, box.surface) == e);
      checked += 2;
    }
  }
  print_message("%d corners and edges of %zu triangles: the same bits\n", checked, box.surface.size());
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_sign_matches_inside_everywhere),
      cmocka_unit_test(test_normals_follow_the_surface),
      cmocka_unit_test(test_matches_a_pass_over_the_surface),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
