// SPDX-License-Identifier: Apache-2.0
// The linear solvers of one body's projected system (S A S + I - S) y = S (b - A z), v = y + z:
// CHOLMOD (DirectSolver) against a dense Cholesky of the same matrix (also as the nodes held still
// change, which the factor leaves out), and projected PCG
// (PcgSolver) against CHOLMOD, for solve and solve_homogeneous; PCG stops at its deadline. A matrix
// that is not positive definite is an error naming CHOLMOD's reason, and CHOLMOD prints nothing.
#include <unistd.h>

#include <cstdio>
#include <cstring>

#include "core/error.hpp"
#include "solver/direct_solver.hpp"  // before cmocka (test_util.hpp)
#include "solver/pcg.hpp"
#include "solver/solver_problem.hpp"

using namespace mica;
using namespace mica_test;

namespace {

// The dense projected matrix P = S A S + I - S.
Eigen::MatrixXd dense_projected(const SolverProblem& p) {
  const ProjectedSystem sys{p.fem.pattern, p.A, p.projection};
  const int32_t n = p.fem.node_count();
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  for (int32_t i = 0; i < n; ++i)
    for (int32_t k = p.fem.pattern.row_start[i]; k < p.fem.pattern.row_start[i + 1]; ++k)
      P.block<3, 3>(3 * i, 3 * p.fem.pattern.col[k]) = sys.block(i, k);
  return P;
}

}  // namespace

static void test_direct_matches_dense(void**) {
  SolverProblem p(0, 2, false);
  for (int32_t i : p.projection.nodes) p.projection.z[i] = Vec3(0, 0.01, 0);  // a prescribed velocity
  const ProjectedSystem sys{p.fem.pattern, p.A, p.projection};
  DirectSolver direct;
  direct.analyze(p.fem.pattern);
  direct.factorize(sys);
  Vec3List v(p.v.size(), Vec3::Zero()), rhs(p.v.size()), tmp(p.v.size());
  direct.solve(sys, p.b, v);
  sys.right_hand_side(p.b, rhs, tmp);
  const Eigen::VectorXd y = dense_projected(p).llt().solve(flat(rhs));
  Vec3List expected(v.size());
  flat(expected) = y;
  for (int32_t i : p.projection.nodes) expected[i] += p.projection.z[i];
  const double d = relative_difference(v, expected);
  print_message("CHOLMOD against dense Cholesky: %.3g\n", d);
  assert_le(d, 1e-12);
  // The homogeneous solve: the response to a force, zero on the prescribed directions.
  Vec3List f(v.size(), Vec3(1, -2, 0.5)), response(v.size());
  direct.solve_homogeneous(sys, f, response);
  for (int32_t i : p.projection.nodes) assert_true(response[i].isZero(0));
  assert_int_equal(direct.factorizations(), 1);
}

// Factors p's system with `direct` and solves it: the relative difference from the dense Cholesky.
static double factored_against_dense(const SolverProblem& p, DirectSolver& direct) {
  const ProjectedSystem sys{p.fem.pattern, p.A, p.projection};
  direct.factorize(sys);
  Vec3List v(p.v.size(), Vec3::Zero()), rhs(p.v.size()), tmp(p.v.size());
  direct.solve(sys, p.b, v);
  sys.right_hand_side(p.b, rhs, tmp);
  Vec3List expected(v.size());
  flat(expected) = dense_projected(p).llt().solve(flat(rhs));
  for (int32_t i : p.projection.nodes) expected[i] += p.projection.z[i];
  return relative_difference(v, expected);
}

// One DirectSolver factoring systems that hold different nodes still, in turn: each solve against
// the dense Cholesky, and the held nodes' couplings left out of the factor (fewer nonzeros in L
// than with the same nodes sliding, whose couplings stay).
static void test_direct_follows_the_held_nodes(void**) {
  SolverProblem p(0, 3, false);
  const Projection bottom_held = p.projection;
  const int32_t n = p.fem.node_count();
  struct Case {
    const char* name;
    int held;  // 0: none, 1: the bottom nodes, 2: the bottom nodes slide on y = 0
  } cases[] = {{"bottom held", 1}, {"none held", 0}, {"bottom sliding", 2}, {"bottom held again", 1}};
  DirectSolver direct;
  direct.analyze(p.fem.pattern);
  double nonzeros[3] = {0, 0, 0};
  for (const Case& c : cases) {
    p.projection.reset(n);
    for (int32_t i : bottom_held.nodes) {
      if (c.held == 1) p.projection.constrain(i, Mat3::Identity(), Vec3(0, 0.01, 0));
      if (c.held == 2) p.projection.constrain(i, line_projector(Vec3::UnitY()), Vec3::Zero());
    }
    const double d = factored_against_dense(p, direct);
    nonzeros[c.held] = direct.factor_nonzeros();
    print_message("%-18s: %.0f nonzeros in L, against dense Cholesky %.3g\n", c.name, direct.factor_nonzeros(), d);
    assert_le(d, 1e-12);
  }
  assert_true(nonzeros[1] < nonzeros[2]);
  assert_true(nonzeros[2] == nonzeros[0]);  // a sliding node keeps its couplings
}

