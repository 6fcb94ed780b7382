// SPDX-License-Identifier: Apache-2.0
// The dense LCP solvers: Lemke on hand-solved and random problems (positive definite,
// positive semidefinite and singular as with redundant contacts, infeasible), projected
// Gauss-Seidel against Lemke. (Friction, which is not an LCP: test_frictional_contact.cpp.)
#include "solver/lcp.hpp"
#include "solver/lcp_problems.hpp"
#include "test_util.hpp"

using namespace mica;
using namespace lcp_problems;

namespace {

Eigen::MatrixXd mat(int rows, int cols, std::initializer_list<double> values) {
  Eigen::MatrixXd m(rows, cols);
  auto it = values.begin();
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) m(i, j) = *it++;
  return m;
}
Eigen::VectorXd vec(std::initializer_list<double> values) {
  Eigen::VectorXd v(Eigen::Index(values.size()));
  Eigen::Index i = 0;
  for (double x : values) v(i++) = x;
  return v;
}

// Lemke solves it, w is M z + q, and complementarity holds to 1e-10 relative.
LcpSolution lemke_solves(const Eigen::MatrixXd& M, const Eigen::VectorXd& q) {
  LcpSolution s = solve_lcp_lemke(M, q);
  if (!s.solved) fail_msg("n = %d: not solved: %s", int(q.size()), s.message.c_str());
  assert_le(relative_complementarity(M, q, s.z), 1e-10);
  assert_le(inf_norm(s.w - (M * s.z + q)), 1e-12 * std::max(1.0, inf_norm(s.w)));
  assert_false(s.message.empty());
  return s;
}

void expect_vector(const Eigen::VectorXd& got, const Eigen::VectorXd& want, double tol) {
  assert_int_equal(got.size(), want.size());
  for (Eigen::Index i = 0; i < got.size(); ++i) assert_near(got(i), want(i), tol);
}

}  // namespace

static void test_trivial_case_takes_no_pivot(void**) {
  const Eigen::MatrixXd M = mat(3, 3, {2, 1, 0, 1, 2, 1, 0, 1, 2});
  const Eigen::VectorXd q = vec({1, 0, 3});
  const LcpSolution s = solve_lcp_lemke(M, q);
  assert_true(s.solved);
  assert_int_equal(s.pivots, 0);
  expect_vector(s.z, Eigen::VectorXd::Zero(3), 0);
  expect_vector(s.w, q, 0);

  const LcpSolution empty = solve_lcp_lemke(Eigen::MatrixXd(0, 0), Eigen::VectorXd(0));
  assert_true(empty.solved);
  assert_int_equal(empty.z.size(), 0);
}

static void test_hand_solved_small_problems(void**) {
  {  // 2 z - 4 = w: z = 2
    const LcpSolution s = lemke_solves(mat(1, 1, {2}), vec({-4}));
    expect_vector(s.z, vec({2}), 1e-15);
    expect_vector(s.w, vec({0}), 1e-15);
  }
  {  // both active: z = M^-1 (5, 6) = (4/3, 7/3)
    const LcpSolution s = lemke_solves(mat(2, 2, {2, 1, 1, 2}), vec({-5, -6}));
    expect_vector(s.z, vec({4.0 / 3, 7.0 / 3}), 1e-14);
    expect_vector(s.w, vec({0, 0}), 1e-14);
  }
  {  // one active: z = (1/2, 0), w = (0, 1/2 + 3)
    const LcpSolution s = lemke_solves(mat(2, 2, {2, 1, 1, 2}), vec({-1, 3}));
    expect_vector(s.z, vec({0.5, 0}), 1e-15);
    expect_vector(s.w, vec({0, 3.5}), 1e-15);
  }
  {  // q_1 = 0 is a degenerate row: z = (0, 1), w = (1, 0)
    const LcpSolution s = lemke_solves(mat(2, 2, {2, 1, 1, 2}), vec({0, -2}));
    expect_vector(s.z, vec({0, 1}), 1e-15);
    expect_vector(s.w, vec({1, 0}), 1e-15);
  }
  {  // non-symmetric P-matrix: z = (4, 0), w = (0, 11)
    const LcpSolution s = lemke_solves(mat(2, 2, {1, -5, 2, 1}), vec({-4, 3}));
    expect_vector(s.z, vec({4, 0}), 1e-14);
    expect_vector(s.w, vec({0, 11}), 1e-14);
  }
}

