// SPDX-License-Identifier: Apache-2.0
// The colourings behind the parallel step: nodes (the colour-ordered MBGS sweep) and elements
// (parallel assembly) are valid on structured boxes and on the nidus mesh, and the checks catch
// an invalid colouring.
#include "fem/element_colouring.hpp"
#include "solver/node_colouring.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

void check_mesh(const TetMesh& mesh, const char* what) {
  const int32_t n = int32_t(mesh.nodes.size()), ne = int32_t(mesh.tets.size());
  const BlockPattern p = build_block_pattern(n, mesh.tets);
  int32_t max_degree = 0;
  for (int32_t i = 0; i < n; ++i) max_degree = std::max(max_degree, p.row_start[i + 1] - p.row_start[i] - 1);
  // Single nodes and tets (the plain colouring), and the blocks the world uses.
  for (int32_t scale : {0, 1}) {
    const int32_t node_block = scale ? block_size_for(n, 8, 512) : 1;
    const int32_t tet_block = scale ? block_size_for(ne, 16, 1024) : 1;
    const Colouring nodes = colour_nodes(p, node_block);
    const Colouring elements = colour_elements(mesh.tets, n, tet_block);
    assert_true(is_valid_node_colouring(p, nodes));
    assert_true(is_valid_element_colouring(mesh.tets, n, elements));
    assert_int_equal(nodes.items(), n);
    assert_int_equal(elements.items(), ne);
    // Greedy first-fit on single nodes needs at most (max degree + 1) colours.
    if (!scale) assert_true(nodes.colours() <= max_degree + 1);
    int32_t smallest = nodes.blocks();
    for (int32_t c = 0; c < nodes.colours(); ++c) smallest = std::min(smallest, nodes.start[c + 1] - nodes.start[c]);
    print_message("%s: %d nodes in %d blocks of %d, %d colours (fewest blocks in a colour %d; max degree %d); "
                  "%d tets in %d blocks of %d, %d colours\n",
                  what, n, nodes.blocks(), node_block, nodes.colours(), smallest, max_degree, ne, elements.blocks(),
                  tet_block, elements.colours());
    // Within a colour, ascending block order (locality of the sweep).
    for (int32_t c = 0; c < nodes.colours(); ++c)
      for (int32_t k = nodes.start[c] + 1; k < nodes.start[c + 1]; ++k)
        assert_true(nodes.order[k - 1] < nodes.order[k]);
  }
}

}  // namespace

static void test_box_colourings_are_valid(void**) {
  check_mesh(make_box_grid(Vec3(0, 0, 0), Vec3(1, 1, 1), {1, 1, 1}, 5), "1 cell x 5");
  check_mesh(make_box_grid(Vec3(0, 0, 0), Vec3(1, 1, 1), {5, 4, 3}, 5), "5x4x3 x 5");
  check_mesh(make_box_grid(Vec3(0, 0, 0), Vec3(0.1, 0.1, 0.1), {12, 12, 12}, 6), "12^3 x 6");
}

static void test_nidus_colourings_are_valid(void**) {
  check_mesh(load_mesh(std::string(MICA_TEST_DATA_DIR) + "/../../data/nidus/nidus.msh"), "nidus");
}

static void test_invalid_colourings_are_caught(void**) {
  const TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(1, 1, 1), {2, 2, 2}, 6);
  const int32_t n = int32_t(mesh.nodes.size()), ne = int32_t(mesh.tets.size());
  const BlockPattern p = build_block_pattern(n, mesh.tets);
  // Every block in one colour: coupled nodes (tets sharing a node) in different blocks of it.
  for (int32_t size : {1, 4}) {
    Colouring one;
    one.block_start = uniform_blocks(n, size);
    for (int32_t b = 0; b < one.blocks(); ++b) one.order.push_back(b);
    one.start = {0, one.blocks()};
    assert_false(is_valid_node_colouring(p, one));
    Colouring all_tets;
    all_tets.block_start = uniform_blocks(ne, size);
    for (int32_t b = 0; b < all_tets.blocks(); ++b) all_tets.order.push_back(b);
    all_tets.start = {0, all_tets.blocks()};
    assert_false(is_valid_element_colouring(mesh.tets, n, all_tets));
  }
  // One block holding everything is valid (the serial loop).
  const Colouring whole = colour_nodes(p, n);
  assert_int_equal(whole.colours(), 1);
  assert_true(is_valid_node_colouring(p, whole));
  // A block listed twice, a block missing, blocks not covering the items.
  Colouring c = colour_nodes(p, 2);
  c.order[1] = c.order[0];
  assert_false(is_valid_node_colouring(p, c));
  Colouring e = colour_elements(mesh.tets, n, 3);
  e.order.pop_back();
  --e.start.back();
  assert_false(is_valid_element_colouring(mesh.tets, n, e));
  Colouring short_blocks = colour_nodes(p, 2);
  short_blocks.block_start.back() -= 1;
  assert_false(is_valid_node_colouring(p, short_blocks));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_box_colourings_are_valid),
      cmocka_unit_test(test_nidus_colourings_are_valid),
      cmocka_unit_test(test_invalid_colourings_are_caught),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