// A pattern marked FillOrdering::Amd (a cut body's) is ordered by AMD alone, in one analysis of
// the pattern as held when it is first analysed; its factors solve as the dense Cholesky does,
// with the nodes held and then free. Marked or not, the same solutions.
static void test_amd_alone_orders_the_held_pattern(void**) {
  for (const FillOrdering fill : {FillOrdering::LeastFill, FillOrdering::Amd}) {
    SolverProblem p(0, 3, false);
    p.fem.pattern.fill_ordering = fill;
    DirectSolver direct;
    direct.analyze(p.fem.pattern, &p.projection);  // the bottom held
    if (fill == FillOrdering::Amd) assert_int_equal(direct.ordering(), CHOLMOD_AMD);
    const double held = factored_against_dense(p, direct);
    p.projection.reset(p.fem.node_count());
    const double free = factored_against_dense(p, direct);
    print_message("%s: against dense Cholesky %.3g held, %.3g free\n",
                  fill == FillOrdering::Amd ? "AMD alone" : "least fill", held, free);
    assert_le(held, 1e-12);
    assert_le(free, 1e-12);
  }
}

// Not positive definite (A negated): Errc::Numerical, and nothing on stdout or stderr (a library
// does not write to its host's streams; CHOLMOD prints its warnings unless told not to).
static void test_pcg_matches_direct(void**) {
  SolverProblem p(0, 3, false);
  const ProjectedSystem sys{p.fem.pattern, p.A, p.projection};
  DirectSolver direct;
  direct.analyze(p.fem.pattern);
  direct.factorize(sys);
  PcgSolver pcg;
  pcg.configure(1e-13, 10000);
  Vec3List exact(p.v.size(), Vec3::Zero()), v = p.v;
  direct.solve(sys, p.b, exact);
  const SolveReport r = pcg.solve(sys, p.b, v);
  assert_true(r.converged);
  assert_le(relative_difference(v, exact), 1e-10);
  Vec3List f(v.size(), Vec3(0, 1, 0)), y_exact(v.size()), y(v.size());
  direct.solve_homogeneous(sys, f, y_exact);
  assert_true(pcg.solve_homogeneous(sys, f, y).converged);
  print_message("PCG against CHOLMOD: %d iterations, v %.3g, response %.3g\n", r.iterations,
                relative_difference(v, exact), relative_difference(y, y_exact));
  assert_le(relative_difference(y, y_exact), 1e-10);
}

// A deadline already past: one iteration, then out of time (not converged).
static void test_pcg_stops_at_its_deadline(void**) {
  SolverProblem p(0, 3, false);
  PcgSolver pcg;
  pcg.configure(1e-13, 10000, PcgSolver::Clock::now());
  const SolveReport r = pcg.solve(ProjectedSystem{p.fem.pattern, p.A, p.projection}, p.b, p.v);
  assert_int_equal(r.iterations, 1);
  assert_true(r.out_of_time);
  assert_false(r.converged);
}

// A system that is not positive definite: the factorization throws Error(Numerical) with
// CHOLMOD's reason, and nothing reaches the process's stdout or stderr (CHOLMOD prints by default).
static void test_direct_failure_prints_nothing(void**) {
  SolverProblem p(0, 2, false);
  for (Mat3& block : p.A) block = -block;  // negative definite
  const ProjectedSystem sys{p.fem.pattern, p.A, p.projection};
  std::fflush(stdout);
  std::fflush(stderr);
  FILE* capture = std::tmpfile();
  assert_non_null(capture);
  const int saved_out = dup(1), saved_err = dup(2);
  dup2(fileno(capture), 1);
  dup2(fileno(capture), 2);
  std::string message;
  try {
    DirectSolver direct;
    direct.analyze(p.fem.pattern);
    direct.factorize(sys);
  } catch (const Error& e) {
    message = e.what();
  }
  std::fflush(stdout);
  std::fflush(stderr);
  dup2(saved_out, 1);
  dup2(saved_err, 2);
  close(saved_out);
  close(saved_err);
  std::fseek(capture, 0, SEEK_END);
  const long printed = std::ftell(capture);
  std::fclose(capture);
  print_message("message: %s; %ld bytes printed\n", message.c_str(), printed);
  assert_int_equal(printed, 0);
  assert_non_null(std::strstr(message.c_str(), "not positive definite"));
  assert_non_null(std::strstr(message.c_str(), "CHOLMOD warning"));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_direct_matches_dense),
      cmocka_unit_test(test_direct_follows_the_held_nodes),
      cmocka_unit_test(test_amd_alone_orders_the_held_pattern),
      cmocka_unit_test(test_direct_failure_prints_nothing),
      cmocka_unit_test(test_pcg_matches_direct),
      cmocka_unit_test(test_pcg_stops_at_its_deadline),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
