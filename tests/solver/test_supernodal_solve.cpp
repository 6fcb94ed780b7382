// SPDX-License-Identifier: Apache-2.0
// The hand-written supernodal solve (solver/supernodal_solve.hpp) against cholmod_solve2 on the
// same factor: the double solve to round-off, the single-precision one to its precision, and a
// factor of another kind refused.
#include "solver/direct_solver.hpp"  // before cmocka (test_util.hpp)
#include "solver/solver_problem.hpp"
#include "solver/supernodal_solve.hpp"

using namespace mica;
using namespace mica_test;

namespace {

// A factored system of the shared problem (a sheared 8^3-cell cube, its base fixed) and a
// right-hand side.
struct Factored {
  SolverProblem p{0, 8, false};
  DirectSolver direct;
  Eigen::VectorXd b;
  explicit Factored(bool single) {
    direct.set_keep_single(single);
    direct.analyze(p.fem.pattern);
    direct.factorize(ProjectedSystem{p.fem.pattern, p.A, p.projection});
    b = Eigen::VectorXd::LinSpaced(3 * p.fem.node_count(), -1, 2).array().sin();
  }
};

double relative(const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return (a - b).norm() / b.norm(); }

}  // namespace

static void test_double_matches_cholmod(void**) {
  Factored f(false);
  Eigen::MatrixXd reference, by_hand;
  f.direct.solve_raw_cholmod(f.b, reference);
  f.direct.solve_raw(f.b, by_hand);  // one right-hand side: by hand
  const double d = relative(by_hand.col(0), reference.col(0));
  print_message("by hand against cholmod_solve2: %.3g\n", d);
  assert_true(d <= 1e-13);
  // Without a single-precision copy, a single-precision solve is the double one.
  Eigen::VectorXd x;
  f.direct.solve_one(f.b, x, true);
  assert_true(x == by_hand.col(0));
}

static void test_single_within_its_precision(void**) {
  Factored f(true);
  Eigen::MatrixXd reference;
  f.direct.solve_raw_cholmod(f.b, reference);
  Eigen::VectorXd x, exact;
  f.direct.solve_one(f.b, x, true);
  f.direct.solve_one(f.b, exact, false);
  assert_true(relative(exact, reference.col(0)) <= 1e-13);
  const double d = relative(x, reference.col(0));
  print_message("single precision against cholmod_solve2: %.3g\n", d);
  assert_true(d > 1e-12);  // it did solve in single precision
  assert_true(d <= 1e-4);  // float's 6e-8 times the growth in the triangular solves
  // The multi-column solves (the contact columns) stay in double.
  Eigen::MatrixXd B(f.b.size(), 2), X;
  B << f.b, f.b;
  f.direct.solve_raw(B, X);
  assert_true(relative(X.col(1), reference.col(0)) <= 1e-13);
}

// A simplicial factor is not a supernodal one: bind refuses it.
static void test_other_factors_refused(void**) {
  struct Simplicial : Eigen::CholmodSimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
    cholmod_factor* factor() const { return m_cholmodFactor; }
  } simplicial;
  Eigen::SparseMatrix<double> A(3, 3);
  for (int i = 0; i < 3; ++i) A.insert(i, i) = 2.0 + i;
  simplicial.compute(A);
  assert_true(simplicial.info() == Eigen::Success);
  SupernodalSolve solve;
  assert_false(solve.bind(simplicial.factor(), false));
  assert_false(solve.bound());
  assert_false(solve.bind(nullptr, true));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_double_matches_cholmod),
      cmocka_unit_test(test_single_within_its_precision),
      cmocka_unit_test(test_other_factors_refused),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
