// SPDX-License-Identifier: Apache-2.0
// The embedding update's plan (normals_plan.hpp) and its kernels: for triangles in a coherent order
// (a grid's strips) and in a random order, in blocks from 1 triangle to more than the mesh has,
// every vertex is placed once, before its first block; it is finished once, after its last; no two
// vertices in use at once share a scratch slot; every triangle is summed once, in its orientation,
// most in pairs sharing an edge where a block holds both; and the kernels run in the plan's order
// give the normals of a plain sum over the triangles (1e-13).
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <set>
#include <random>

#include "embedding/normals_plan.hpp"
#include "embedding/vertex_normals.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

struct Surface {
  std::vector<double> xyz;
  std::vector<int32_t> triangles;
  int32_t vertices() const { return int32_t(xyz.size() / 3); }
};

// An n x n grid of vertices on a bumpy sheet, two triangles per cell, cells row by row (shuffled:
// the triangles in a random order), and one vertex in no triangle.
Surface sheet(int32_t n, bool shuffled) {
  Surface s;
  for (int32_t j = 0; j < n; ++j)
    for (int32_t i = 0; i < n; ++i) {
      const double x = 0.01 * i, y = 0.01 * j;
      s.xyz.insert(s.xyz.end(), {x, y, 0.002 * std::sin(300 * x) * std::cos(200 * y)});
    }
  s.xyz.insert(s.xyz.end(), {0.5, 0.5, 0.5});
  std::vector<std::array<int32_t, 3>> tris;
  for (int32_t j = 0; j + 1 < n; ++j)
    for (int32_t i = 0; i + 1 < n; ++i) {
      const int32_t v = j * n + i;
      tris.push_back({v, v + 1, v + n + 1});
      tris.push_back({v, v + n + 1, v + n});
    }
  if (shuffled) std::shuffle(tris.begin(), tris.end(), std::mt19937(5));
  for (const auto& t : tris) s.triangles.insert(s.triangles.end(), t.begin(), t.end());
  return s;
}

// A triangle turned to start at its least vertex (the same triangle, the same orientation).
std::array<int32_t, 3> canonical(std::array<int32_t, 3> t) {
  std::rotate(t.begin(), std::min_element(t.begin(), t.end()), t.end());
  return t;
}

std::vector<double> plain_normals(const Surface& s) {
  std::vector<double> n(s.xyz.size(), 0.0);
  for (size_t t = 0; t < s.triangles.size(); t += 3) {
    const auto p = [&](int k) { return Vec3(&s.xyz[3 * size_t(s.triangles[t + size_t(k)])]); };
    const Vec3 face = (p(1) - p(0)).cross(p(2) - p(0));
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) n[3 * size_t(s.triangles[t + size_t(k)]) + size_t(a)] += face[a];
  }
  for (size_t i = 0; i < n.size(); i += 3) {
    const double length = Vec3(&n[i]).norm();
    for (int a = 0; a < 3; ++a) n[i + size_t(a)] = length > 0 ? n[i + size_t(a)] / length : 0.0;
  }
  return n;
}

