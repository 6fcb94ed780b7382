// SPDX-License-Identifier: Apache-2.0
// The FEM model's per-node views (fem/fem_model.hpp): the elements that hold each node, and the
// node rotations gathered from them, against a plain scatter over the elements.
#include <cstring>

#include "fem/fem_model.hpp"
#include "fem/rotation.hpp"
#include "mesh/tet_mesh.hpp"
#include "test_util.hpp"

using namespace mica;

static void test_node_elements_list_each_holder_once_in_order(void**) {
  const TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(1, 1, 1), {3, 2, 2}, 6);
  const FemModel m = build_fem_model(mesh, Material{1e4, 0.4, 1000}, MassKind::Consistent, "box");
  std::vector<std::vector<int32_t>> holders(mesh.nodes.size());
  for (size_t e = 0; e < mesh.tets.size(); ++e)
    for (int32_t a : mesh.tets[e]) holders[size_t(a)].push_back(int32_t(e));
  assert_int_equal(m.node_element_start.size(), mesh.nodes.size() + 1);
  for (size_t i = 0; i < holders.size(); ++i) {
    const std::vector<int32_t> listed(m.node_elements.begin() + m.node_element_start[i],
                                      m.node_elements.begin() + m.node_element_start[i + 1]);
    assert_true(listed == holders[i]);
  }
}

// Each node's rotation is the polar factor of the sum of its elements' rotations (scaled to a
// rotation's size), summed in element order as a scatter over the elements would: the same bits.
static void test_node_rotations_are_the_scattered_sums(void**) {
  const TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(1, 1, 1), {3, 3, 2}, 6);
  const FemModel m = build_fem_model(mesh, Material{1e4, 0.4, 1000}, MassKind::Consistent, "box");
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  Vec3List x = m.rest;
  for (Vec3& p : x) p += Vec3(u(rng), u(rng), u(rng));  // a rough deformation: the rotations differ
  std::vector<Mat3> R(m.elements.size()), nodes;
  compute_rotations(m, x, R);
  compute_node_rotations(m, R, nodes);
  std::vector<Mat3> sums(size_t(m.node_count()), Mat3::Zero());
  for (size_t e = 0; e < m.elements.size(); ++e)
    for (int32_t a : m.elements[e].nodes) sums[size_t(a)] += R[e];
  for (size_t i = 0; i < sums.size(); ++i) {
    const Mat3 expected = proper_rotation(Mat3(sums[i] * std::sqrt(3 / sums[i].squaredNorm())));
    assert_memory_equal(nodes[i].data(), expected.data(), sizeof(Mat3));
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_node_elements_list_each_holder_once_in_order),
      cmocka_unit_test(test_node_rotations_are_the_scattered_sums),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
