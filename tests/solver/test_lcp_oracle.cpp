// SPDX-License-Identifier: Apache-2.0
// Independent oracle for solve_lcp_lemke: Siconos numerics' lexicographic Lemke solver
// (SICONOS_LCP_LEMKE through linearComplementarity_driver), a test-only dependency wired by
// tests/solver/oracle.cmake. On the random LCPs of test_lcp.cpp both must satisfy
// complementarity to 1e-8; where the solution is unique (M positive definite) the two z must
// agree to 1e-8, and for singular symmetric positive semidefinite M, where z may not be
// unique, w = M z + q still is and must agree (there Siconos is trusted only where its driver
// reports success: see test_semidefinite_singular_w_agrees).
// Built without Siconos, the test exits with code 77, which ctest reports as skipped.
// Built without oracle.cmake (MICA_HAVE_SICONOS undefined), it fails and says so.
#include "solver/lcp.hpp"
#include "solver/lcp_problems.hpp"
#include "test_util.hpp"

#if MICA_HAVE_SICONOS
// C headers of libsiconos-numerics-dev (/usr/include/siconos/numerics); they carry their own
// extern "C" guards.
#include "LCP_Solvers.h"
#include "LinearComplementarityProblem.h"
#include "NonSmoothDrivers.h"
#include "NumericsMatrix.h"
#include "SolverOptions.h"
#include "lcp_cst.h"
#endif

using namespace mica;
using namespace lcp_problems;

#if MICA_HAVE_SICONOS

namespace {

struct OracleResult {
  Eigen::VectorXd z, w;
  int info = -1;  // 0: solved; otherwise the driver's failure code
  int pivots = 0;
};

OracleResult siconos_lemke(const Eigen::MatrixXd& M, const Eigen::VectorXd& q) {
  const int n = int(q.size());
  // Siconos' dense storage is column-major, like Eigen's default.
  NumericsMatrix* matrix = NM_create(NM_DENSE, n, n);
  std::memcpy(matrix->matrix0, M.data(), sizeof(double) * size_t(n) * size_t(n));
  Eigen::VectorXd q_copy = q;  // the problem holds a non-const pointer
  LinearComplementarityProblem problem{};
  problem.size = n;
  problem.M = matrix;
  problem.q = q_copy.data();

  SolverOptions* options = solver_options_create(SICONOS_LCP_LEMKE);
  options->iparam[SICONOS_IPARAM_MAX_ITER] = 50 * n + 10;
  options->dparam[SICONOS_DPARAM_TOL] = 1e-8;  // the driver's own a-posteriori check

  OracleResult r;
  r.z = Eigen::VectorXd::Zero(n);
  r.w = Eigen::VectorXd::Zero(n);
  r.info = linearComplementarity_driver(&problem, r.z.data(), r.w.data(), options);
  r.pivots = options->iparam[SICONOS_IPARAM_ITER_DONE];
  solver_options_delete(options);
  NM_free(matrix);
  return r;
}

// Ours solves the problem to 1e-8 relative complementarity.
LcpSolution ours_solves(const Problem& p, const char* kind) {
  LcpSolution ours = solve_lcp_lemke(p.M, p.q);
  if (!ours.solved) fail_msg("%s, n = %d: ours not solved: %s", kind, int(p.q.size()), ours.message.c_str());
  assert_le(relative_complementarity(p.M, p.q, ours.z), 1e-8);
  return ours;
}

}  // namespace

static void test_positive_definite_unique_solution_agrees(void**) {
  int compared = 0;
  for (int32_t n : {1, 2, 3, 5, 8, 13, 20, 30, 45, 60})
    for (uint32_t seed = 1; seed <= 5; ++seed) {
      const Problem p = spd(n, 1000u * uint32_t(n) + seed);
      const LcpSolution ours = ours_solves(p, "SPD");
      const OracleResult oracle = siconos_lemke(p.M, p.q);
      if (oracle.info != 0) fail_msg("SPD, n = %d, seed %u: Siconos info = %d", n, seed, oracle.info);
      assert_le(relative_complementarity(p.M, p.q, oracle.z), 1e-8);
      assert_le(relative_difference(ours.z, oracle.z), 1e-8);
      assert_le(relative_difference(ours.w, p.M * oracle.z + p.q), 1e-8);
      ++compared;
    }
  assert_int_equal(compared, 50);
}

// Siconos' lexicolemke accepts any positive pivot, with no tolerance: on an exactly singular
// M a round-off entry (~1e-17) can be taken as a pivot and derail it, and its driver then
// reports failure (info != 0; seen on rank-1 M and on many copies of one row). So its answer
// serves as the oracle where its driver vouches for it, ours must solve every problem, and
// the oracle must cover most of them for the comparison to mean something.
static void test_semidefinite_singular_w_agrees(void**) {
  int total = 0, covered = 0;
  auto compare = [&](const Problem& p, const char* kind) {
    const LcpSolution ours = ours_solves(p, kind);
    const OracleResult oracle = siconos_lemke(p.M, p.q);
    ++total;
    if (oracle.info != 0) return;
    ++covered;
    assert_le(relative_complementarity(p.M, p.q, oracle.z), 1e-8);
    // z may differ (copies of a row split their impulse arbitrarily), but for symmetric PSD
    // M every solution has the same M z, hence the same w.
    assert_le(relative_difference(ours.w, p.M * oracle.z + p.q), 1e-8);
  };
  // Redundant contacts: copies of rows of an SPD base, with equal or different q.
  for (int32_t m : {1, 3, 10, 30})
    for (uint32_t seed = 1; seed <= 4; ++seed)
      for (bool same_q : {true, false})
        compare(duplicated(m, std::min(60, 2 * m), 50u * uint32_t(m) + seed, same_q).problem, "duplicated");
  // Low rank M = B B^T with a feasible q.
  for (int32_t n : {2, 5, 10, 25, 40, 60})
    for (int32_t k : {1, n / 2, n - 1}) {
      if (k < 1) continue;
      for (uint32_t seed = 1; seed <= 3; ++seed) compare(low_rank(n, k, 7u * uint32_t(n + k) + seed), "low rank");
    }
  std::printf("Siconos vouched for %d of %d singular problems (ours solved all)\n", covered, total);
  assert_le(4 * (total - covered), total);
}

static void test_infeasible_problems_fail_in_both(void**) {
  const Eigen::MatrixXd skew = (Eigen::MatrixXd(2, 2) << 0, -1, 1, 0).finished();
  const Problem problems[] = {
      {-Eigen::MatrixXd::Identity(3, 3), -Eigen::VectorXd::Ones(3)},  // w = q - z < 0
      {skew, -Eigen::VectorXd::Ones(2)},                               // w_0 = -z_1 - 1 < 0
  };
  for (const Problem& p : problems) {
    const LcpSolution ours = solve_lcp_lemke(p.M, p.q);
    assert_false(ours.solved);
    assert_false(ours.message.empty());
    assert_int_not_equal(siconos_lemke(p.M, p.q).info, 0);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_positive_definite_unique_solution_agrees),
      cmocka_unit_test(test_semidefinite_singular_w_agrees),
      cmocka_unit_test(test_infeasible_problems_fail_in_both),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

#elif defined(MICA_HAVE_SICONOS)

int main(void) {
  std::printf("test_lcp_oracle: Siconos numerics not found (libsiconos-numerics-dev); skipped\n");
  return 77;  // SKIP_RETURN_CODE, set by tests/solver/oracle.cmake
}

#else

int main(void) {
  std::printf("test_lcp_oracle: tests/solver/oracle.cmake is not included from tests/CMakeLists.txt\n");
  return 1;
}

#endif