void check(const Surface& s, int32_t block, bool shuffled) {
  const int32_t n = s.vertices(), t = int32_t(s.triangles.size() / 3);
  const NormalsPlan p = plan_normals(s.triangles.data(), t, n, block);
  assert_int_equal(p.blocks(), (t + block - 1) / block);
  // Every vertex once in the order; the vertex in no triangle before the first block.
  std::vector<int32_t> sorted = p.order;
  std::sort(sorted.begin(), sorted.end());
  std::vector<int32_t> all(static_cast<size_t>(n));
  std::iota(all.begin(), all.end(), 0);
  assert_true(sorted == all);
  assert_int_equal(p.first_start[0], 1);
  assert_int_equal(p.order[0], n - 1);
  assert_int_equal(int32_t(p.last.size()), n - 1);

  // Replays the plan: a vertex is placed before any triangle uses it, used only while placed and
  // not finished, finished once after its last use; its slot is its own while it is in use.
  std::vector<int32_t> state(size_t(n), 0);  // 0 not placed, 1 in use, 2 finished
  std::vector<int32_t> owner(size_t(p.slots), -1);
  std::vector<NormalSlot> scratch(size_t(p.slots));
  std::vector<double> normals(s.xyz.size(), -7.0);
  std::multiset<std::array<int32_t, 3>> planned;  // the triangles the plan names, as it runs
  int32_t pairs = 0;
  for (int32_t k = 0; k < p.blocks(); ++k) {
    for (int32_t j = p.first_start[size_t(k)]; j < p.first_start[size_t(k) + 1]; ++j) {
      const int32_t v = p.order[size_t(j)], slot = p.slot[size_t(j)];
      assert_int_equal(state[size_t(v)], 0);
      assert_int_equal(owner[size_t(slot)], -1);
      state[size_t(v)] = 1, owner[size_t(slot)] = v;
      std::copy_n(&s.xyz[3 * size_t(v)], 3, scratch[size_t(slot)].xyz);
      std::fill_n(scratch[size_t(slot)].normal, 4, 0.0);
    }
    const auto named = [&](int32_t slot) {
      const int32_t v = owner[size_t(slot)];
      assert_true(v >= 0 && state[size_t(v)] == 1);
      return v;
    };
    for (int32_t q = p.pair_start[size_t(k)]; q < p.pair_start[size_t(k) + 1]; ++q) {
      const int32_t* c = &p.pairs[4 * size_t(q)];
      planned.insert(canonical({named(c[0]), named(c[1]), named(c[2])}));
      planned.insert(canonical({named(c[0]), named(c[2]), named(c[3])}));
    }
    for (int32_t t = p.single_start[size_t(k)]; t < p.single_start[size_t(k) + 1]; ++t) {
      const int32_t* c = &p.singles[3 * size_t(t)];
      planned.insert(canonical({named(c[0]), named(c[1]), named(c[2])}));
    }
    pairs += p.pair_start[size_t(k) + 1] - p.pair_start[size_t(k)];
    add_pair_normals(scratch.data(), p.pairs.data() + 4 * size_t(p.pair_start[size_t(k)]),
                     p.pair_start[size_t(k) + 1] - p.pair_start[size_t(k)]);
    add_triangle_normals(scratch.data(), p.singles.data() + 3 * size_t(p.single_start[size_t(k)]),
                         p.single_start[size_t(k) + 1] - p.single_start[size_t(k)]);
    const int32_t first = p.last_start[size_t(k)], count = p.last_start[size_t(k) + 1] - first;
    for (int32_t j = first; j < first + count; ++j) {
      const int32_t v = p.last[size_t(j)], slot = p.last_slot[size_t(j)];
      assert_int_equal(state[size_t(v)], 1);
      assert_int_equal(owner[size_t(slot)], v);
    }
    finish_normals(scratch.data(), p.last.data() + first, p.last_slot.data() + first, count, normals.data());
    for (int32_t j = first; j < first + count; ++j) {
      state[size_t(p.last[size_t(j)])] = 2;
      owner[size_t(p.last_slot[size_t(j)])] = -1;
    }
  }
  for (int32_t v = 0; v + 1 < n; ++v) assert_int_equal(state[size_t(v)], 2);
  // The plan named the given triangles, each once, in their orientation; most of them in pairs
  // (all but a few at the blocks' edges and the grid's border).
  std::multiset<std::array<int32_t, 3>> given;
  for (size_t c = 0; c < s.triangles.size(); c += 3)
    given.insert(canonical({s.triangles[c], s.triangles[c + 1], s.triangles[c + 2]}));
  assert_true(planned == given);
  assert_int_equal(p.triangles, t);
  if (block >= 64 && (!shuffled || block >= t)) assert_true(2 * pairs > 9 * t / 10);
  const std::vector<double> expected = plain_normals(s);
  for (int32_t v = 0; v + 1 < n; ++v)
    for (int a = 0; a < 3; ++a) assert_near(normals[3 * size_t(v) + size_t(a)], expected[3 * size_t(v) + size_t(a)], 1e-13);
}

}  // namespace

static void test_the_plan_places_sums_and_finishes_each_vertex_once(void**) {
  const struct {
    bool shuffled;
    int32_t block;
  } cases[] = {{false, 1}, {false, 5}, {false, 64}, {false, 2048}, {true, 1}, {true, 7}, {true, 64}, {true, 2048}};
  for (const auto& c : cases) check(sheet(23, c.shuffled), c.block, c.shuffled);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_the_plan_places_sums_and_finishes_each_vertex_once),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
