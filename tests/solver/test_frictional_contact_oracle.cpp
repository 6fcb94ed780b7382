// SPDX-License-Identifier: Apache-2.0
// Independent oracle for solve_frictional_contact: Siconos numerics' 3-D frictional contact
// solver (SICONOS_FRICTION_3D_NSGS through fc3d_driver; its rows are ordered normal, t1, t2 per
// contact as ours, and its velocity is u = M r + q, with the Coulomb law in De Saxce's form,
// whose solutions are exactly the Coulomb ones). On random well-posed problems (SPD M, pressing
// normals) both must satisfy cone_error to 1e-9 and, where Siconos' driver reports success, the
// impulses must agree to 1e-6 relative (its own stopping test is a relative 1e-12 error).
// Built without Siconos it exits with 77 (skipped), as test_lcp_oracle does.
#include "solver/frictional_contact.hpp"
#include "solver/lcp_problems.hpp"
#include "test_util.hpp"

#if MICA_HAVE_SICONOS
#include "FrictionContactProblem.h"
#include "Friction_cst.h"
#include "NonSmoothDrivers.h"
#include "NumericsMatrix.h"
#include "SolverOptions.h"
#endif

using namespace mica;
using namespace lcp_problems;

#if MICA_HAVE_SICONOS

namespace {

struct Oracle {
  Eigen::VectorXd z, w;
  int info = -1;
};

Oracle siconos_fc3d(const Eigen::MatrixXd& M, const Eigen::VectorXd& q, const Eigen::VectorXd& mu_per_contact) {
  const int n = int(q.size());
  NumericsMatrix* matrix = NM_create(NM_DENSE, n, n);
  std::memcpy(matrix->matrix0, M.data(), sizeof(double) * size_t(n) * size_t(n));  // column-major both
  Eigen::VectorXd q_copy = q, mu_copy = mu_per_contact;
  FrictionContactProblem problem{};
  problem.dimension = 3;
  problem.numberOfContacts = n / 3;
  problem.M = matrix;
  problem.q = q_copy.data();
  problem.mu = mu_copy.data();
  SolverOptions* options = solver_options_create(SICONOS_FRICTION_3D_NSGS);
  options->iparam[SICONOS_IPARAM_MAX_ITER] = 100000;
  options->dparam[SICONOS_DPARAM_TOL] = 1e-12;
  Oracle r;
  r.z = Eigen::VectorXd::Zero(n);
  r.w = Eigen::VectorXd::Zero(n);
  r.info = fc3d_driver(&problem, r.z.data(), r.w.data(), options);
  solver_options_delete(options);
  NM_free(matrix);
  return r;
}

}  // namespace

static void test_random_problems_agree_with_siconos(void**) {
  int total = 0, covered = 0;
  for (int32_t contacts : {1, 2, 3, 5, 10, 20})
    for (uint32_t seed = 1; seed <= 4; ++seed)
      for (double mu_max : {0.3, 1.0}) {
        const int32_t n = 3 * contacts;
        Problem p = spd(n, 700u * uint32_t(contacts) + seed);
        Rng rng(seed + 17u);
        Eigen::VectorXd mu = Eigen::VectorXd::Zero(n), mu_c(contacts);
        std::vector<int32_t> normal_of(size_t(n), -1);
        for (int32_t c = 0; c < contacts; ++c) {
          p.q(3 * c) = -std::fabs(p.q(3 * c)) - 0.1;
          mu_c(c) = rng.uniform(0, mu_max);
          for (int32_t t : {1, 2}) {
            normal_of[size_t(3 * c + t)] = 3 * c;
            mu(3 * c + t) = mu_c(c);
          }
        }
        FrictionalSettings fs;
        fs.tolerance = 1e-13;
        const FrictionalSolution ours = solve_frictional_contact(p.M, p.q, mu, normal_of, Eigen::VectorXd(), fs);
        if (!ours.solved) fail_msg("%d contacts, seed %u: %s", contacts, seed, ours.message.c_str());
        assert_le(cone_error(p.M, p.q, mu, normal_of, ours.z), 1e-10);
        const Oracle oracle = siconos_fc3d(p.M, p.q, mu_c);
        ++total;
        if (oracle.info != 0) continue;
        ++covered;
        assert_le(cone_error(p.M, p.q, mu, normal_of, oracle.z), 1e-9);
        const double scale = std::max(1.0, ours.z.cwiseAbs().maxCoeff());
        const double diff = (ours.z - oracle.z).cwiseAbs().maxCoeff() / scale;
        if (!(diff <= 1e-6)) fail_msg("%d contacts, seed %u, mu <= %g: impulses differ by %.3g", contacts, seed, mu_max, diff);
      }
  std::printf("Siconos fc3d_nsgs vouched for %d of %d problems (ours solved all)\n", covered, total);
  assert_le(4 * (total - covered), total);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_random_problems_agree_with_siconos),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}

#elif defined(MICA_HAVE_SICONOS)

int main(void) {
  std::printf("test_frictional_contact_oracle: Siconos numerics not found (libsiconos-numerics-dev); skipped\n");
  return 77;
}

#else

int main(void) {
  std::printf("test_frictional_contact_oracle: tests/solver/oracle.cmake is not included from tests/CMakeLists.txt\n");
  return 1;
}

#endif