static void test_degenerate_ties_do_not_cycle(void**) {
  {  // all q equal (a tie at the first pivot), cyclic P-matrix: z = (1, 1, 1) / 3
    const LcpSolution s = lemke_solves(mat(3, 3, {1, 2, 0, 0, 1, 2, 2, 0, 1}), vec({-1, -1, -1}));
    expect_vector(s.z, vec({1.0 / 3, 1.0 / 3, 1.0 / 3}), 1e-15);
  }
  {  // two identical contacts: any split with z_0 + z_1 = 1 is a solution, w = 0
    const LcpSolution s = lemke_solves(mat(2, 2, {1, 1, 1, 1}), vec({-1, -1}));
    assert_near(s.z.sum(), 1.0, 1e-15);
    expect_vector(s.w, vec({0, 0}), 1e-15);
  }
  {  // three identical contacts
    const LcpSolution s = lemke_solves(Eigen::MatrixXd::Ones(3, 3), vec({-2, -2, -2}));
    assert_near(s.z.sum(), 2.0, 1e-15);
    expect_vector(s.w, vec({0, 0, 0}), 1e-15);
  }
  {  // two pairs of duplicates coupled, with equal q: the base problem [[2,1],[1,2]] z = (1,1)
    const Eigen::MatrixXd M = mat(4, 4, {2, 2, 1, 1, 2, 2, 1, 1, 1, 1, 2, 2, 1, 1, 2, 2});
    const LcpSolution s = lemke_solves(M, vec({-3, -3, -3, -3}));
    assert_near(s.z(0) + s.z(1), 1.0, 1e-14);
    assert_near(s.z(2) + s.z(3), 1.0, 1e-14);
    expect_vector(s.w, vec({0, 0, 0, 0}), 1e-14);
  }
  {  // duplicates with different q: only the smaller matters, the other row stays open
    const LcpSolution s = lemke_solves(mat(3, 3, {1, 1, 0, 1, 1, 0, 0, 0, 1}), vec({-1, -0.5, 0}));
    expect_vector(s.z, vec({1, 0, 0}), 1e-15);
    expect_vector(s.w, vec({0, 0.5, 0}), 1e-15);
  }
}

static void test_random_positive_definite(void**) {
  for (int32_t n : {1, 2, 3, 5, 8, 13, 20, 30, 45, 60})
    for (uint32_t seed = 1; seed <= 5; ++seed) {
      const Problem p = spd(n, 1000u * uint32_t(n) + seed);
      const LcpSolution s = lemke_solves(p.M, p.q);
      assert_le(s.pivots, 2 * n + 1);
    }
}

static void test_random_redundant_contacts(void**) {
  for (int32_t m : {1, 3, 10, 30})
    for (uint32_t seed = 1; seed <= 4; ++seed) {
      const int32_t n = std::min(60, 2 * m);
      for (bool same_q : {true, false}) {
        const Duplicated d = duplicated(m, n, 50u * uint32_t(m) + seed, same_q);
        const LcpSolution s = lemke_solves(d.problem.M, d.problem.q);
        if (!same_q) continue;
        // Copies of a base row share its impulse: their z add up to the base solution, and
        // every copy sees the base w.
        const LcpSolution base = lemke_solves(d.base.M, d.base.q);
        Eigen::VectorXd sum = Eigen::VectorXd::Zero(m);
        for (int32_t i = 0; i < n; ++i) sum(d.source[size_t(i)]) += s.z(i);
        assert_le(relative_difference(sum, base.z), 1e-10);
        for (int32_t i = 0; i < n; ++i)
          assert_near(s.w(i), base.w(d.source[size_t(i)]), 1e-10 * std::max(1.0, inf_norm(base.w)));
      }
    }
}

static void test_random_low_rank_semidefinite(void**) {
  for (int32_t n : {2, 5, 10, 25, 40, 60})
    for (int32_t k : {1, n / 2, n - 1}) {
      if (k < 1) continue;
      for (uint32_t seed = 1; seed <= 3; ++seed) {
        const Problem p = low_rank(n, k, 7u * uint32_t(n + k) + seed);
        lemke_solves(p.M, p.q);
      }
    }
}

