// SPDX-License-Identifier: Apache-2.0
// The factored MICA solver against the exact one on the same problem, through the solver
// contract: velocities and impulses agree to the tolerance, with and without friction, from a
// cold and a warm start, with the factor of the current system and with one warped from an
// earlier one; a body's factor is made once per system key and dropped with the body. Each case
// runs both loops: the alternating one and the active-set one (SolverSettings::active_set).
#include "solver/exact_contact_solver.hpp"  // before cmocka (test_util.hpp)
#include "solver/factored_mica.hpp"
#include "solver/solver_problem.hpp"

using namespace mica;
using namespace mica_test;

namespace {

const bool kLoops[] = {false, true};  // SolverSettings::active_set

SolverSettings tight(bool active_set) {
  SolverSettings s;
  s.active_set = active_set;
  s.tolerance = 1e-10;
  s.max_iterations = 100000;
  s.refactor_after = 0;
  return s;
}

void compare(SolverProblem& mica, double mu, double tol, const char* what) {
  SolverProblem exact(mu);
  ExactContactSolver reference(LinearMethod::Direct);
  exact.solve(reference);
  const double dv = relative_difference(mica.v, exact.v), dl = relative_difference(mica.lambda, exact.lambda);
  print_message("%s, mu %.1f: against the exact solver v %.3g, lambda %.3g\n", what, mu, dv, dl);
  assert_le(dv, tol);
  assert_le(dl, tol);
}

// The problem's system assembled at the rest shape (R = I): an earlier system than its own.
void at_rest_shape(SolverProblem& p) {
  compute_rotations(p.fem, p.fem.rest, p.R);
  set_scaled_mass(p.fem, 1.0, p.A);
  assemble_elastic(p.fem, p.fem.rest, &p.R, SolverProblem::kH * SolverProblem::kH, &p.A, p.f_int);
}

// A rounded tool's curvature: a positive semidefinite stiffness of rank 4 over the corners of a
// top face, as large as a corner's own diagonal block of A, added to A.
TriangleStiffness add_triangle_stiffness(SolverProblem& p) {
  TriangleStiffness e{};
  for (const TetElement& el : p.fem.elements) {
    int k = 0;
    for (int32_t i : el.nodes)
      if (p.fem.rest[i].y() > 0.1 - 1e-9 && k < 3) e.nodes[size_t(k++)] = i;
    if (k == 3) break;
  }
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  Eigen::Matrix<double, 9, 4> B;
  for (int k = 0; k < 36; ++k) B(k / 4, k % 4) = normal(rng);
  const double s = p.A[size_t(p.fem.pattern.find(e.nodes[0], e.nodes[0]))].norm();
  e.K = (s / B.squaredNorm()) * B * B.transpose();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) p.A[size_t(p.fem.pattern.find(e.nodes[r], e.nodes[c]))] += e.K.block<3, 3>(3 * r, 3 * c);
  return e;
}

}  // namespace

static void test_matches_exact(void**) {
  for (bool active_set : kLoops)
    for (double mu : {0.0, 0.5}) {
      SolverProblem p(mu);
      FactoredMicaSolver solver(tight(active_set));
      const SolveReport r = p.solve(solver);
      print_message("active set %d: %d iterations\n", int(active_set), r.iterations);
      assert_true(r.converged);
      assert_le(r.momentum_residual, 1e-10);
      check_solution(p, 1e-8);
      compare(p, mu, 1e-7, "cold start");
      assert_int_equal(solver.row_diagonal().size(), p.rows.size());
    }
}

// The second solve starts from the first one's impulses (and velocities): the same answer, in
// fewer iterations for the alternating loop (14 -> 4) and no more rounds for the active-set loop.
// The active-set loop's iterations are not held lower: at this tolerance (1e-10) its rounds are
// set by the small problem's prediction from the half copy's compliance (its half columns are
// the copy's), and the warm start took 10 against 9 (with the double factor's columns, 9 and 9).
static void test_warm_start(void**) {
  for (bool active_set : kLoops) {
    SolverProblem p(0.3);
    FactoredMicaSolver solver(tight(active_set));
    const SolveReport cold = p.solve(solver);
    p.v.assign(p.v.size(), Vec3(0, 0.05, 0));
    const SolveReport warm = p.solve(solver);
    print_message("active set %d: iterations cold %d, warm %d; rounds cold %d, warm %d\n", int(active_set),
                  cold.iterations, warm.iterations, cold.solves, warm.solves);
    if (active_set) assert_true(warm.solves <= cold.solves);
    else assert_true(warm.iterations < cold.iterations);
    compare(p, 0.3, 1e-7, "warm start");
  }
}

