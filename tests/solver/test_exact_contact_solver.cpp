// SPDX-License-Identifier: Apache-2.0
// The exact contact solver (the reference every other solver is tested against): its solution
// meets the conditions of the problem to round-off, with and without friction; without contact
// it is the plain projected solve; a body's factor is kept while its A and constraints stay, and
// dropped with the body. With PCG for the linear solves it agrees with CHOLMOD to the tolerance.
// A problem out of double precision is the step's numerical failure (issue 16: dt = 5e-324 with
// DIRECT made gap / h infinite, and Lemke's own argument check surfaced as
// MICA_ERR_INVALID_ARGUMENT "solve_lcp_lemke: M or q has a non-finite entry").
#include "solver/exact_contact_solver.hpp"  // before cmocka (test_util.hpp)
#include "solver/solver_problem.hpp"

using namespace mica;
using namespace mica_test;

static void test_frictionless_solution_is_exact(void**) {
  SolverProblem p;
  ExactContactSolver solver(LinearMethod::Direct);
  const SolveReport r = p.solve(solver);
  assert_true(r.converged);
  const int active = check_solution(p, 1e-10);
  print_message("%zu rows, %d active, residual %.3g\n", p.rows.size(), active, r.residual);
  assert_true(active > 0 && active < int(p.rows.size()));  // some press, some are left apart
  assert_int_equal(solver.row_diagonal().size(), p.rows.size());
}

static void test_frictional_solution_is_exact(void**) {
  for (double mu : {0.1, 1.0}) {
    SolverProblem p(mu);
    ExactContactSolver solver(LinearMethod::Direct);
    const SolveReport r = p.solve(solver);
    assert_true(r.converged);
    const int active = check_solution(p, 1e-8);
    print_message("mu %.1f: %zu rows, %d active contacts, %d sweeps and solves\n", mu, p.rows.size(), active,
                  r.iterations);
    assert_true(active > 0);
  }
}

// No rows: v solves the projected system and there is no impulse.
static void test_without_contact_is_the_linear_solve(void**) {
  SolverProblem p(0, 3, false);
  p.impulse.assign(p.impulse.size(), Vec3(1, 1, 1));  // stale: must be cleared
  ExactContactSolver solver(LinearMethod::Direct);
  p.solve(solver);
  assert_true(p.lambda.empty());
  for (const Vec3& f : p.impulse) assert_true(f.isZero(0));
  DirectSolver direct;
  direct.analyze(p.fem.pattern);
  const ProjectedSystem sys{p.fem.pattern, p.A, p.projection};
  direct.factorize(sys);
  Vec3List v(p.v.size(), Vec3::Zero());
  direct.solve(sys, p.b, v);
  assert_true(relative_difference(p.v, v) == 0);
  check_solution(p, 1e-10);
}

// The factor is the body's: kept while matrix_version and constraint_version stay, made again
// when either changes, forgotten with the body.
static void test_factor_follows_the_versions(void**) {
  SolverProblem p;
  ExactContactSolver solver(LinearMethod::Direct);
  std::vector<SolverBody> bodies{p.body(7)};
  for (int k = 0; k < 3; ++k) solver.solve({}, bodies, p.rows, p.lambda);
  assert_int_equal(solver.factorizations(7), 1);
  bodies[0].matrix_version = 1;
  solver.solve({}, bodies, p.rows, p.lambda);
  assert_int_equal(solver.factorizations(7), 2);
  bodies[0].constraint_version = 1;
  solver.solve({}, bodies, p.rows, p.lambda);
  solver.solve({}, bodies, p.rows, p.lambda);
  assert_int_equal(solver.factorizations(7), 3);
  solver.forget(7);
  assert_int_equal(solver.factorizations(7), 0);
}

static void test_pcg_agrees_with_cholmod(void**) {
  for (double mu : {0.0, 0.5}) {
    SolverProblem exact(mu), pcg(mu);
    ExactContactSolver direct(LinearMethod::Direct);
    SolverSettings s;
    s.tolerance = 1e-13;
    s.max_iterations = 10000;
    ExactContactSolver iterative(LinearMethod::Pcg, s);
    exact.solve(direct);
    const SolveReport r = pcg.solve(iterative);
    assert_true(r.converged);
    const double dv = relative_difference(pcg.v, exact.v), dl = relative_difference(pcg.lambda, exact.lambda);
    print_message("mu %.1f: PCG against CHOLMOD: v %.3g, lambda %.3g (%d iterations)\n", mu, dv, dl, r.iterations);
    assert_le(dv, 1e-9);
    assert_le(dl, 1e-8);
    assert_int_equal(iterative.factorizations(1), 0);
  }
}

static void test_non_finite_problem_is_a_numerical_failure(void**) {
  auto failure = [](SolverProblem& p) {
    ExactContactSolver solver(LinearMethod::Direct);
    try {
      p.solve(solver);
    } catch (const Error& e) {
      assert_true(e.code() == Errc::Numerical);
      assert_true(std::string(e.what()).find("not finite") != std::string::npos);
      assert_true(std::string(e.what()).find("lemke") == std::string::npos);
      return;
    }
    fail_msg("a non-finite contact problem was solved");
  };
  SolverProblem infinite_bias;  // gap / h with h = 5e-324
  infinite_bias.rows.bias[0] = -HUGE_VAL;
  failure(infinite_bias);
  SolverProblem nan_rhs;  // a NaN in the free velocities' right-hand side
  nan_rhs.b.back() = Vec3(0, 0, NAN);
  failure(nan_rhs);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_frictionless_solution_is_exact),
      cmocka_unit_test(test_frictional_solution_is_exact),
      cmocka_unit_test(test_without_contact_is_the_linear_solve),
      cmocka_unit_test(test_factor_follows_the_versions),
      cmocka_unit_test(test_pcg_agrees_with_cholmod),
      cmocka_unit_test(test_non_finite_problem_is_a_numerical_failure),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
