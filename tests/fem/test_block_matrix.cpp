// SPDX-License-Identifier: Apache-2.0
// The block matrix's product y = A x (fem/block_matrix.hpp) against the same product with A
// written out dense: the vector kernel where the CPU has AVX2 and FMA (its last block included,
// which goes the scalar way), else the portable one; and block_multiply_bound's product and row
// bounds against a plain loop over each row's blocks.
#include "fem/block_matrix.hpp"
#include "mesh/tet_mesh.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {
// A box mesh's block pattern with random blocks A and a random vector x, entries in [-1, 1].
struct RandomProduct {
  BlockPattern p;
  BlockValues A;
  Vec3List x;
  RandomProduct(std::array<int, 3> cells, unsigned seed) {
    const TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(1, 1, 1), cells, 6);
    p = build_block_pattern(int32_t(mesh.nodes.size()), mesh.tets);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    A.resize(p.block_count());
    for (Mat3& block : A)
      for (int k = 0; k < 9; ++k) block(k / 3, k % 3) = u(rng);
    x.resize(size_t(p.rows));
    for (Vec3& v : x) v = Vec3(u(rng), u(rng), u(rng));
  }
};
}  // namespace

static void test_product_matches_dense(void**) {
  for (const int cells : {1, 3}) {
    const RandomProduct r({cells, cells + 1, 2}, 3);
    const BlockPattern& p = r.p;
    const BlockValues& A = r.A;
    const Vec3List& x = r.x;
    Vec3List y(size_t(p.rows));
    Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * p.rows, 3 * p.rows);
    Eigen::VectorXd flat_x(3 * p.rows);
    for (int32_t i = 0; i < p.rows; ++i) {
      flat_x.segment<3>(3 * i) = x[size_t(i)];
      for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k) dense.block<3, 3>(3 * i, 3 * p.col[k]) = A[k];
    }
    block_multiply(p, A, x, y);
    const Eigen::VectorXd reference = dense * flat_x;
    double worst = 0;
    for (int32_t i = 0; i < p.rows; ++i) worst = std::max(worst, (y[size_t(i)] - reference.segment<3>(3 * i)).norm());
    print_message("%d nodes, %zu blocks: largest difference %.2g of %.2g\n", p.rows, p.block_count(), worst,
                  reference.lpNorm<Eigen::Infinity>());
    assert_true(worst <= 1e-14 * reference.lpNorm<Eigen::Infinity>());
  }
}

static void test_bound_matches_its_definition(void**) {
  const RandomProduct r({3, 4, 2}, 5);
  const BlockPattern& p = r.p;
  const BlockValues& A = r.A;
  const Vec3List& x = r.x;
  Vec3List y(size_t(p.rows)), y_plain(size_t(p.rows));
  std::vector<double> bound(size_t(p.rows));
  block_multiply_bound(p, A, x, y, bound);
  block_multiply(p, A, x, y_plain);
  double worst_y = 0, worst_bound = 0;
  for (int32_t i = 0; i < p.rows; ++i) {
    double a2 = 0, x2 = 0, sum = 0;  // sum: sum_j |A_ij| |x_j|, which the bound bounds
    for (int32_t k = p.row_start[i]; k < p.row_start[i + 1]; ++k) {
      a2 += A[k].squaredNorm();
      x2 += x[size_t(p.col[k])].squaredNorm();
      sum += A[k].norm() * x[size_t(p.col[k])].norm();
    }
    assert_true(sum * sum <= bound[size_t(i)] * (1 + 1e-12));
    worst_bound = std::max(worst_bound, std::fabs(bound[size_t(i)] - a2 * x2) / (a2 * x2));
    worst_y = std::max(worst_y, (y[size_t(i)] - y_plain[size_t(i)]).norm() / y_plain[size_t(i)].norm());
  }
  print_message("relative differences: product %.2g, bound %.2g\n", worst_y, worst_bound);
  assert_true(worst_y <= 1e-14);
  assert_true(worst_bound <= 1e-14);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_product_matches_dense),
      cmocka_unit_test(test_bound_matches_its_definition),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
