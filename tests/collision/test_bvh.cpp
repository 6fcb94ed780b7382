// SPDX-License-Identifier: Apache-2.0
// The triangle AABB tree returns exactly the triangles whose boxes overlap a query box, before and
// after refitting to moved vertices.
#include "collision/bvh.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

std::vector<int32_t> brute_force(const Vec3List& x, const std::vector<Tri>& tris, const Aabb& box) {
  std::vector<int32_t> hits;
  for (size_t t = 0; t < tris.size(); ++t)
    if (Aabb::of(x[tris[t][0]], x[tris[t][1]], x[tris[t][2]]).overlaps(box)) hits.push_back(int32_t(t));
  return hits;
}

std::vector<int32_t> tree_query(const TriangleBvh& bvh, const Aabb& box) {
  std::vector<int32_t> hits;
  bvh.query(box, [&](int32_t t) { hits.push_back(t); });
  std::sort(hits.begin(), hits.end());
  assert_true(std::adjacent_find(hits.begin(), hits.end()) == hits.end());  // each triangle once
  return hits;
}

// Random boxes of all sizes around [lo, hi], each answered as by brute force; returns the total hits.
size_t check_queries(const TriangleBvh& bvh, const Vec3List& x, const std::vector<Tri>& tris, std::mt19937& rng) {
  std::uniform_real_distribution<double> centre(-0.2, 1.2), half(0.0, 0.3);
  size_t total = 0;
  for (int q = 0; q < 400; ++q) {
    Aabb box;
    box.add(Vec3(centre(rng), centre(rng), centre(rng)));
    box = box.inflated(q % 10 == 0 ? 0.0 : half(rng));  // some boxes are points
    const std::vector<int32_t> expected = brute_force(x, tris, box);
    const std::vector<int32_t> got = tree_query(bvh, box);
    if (got != expected)
      fail_msg("query %d: %zu triangles, brute force %zu", q, got.size(), expected.size());
    total += got.size();
  }
  return total;
}

}  // namespace

static void test_query_matches_brute_force(void**) {
  const TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(1, 0.8, 0.6), {6, 5, 4}, 6);
  const std::vector<Tri> tris = extract_surface(mesh);
  Vec3List x = mesh.nodes;
  TriangleBvh bvh;
  bvh.build(x, tris);
  assert_true(bvh.node_count() >= tris.size() / TriangleBvh::kLeafSize);
  std::mt19937 rng(5);
  assert_true(check_queries(bvh, x, tris, rng) > 1000);

  // Every triangle is found by a box around the whole body, and by its own box.
  assert_int_equal(tree_query(bvh, bvh.bounds()).size(), tris.size());
  for (size_t t = 0; t < tris.size(); t += 7) {
    const std::vector<int32_t> hits = tree_query(bvh, Aabb::of(x[tris[t][0]], x[tris[t][1]], x[tris[t][2]]));
    assert_true(std::binary_search(hits.begin(), hits.end(), int32_t(t)));
  }

  // Bend and shake the body: the refitted tree still answers exactly.
  std::normal_distribution<double> shake(0, 0.02);
  for (Vec3& p : x) p += Vec3(0.3 * std::sin(3 * p.z()), 0.2 * p.x() * p.x(), 0) + Vec3(shake(rng), shake(rng), shake(rng));
  bvh.refit(x);
  assert_true(check_queries(bvh, x, tris, rng) > 1000);
  for (const Vec3& p : x) assert_true(bvh.bounds().contains(p));
}

static void test_small_and_degenerate_sets(void**) {
  TriangleBvh bvh;
  const Vec3List x = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  bvh.build(x, {});
  assert_true(bvh.empty());
  int visits = 0;
  bvh.query(Aabb{Vec3::Constant(-1e9), Vec3::Constant(1e9)}, [&](int32_t) { ++visits; });
  assert_int_equal(visits, 0);
  bvh.refit(x);

  bvh.build(x, {{0, 1, 2}});
  assert_int_equal(tree_query(bvh, Aabb::of(Vec3(0.2, 0.2, 0), Vec3(0.3, 0.3, 0), Vec3(0.3, 0.3, 0))).size(), 1);
  assert_int_equal(tree_query(bvh, Aabb::of(Vec3(0.2, 0.2, 0.1), Vec3(0.3, 0.3, 0.1), Vec3(0.3, 0.3, 0.1))).size(), 0);
  // Touching boxes overlap.
  assert_int_equal(tree_query(bvh, Aabb::of(Vec3(1, 0, 0), Vec3(2, 1, 0), Vec3(2, 1, 0))).size(), 1);

  // Many copies of one triangle: every centroid is the same, the split must still terminate.
  const std::vector<Tri> copies(37, Tri{1, 2, 3});
  bvh.build(x, copies);
  assert_int_equal(tree_query(bvh, Aabb::of(Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(1, 1, 1))).size(), 37);

  bool thrown = false;
  try {
    bvh.build(x, {{0, 1, 4}});
  } catch (const Error& e) {
    thrown = e.code() == Errc::OutOfRange;
  }
  assert_true(thrown);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_query_matches_brute_force),
      cmocka_unit_test(test_small_and_degenerate_sets),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