static void test_pgs_agrees_with_lemke_on_positive_definite(void**) {
  for (int32_t n : {1, 2, 5, 10, 20, 40, 60})
    for (uint32_t seed = 1; seed <= 3; ++seed) {
      const Problem p = spd(n, 1000u * uint32_t(n) + seed);
      const LcpSolution exact = lemke_solves(p.M, p.q);
      const LcpSolution pgs = solve_lcp_pgs(p.M, p.q, 1e-14, 1000000);
      if (!pgs.solved) fail_msg("n = %d: %s", n, pgs.message.c_str());
      assert_le(relative_difference(pgs.z, exact.z), 1e-8);
      assert_le(relative_difference(pgs.w, exact.w), 1e-8);
    }
}

static void test_pgs_skips_rows_without_diagonal(void**) {
  const Eigen::MatrixXd M = mat(2, 2, {0, 0, 0, 2});
  const LcpSolution ok = solve_lcp_pgs(M, vec({1, -2}), 1e-14, 100);
  assert_true(ok.solved);
  expect_vector(ok.z, vec({0, 1}), 1e-15);
  // Row 0 would need z_0 > 0 but cannot move: reported, not solved.
  const LcpSolution stuck = solve_lcp_pgs(M, vec({-1, -2}), 1e-14, 100);
  assert_false(stuck.solved);
  assert_int_equal(stuck.pivots, 100);
  assert_true(std::isfinite(stuck.z.sum()));
}

static void test_no_solution_is_reported(void**) {
  for (int n : {1, 2, 5}) {  // w = q - z < 0 for every z >= 0
    const LcpSolution s = solve_lcp_lemke(-Eigen::MatrixXd::Identity(n, n), -Eigen::VectorXd::Ones(n));
    assert_false(s.solved);
    assert_true(s.ray);
    assert_non_null(std::strstr(s.message.c_str(), "ray"));
    assert_le(s.pivots, 50 * n);
  }
  {  // skew-symmetric (copositive-plus), infeasible: w_0 = -z_1 - 1 < 0
    const LcpSolution s = solve_lcp_lemke(mat(2, 2, {0, -1, 1, 0}), vec({-1, -1}));
    assert_false(s.solved);
    assert_true(s.ray);
    assert_non_null(std::strstr(s.message.c_str(), "ray"));
  }
  {  // M = 0 with a negative q
    const LcpSolution s = solve_lcp_lemke(Eigen::MatrixXd::Zero(3, 3), vec({1, -1, 0}));
    assert_false(s.solved);
  }
  {  // the pivot limit is reported, not exceeded
    const Problem p = spd(30, 4242);
    const LcpSolution s = solve_lcp_lemke(p.M, p.q, 3);
    assert_false(s.solved);
    assert_int_equal(s.pivots, 3);
    assert_false(s.ray);  // which says nothing of a solution
    assert_non_null(std::strstr(s.message.c_str(), "pivot limit"));
  }
}

static void test_bad_input_throws(void**) {
  auto throws_invalid = [](auto&& call) {
    try {
      call();
    } catch (const Error& e) {
      return e.code() == Errc::InvalidArgument;
    }
    return false;
  };
  assert_true(throws_invalid([] { solve_lcp_lemke(Eigen::MatrixXd::Identity(2, 3), vec({1, 1})); }));
  assert_true(throws_invalid([] { solve_lcp_lemke(Eigen::MatrixXd::Identity(2, 2), vec({1})); }));
  assert_true(throws_invalid([] { solve_lcp_lemke(Eigen::MatrixXd::Identity(1, 1), vec({NAN})); }));
  assert_true(throws_invalid([] { solve_lcp_lemke(Eigen::MatrixXd::Identity(1, 1), vec({-1}), -1); }));
  assert_true(throws_invalid([] { solve_lcp_pgs(Eigen::MatrixXd::Identity(1, 1), vec({-1}), -1.0, 10); }));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_trivial_case_takes_no_pivot),
      cmocka_unit_test(test_hand_solved_small_problems),
      cmocka_unit_test(test_degenerate_ties_do_not_cycle),
      cmocka_unit_test(test_random_positive_definite),
      cmocka_unit_test(test_random_redundant_contacts),
      cmocka_unit_test(test_random_low_rank_semidefinite),
      cmocka_unit_test(test_pgs_agrees_with_lemke_on_positive_definite),
      cmocka_unit_test(test_pgs_skips_rows_without_diagonal),
      cmocka_unit_test(test_no_solution_is_reported),
      cmocka_unit_test(test_bad_input_throws),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