// The factor of an earlier system (the body sheared less), warped by the node rotations since:
// more iterations, the same answer; the factor is not made again for the same key.
static void check_lagged_factor(bool active_set) {
  SolverProblem earlier(0.0), p(0.0);
  at_rest_shape(earlier);
  FactoredMicaSolver solver(tight(active_set));
  earlier.solve(solver);
  assert_int_equal(solver.factorizations(1), 1);
  const SolveReport r = p.solve(solver);  // key 1 again: the same body, a turned system
  assert_int_equal(solver.factorizations(1), 1);
  assert_true(r.converged);
  compare(p, 0.0, 1e-7, "lagged factor");
  // Refactoring once a solve has used 2 iterations: a second factorization, the same answer.
  SolverSettings s = tight(active_set);
  s.refactor_after = 2;
  FactoredMicaSolver eager(s);
  earlier.solve(eager);
  SolverProblem q(0.0);
  q.solve(eager);
  assert_int_equal(eager.factorizations(1), 2);
  compare(q, 0.0, 1e-7, "refactored");
  eager.forget(1);
  assert_int_equal(eager.factorizations(1), 0);
}

static void test_lagged_factor_converges_to_exact(void**) {
  for (bool active_set : kLoops) check_lagged_factor(active_set);
}

// A deadline already past: each loop stops after one conjugate-gradient iteration of its first
// round on the turned system (the factor of the rest shape: more than one is needed), says it ran
// out of time and did not converge, and returns finite velocities and impulses.
static void test_deadline_stops_the_solve(void**) {
  for (bool active_set : kLoops) {
    SolverProblem earlier(0.0), p(0.0);
    at_rest_shape(earlier);
    FactoredMicaSolver solver(tight(active_set));
    earlier.solve(solver);
    SolveContext late;
    late.deadline = SolveContext::Clock::now() - std::chrono::seconds(1);
    const SolveReport r = p.solve(solver, late);
    print_message("active set %d: %d iterations, out of time %d\n", int(active_set), r.iterations, int(r.out_of_time));
    assert_true(r.out_of_time);
    assert_false(r.converged);
    assert_int_equal(r.iterations, 1);
    for (const Vec3& v : p.v) assert_true(v.allFinite());
    for (double l : p.lambda) assert_true(std::isfinite(l));
  }
}

// A system key or constraint version that changes makes the factor again at once.
static void test_new_key_factors_again(void**) {
  SolverProblem p;
  FactoredMicaSolver solver(tight(true));
  std::vector<SolverBody> bodies{p.body(3)};
  solver.solve({}, bodies, p.rows, p.lambda);
  bodies[0].constraint_version = 1;
  solver.solve({}, bodies, p.rows, p.lambda);
  bodies[0].system.h = 0.02;  // a new key (A itself unchanged: the solve is still the same problem)
  solver.solve({}, bodies, p.rows, p.lambda);
  assert_int_equal(solver.factorizations(3), 3);
}

