// The colourings behind the parallel step: nodes (the colour-ordered MBGS sweep) and elements
// (parallel assembly) are valid on structured boxes and on the nidus mesh, and the checks catch
// an invalid colouring.
#include "fem/element_colouring.hpp"
#include "solver/node_colouring.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

void check_mesh(const TetMesh& mesh, const char* what) {
  const int32_t n = int32_t(mesh.nodes.size());
  const BlockPattern p = build_block_pattern(n, mesh.tets);
  const Colouring nodes = colour_nodes(p);
  const Colouring elements = colour_elements(mesh.tets, n);
  assert_true(is_valid_node_colouring(p, nodes));
  assert_true(is_valid_element_colouring(mesh.tets, n, elements));
  // Greedy first-fit needs at most (max degree + 1) colours.
  int32_t max_degree = 0;
  for (int32_t i = 0; i < n; ++i) max_degree = std::max(max_degree, p.row_start[i + 1] - p.row_start[i] - 1);
  assert_true(nodes.colours() <= max_degree + 1);
  int32_t smallest = n;
  for (int32_t c = 0; c < nodes.colours(); ++c) smallest = std::min(smallest, nodes.size(c));
  print_message("%s: %d nodes in %d colours (smallest %d; max degree %d), %zu tets in %d colours\n", what, n,
                nodes.colours(), smallest, max_degree, mesh.tets.size(), elements.colours());
  // Within a colour, ascending order (locality of the sweep).
  for (int32_t c = 0; c < nodes.colours(); ++c)
    for (int32_t k = nodes.start[c] + 1; k < nodes.start[c + 1]; ++k) assert_true(nodes.order[k - 1] < nodes.order[k]);
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
  const int32_t n = int32_t(mesh.nodes.size());
  const BlockPattern p = build_block_pattern(n, mesh.tets);
  // One colour for all: coupled nodes share it.
  Colouring one;
  for (int32_t i = 0; i < n; ++i) one.order.push_back(i);
  one.start = {0, n};
  assert_false(is_valid_node_colouring(p, one));
  Colouring all_tets;
  for (int32_t e = 0; e < int32_t(mesh.tets.size()); ++e) all_tets.order.push_back(e);
  all_tets.start = {0, int32_t(mesh.tets.size())};
  assert_false(is_valid_element_colouring(mesh.tets, n, all_tets));
  // A node missing, or listed twice.
  Colouring c = colour_nodes(p);
  std::swap(c.order[0], c.order[1]);
  c.order[1] = c.order[0];
  assert_false(is_valid_node_colouring(p, c));
  Colouring e = colour_elements(mesh.tets, n);
  e.order.pop_back();
  assert_false(is_valid_element_colouring(mesh.tets, n, e));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_box_colourings_are_valid),
      cmocka_unit_test(test_nidus_colourings_are_valid),
      cmocka_unit_test(test_invalid_colourings_are_caught),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