// The contacts' own stiffness (SolverBody::extra_stiffness) is left out of the factor and added
// back exactly (Woodbury): with the factor of A without it, a solve takes about as many
// iterations as with the factor of A itself, where the same factor without the correction takes
// more; all three agree with the exact solver on A.
static void test_extra_stiffness_is_added_back(void**) {
  for (bool active_set : kLoops) {
    const double mu = 0.3;
    SolverProblem exact(mu);
    add_triangle_stiffness(exact);
    ExactContactSolver reference(LinearMethod::Direct);
    exact.solve(reference);
    // told: the factor of A without the stiffness (the first solve's), then A with it, declared
    FactoredMicaSolver told(tight(active_set));
    SolverProblem plain(mu), p(mu);
    plain.solve(told);
    p.extra = {add_triangle_stiffness(p)};
    const SolveReport r_told = p.solve(told);
    // blind: the same factor, the stiffness in A but not declared
    FactoredMicaSolver blind(tight(active_set));
    SolverProblem plain2(mu), q(mu);
    plain2.solve(blind);
    add_triangle_stiffness(q);
    const SolveReport r_blind = q.solve(blind);
    // current: the factor of A with the stiffness
    FactoredMicaSolver current(tight(active_set));
    SolverProblem c(mu);
    add_triangle_stiffness(c);
    const SolveReport r_current = c.solve(current);
    print_message("active set %d: iterations with the stiffness added back %d, left out %d, factored %d\n",
                  int(active_set), r_told.iterations, r_blind.iterations, r_current.iterations);
    for (const SolverProblem* s : {&p, &q, &c}) {
      const double dv = relative_difference(s->v, exact.v), dl = relative_difference(s->lambda, exact.lambda);
      print_message("  against the exact solver: v %.3g, lambda %.3g\n", dv, dl);
      assert_le(dv, 1e-7);
      assert_le(dl, 1e-7);
    }
    assert_true(r_told.converged && r_blind.converged && r_current.converged);
    assert_true(r_told.iterations <= r_current.iterations + 1);
    assert_true(r_blind.iterations > r_told.iterations);
  }
}

// A first prediction that is wrong (the warm start moves the top away from the ceiling it then
// presses against: the small problem predicts no contact): the active-set loop gives that set up
// while its solve is still loose and solves the right one, the same answer as the exact solver in
// fewer iterations than polishing the wrong set first (set_check_residual(0)), both in two rounds
// or more.
static void test_wrong_set_given_up_early(void**) {
  int32_t iterations[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    FactoredMicaSolver solver(tight(true));
    solver.set_check_residual(k ? FactoredMicaSolver::kSetCheckResidual : 0);
    SolverProblem earlier(0.0), p(0.0);  // the factor of an earlier system: solves take a few iterations
    at_rest_shape(earlier);
    earlier.solve(solver);
    p.v.assign(p.v.size(), Vec3(0, -0.5, 0));
    const SolveReport r = p.solve(solver);
    print_message("set check %d: %d iterations in %d rounds\n", k, r.iterations, r.solves);
    assert_true(r.converged);
    assert_true(r.solves >= 2);  // the first set was wrong
    check_solution(p, 1e-8);
    compare(p, 0.0, 1e-7, k ? "set checked" : "set not checked");
    iterations[k] = r.iterations;
  }
  assert_true(iterations[1] < iterations[0]);
}

// The contact nodes' products H_a^T H_b are kept from one solve to the next while the factor's
// columns are the same (prepare_contact_nodes). A solve after one with other contact nodes (every
// other top node) then gives the same bits as a fresh solver's first: the kept blocks are the
// products they stand for, wherever the nodes moved among the slots.
static void test_kept_products_give_the_same_bits(void**) {
  for (bool active_set : kLoops) {
    SolverProblem p(0.3), fresh_p(0.3);
    FactoredMicaSolver kept(tight(active_set)), fresh(tight(active_set));
    const std::vector<Contact> all = p.contacts;
    std::vector<Contact> some;
    for (size_t k = 1; k < all.size(); k += 2) some.push_back(all[k]);
    auto use = [&](const std::vector<Contact>& contacts) {
      p.contacts = contacts;
      p.rows.build(contacts, SolverProblem::kH, 1.0);
      p.lambda.assign(p.rows.size(), 0.0);
      p.v = fresh_p.v;  // the same warm start
      p.impulse = fresh_p.impulse;
    };
    use(some);
    p.solve(kept);
    use(all);
    const SolveReport a = p.solve(kept), b = fresh_p.solve(fresh);
    print_message("active set %d: %d and %d iterations\n", int(active_set), a.iterations, b.iterations);
    assert_int_equal(a.iterations, b.iterations);
    assert_true(p.v == fresh_p.v);
    assert_true(p.lambda == fresh_p.lambda);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_matches_exact),
      cmocka_unit_test(test_warm_start),
      cmocka_unit_test(test_lagged_factor_converges_to_exact),
      cmocka_unit_test(test_new_key_factors_again),
      cmocka_unit_test(test_deadline_stops_the_solve),
      cmocka_unit_test(test_extra_stiffness_is_added_back),
      cmocka_unit_test(test_wrong_set_given_up_early),
      cmocka_unit_test(test_kept_products_give_the_same_bits),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
