// SPDX-License-Identifier: Apache-2.0
// The isotropic Coulomb cone: the disk projection every contact solver shares, the exact solve of
// one contact (friction_cone.hpp) against hand-solved cases, the natural residual cone_error
// (lcp.hpp), and the dense solver (frictional_contact.hpp) on random problems, checked against
// the Coulomb conditions directly (test_frictional_contact_oracle.cpp compares with Siconos).
#include "solver/friction_cone.hpp"
#include "solver/frictional_contact.hpp"
#include "solver/lcp_problems.hpp"
#include "test_util.hpp"

#include <cstdio>
#include <cstring>

using namespace mica;
using namespace lcp_problems;

namespace {

struct Case {
  const char* name;
  double a, b, c;  // inputs
  double x, y, z;  // expected
};

// 3-row contacts (normal, t1, t2) coupled through an SPD M; the normal rows pressing.
struct ContactProblem {
  Eigen::MatrixXd M;
  Eigen::VectorXd q, mu;
  std::vector<int32_t> normal_of;
};

ContactProblem random_contacts(int32_t contacts, uint32_t seed, double mu_max) {
  const int32_t n = 3 * contacts;
  const Problem p = spd(n, 300u * uint32_t(contacts) + seed);
  ContactProblem c{p.M, p.q, Eigen::VectorXd::Zero(n), std::vector<int32_t>(size_t(n), -1)};
  Rng rng(seed);
  for (int32_t k = 0; k < contacts; ++k) {
    c.q(3 * k) = -std::fabs(c.q(3 * k)) - 0.1;  // pressing
    const double mu = rng.uniform(0, mu_max);
    for (int32_t t : {1, 2}) {
      c.normal_of[size_t(3 * k + t)] = 3 * k;
      c.mu(3 * k + t) = mu;
    }
  }
  return c;
}

// The Coulomb conditions row by row, independently of cone_error: normal complementarity, the
// disk, w_t = 0 when sticking, and when sliding w_t opposite z_t (maximal dissipation).
void expect_coulomb(const ContactProblem& p, const Eigen::VectorXd& z, double tol) {
  const Eigen::VectorXd w = p.M * z + p.q;
  for (Eigen::Index n = 0; n < z.size(); n += 3) {
    const double mu = p.mu(n + 1);
    assert_le(-z(n), tol);
    assert_le(-w(n), tol);
    assert_le(std::min(z(n), w(n)), tol);
    const Eigen::Vector2d zt(z(n + 1), z(n + 2)), wt(w(n + 1), w(n + 2));
    assert_le(zt.norm(), mu * z(n) + tol);
    if (zt.norm() < mu * z(n) - tol) {
      assert_le(wt.norm(), tol);  // sticking
    } else if (wt.norm() > tol && zt.norm() > tol) {  // sliding: the friction impulse opposes the slip
      assert_le(zt.dot(wt), -(1 - 1e-6) * zt.norm() * wt.norm());
    }
  }
}

}  // namespace

static void test_disk_projection(void**) {
  const Case cases[] = {
      {"inside: unchanged", 1.0, 0.3, -0.4, 0, 0.3, -0.4},
      {"on the rim: unchanged", 0.5, 0.3, -0.4, 0, 0.3, -0.4},
      {"outside: scaled to the rim, same direction", 0.5, 3.0, -4.0, 0, 0.3, -0.4},
      {"outside along the diagonal (a box would keep 0.5, 0.5)", 0.5, 0.5, 0.5, 0, 0.5 / std::sqrt(2.0), 0.5 / std::sqrt(2.0)},
      {"zero radius: the origin", 0.0, 0.3, -0.4, 0, 0, 0},
      {"negative radius: the origin", -1.0, 0.3, -0.4, 0, 0, 0},
  };
  for (const Case& c : cases) {
    double t1 = c.b, t2 = c.c;
    project_onto_disk(c.a, t1, t2);
    print_message("%s: (%.17g, %.17g)\n", c.name, t1, t2);
    assert_near(t1, c.y, 1e-15);
    assert_near(t2, c.z, 1e-15);
  }
  // The whole contact: a negative normal impulse gives zero, friction included.
  const Case cone[] = {
      {"pressing, tangent inside", 2.0, 0.3, 0.4, 2.0, 0.3, 0.4},
      {"pressing, tangent outside (mu = 0.5)", 0.4, 3.0, 4.0, 0.4, 0.12, 0.16},
      {"pulling", -1.0, 0.3, 0.4, 0, 0, 0},
  };
  for (const Case& c : cone) {
    double n = c.a, t1 = c.b, t2 = c.c;
    project_onto_cone(0.5, n, t1, t2);
    print_message("%s: (%.17g, %.17g, %.17g)\n", c.name, n, t1, t2);
    assert_near(n, c.x, 1e-15);
    assert_near(t1, c.y, 1e-15);
    assert_near(t2, c.z, 1e-15);
  }
}

// One contact with W = diag(2, 4, 4) (mu = 0.5): hand-solved. q -> expected impulse.
static void test_local_solve_hand_solved(void**) {
  const Mat3 W = Vec3(2, 4, 4).asDiagonal();
  const double s = 1 / std::sqrt(2.0);
  const Case cases[] = {
      {"separating", 0.3, 1.0, -2.0, 0, 0, 0},
      {"touching, no load", 0.0, 1.0, -2.0, 0, 0, 0},
      {"sticking", -2.0, 1.0, -0.4, 1.0, -0.25, 0.1},  // z = -W^-1 q, |z_t| = 0.27 < 0.5
      {"sliding along t1", -2.0, 4.0, 0.0, 1.0, -0.5, 0.0},
      {"sliding along the diagonal (a box gives 0.5 sqrt 2)", -2.0, 4.0, 4.0, 1.0, -0.5 * s, -0.5 * s},
      {"sliding, just past the rim", -2.0, 2.0 + 1e-9, 0.0, 1.0, -0.5, 0.0},
  };
  for (const Case& c : cases) {
    const Vec3 z = solve_contact_coulomb(W, Vec3(c.a, c.b, c.c), 0.5);
    print_message("%s: (%.17g, %.17g, %.17g)\n", c.name, z(0), z(1), z(2));
    assert_near(z(0), c.x, 1e-14);
    assert_near(z(1), c.y, 1e-14);
    assert_near(z(2), c.z, 1e-14);
  }
  // Frictionless: the normal alone.
  const Vec3 z = solve_contact_coulomb(W, Vec3(-2, 4, 4), 0.0);
  assert_near(z(0), 1.0, 1e-15);
  assert_near(z.tail<2>().norm(), 0.0, 0.0);
  // An absent tangent row (decoupled, q = 0) stays at zero: sliding along t1 only.
  const Vec3 z1 = solve_contact_coulomb(W, Vec3(-2, 4, 0), 0.5);
  assert_near(z1(2), 0.0, 0.0);
}

// Coupled 3x3 blocks (normal and tangents interact, unequal tangent compliances): the exact local
// solve satisfies the Coulomb conditions to round-off, sticking and sliding, small and large mu.
static void test_local_solve_coupled(void**) {
  int32_t sliding = 0;
  for (uint32_t seed = 1; seed <= 200; ++seed) {
    ContactProblem p = random_contacts(1, seed, seed % 2 ? 0.3 : 3.0);
    const Vec3 z = solve_contact_coulomb(p.M, p.q, p.mu(1));
    const Eigen::VectorXd zv = z;
    assert_le(cone_error(p.M, p.q, p.mu, p.normal_of, zv), 1e-14);
    expect_coulomb(p, zv, 1e-13);
    sliding += std::hypot(z(1), z(2)) >= p.mu(1) * z(0) * (1 - 1e-12);
  }
  print_message("%d of 200 contacts slide\n", sliding);
  assert_true(sliding > 20 && sliding < 180);  // both regimes covered
}

// cone_error is zero exactly at Coulomb solutions: the box answer on a diagonal, friction along
// the slip, a sticking contact that moves, or a negative normal impulse each show.
static void test_cone_error_sees_violations(void**) {
  const Eigen::MatrixXd M = Eigen::MatrixXd::Identity(3, 3);
  const Eigen::VectorXd mu = (Eigen::VectorXd(3) << 0, 0.5, 0.5).finished();
  const std::vector<int32_t> normal_of = {-1, 0, 0};
  const Eigen::VectorXd q = (Eigen::VectorXd(3) << -1, 2, 2).finished();
  struct Row {
    const char* name;
    Eigen::Vector3d z;
    bool solution;
  };
  const double s = 0.5 / std::sqrt(2.0);
  const Row rows[] = {
      {"the cone's answer", {1, -s, -s}, true},
      {"the box's answer", {1, -0.5, -0.5}, false},
      {"friction along the slip", {1, s, s}, false},
      {"inside the disk while slipping", {1, -0.1, -0.1}, false},
      {"negative normal impulse", {-1, 0, 0}, false},
  };
  for (const Row& r : rows) {
    const double e = cone_error(M, q, mu, normal_of, r.z);
    print_message("%s: cone_error %.3g\n", r.name, e);
    if (r.solution) assert_le(e, 1e-15);
    else assert_true(e > 0.05);
  }
}

// The dense solver on random coupled contacts: solved, cone_error below 1e-10, and the Coulomb
// conditions checked row by row. Also prints the sweeps and Newton steps it took.
static void test_dense_random_problems(void**) {
  for (int32_t contacts : {1, 2, 5, 10, 30})
    for (uint32_t seed = 1; seed <= 3; ++seed)
      for (double mu_max : {0.3, 1.0, 3.0}) {
        const ContactProblem p = random_contacts(contacts, seed, mu_max);
        FrictionalSettings tight;
        tight.tolerance = 1e-13;
        const FrictionalSolution s = solve_frictional_contact(p.M, p.q, p.mu, p.normal_of, Eigen::VectorXd(), tight);
        if (!s.solved) fail_msg("%d contacts, seed %u, mu <= %g: %s", contacts, seed, mu_max, s.message.c_str());
        if (seed == 1) print_message("%d contacts, mu <= %g: %s\n", contacts, mu_max, s.message.c_str());
        assert_le(cone_error(p.M, p.q, p.mu, p.normal_of, s.z), 1e-10);
        expect_coulomb(p, s.z, 1e-9);
        // Started at its solution it does nothing.
        const FrictionalSolution again = solve_frictional_contact(p.M, p.q, p.mu, p.normal_of, s.z, tight);
        assert_true(again.solved);
        assert_int_equal(again.sweeps, 0);
      }
}

// A tolerance that cannot be met is said, not thrown; a deadline in the past stops at once.
static void test_unsolved_is_reported(void**) {
  const ContactProblem p = random_contacts(30, 2, 1.0);
  FrictionalSettings few;
  few.max_sweeps = 20;
  few.tolerance = 0;
  const FrictionalSolution s = solve_frictional_contact(p.M, p.q, p.mu, p.normal_of, Eigen::VectorXd(), few);
  print_message("%s\n", s.message.c_str());
  assert_false(s.solved);
  assert_true(s.z.allFinite());
  FrictionalSettings late;
  late.deadline = std::chrono::steady_clock::now() - std::chrono::seconds(1);
  const FrictionalSolution t = solve_frictional_contact(p.M, p.q, p.mu, p.normal_of, Eigen::VectorXd(), late);
  assert_true(t.out_of_time);
  assert_false(t.solved);
  assert_int_equal(t.sweeps, 0);
}

// A problem from a fuzzed scene (tests/data/frictional_stall.txt): 72 frictionless contact rows
// whose Delassus matrix is singular (redundant contacts), on which Lemke's pivoting ends on a ray,
// so the exact solver falls back to these sweeps. They stall near a relative residual of 1e-4.
// Before the stall rule the solve spent its whole budget there (10^4 sweeps, 78 Newton steps: 40 s
// a step under the fuzzer's sanitizers); now it says "stalled" within a few windows and returns
// admissible impulses no worse than where it stalled.
static void test_stall_stops_early(void**) {
  std::FILE* f = std::fopen(MICA_TEST_DATA_DIR "/frictional_stall.txt", "r");
  assert_non_null(f);
  char line[256];
  while (std::fgets(line, sizeof line, f) && line[0] == '#') {
  }
  int n = 0, rows = 0;
  assert_int_equal(std::sscanf(line, "%d %d", &n, &rows), 2);
  ContactProblem p{Eigen::MatrixXd(n, n), Eigen::VectorXd(n), Eigen::VectorXd(n), std::vector<int32_t>(size_t(n))};
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) assert_int_equal(std::fscanf(f, "%lf", &p.M(i, j)), 1);
  double z0 = 0;
  for (int i = 0; i < n; ++i)
    assert_int_equal(std::fscanf(f, "%lf %lf %d %lf", &p.q(i), &p.mu(i), &p.normal_of[size_t(i)], &z0), 4);
  std::fclose(f);
  const FrictionalSettings defaults;
  const FrictionalSolution s = solve_frictional_contact(p.M, p.q, p.mu, p.normal_of, Eigen::VectorXd(), defaults);
  print_message("%s\n", s.message.c_str());
  assert_false(s.solved);
  assert_non_null(std::strstr(s.message.c_str(), "stalled"));
  assert_true(s.sweeps < defaults.max_sweeps);
  assert_true(s.z.allFinite());
  assert_true(s.error <= 1e-3 * s.scale);
  for (int i = 0; i < n; ++i) {
    if (p.normal_of[size_t(i)] >= 0) continue;
    assert_true(s.z(i) >= 0);
    double t2 = 0, mu = 0;  // a contact's mu is on its tangent rows
    for (int j = 0; j < n; ++j)
      if (p.normal_of[size_t(j)] == i) {
        t2 += s.z(j) * s.z(j);
        mu = p.mu(j);
      }
    assert_true(std::sqrt(t2) <= mu * s.z(i) * (1 + 1e-12) + 1e-300);
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
  const Eigen::MatrixXd I3 = Eigen::MatrixXd::Identity(3, 3);
  const Eigen::VectorXd q = (Eigen::VectorXd(3) << -1, 0, 0).finished();
  const Eigen::VectorXd mu = (Eigen::VectorXd(3) << 0, 0.5, 0.5).finished();
  const Eigen::VectorXd z = Eigen::VectorXd::Zero(3);
  // A friction row must name a normal row.
  assert_true(throws_invalid([&] { cone_error(I3, q, mu, {-1, 0, 1}, z); }));
  // mu >= 0, the same on both tangents.
  assert_true(throws_invalid([&] { cone_error(I3, q, (Eigen::VectorXd(3) << 0, -0.5, -0.5).finished(), {-1, 0, 0}, z); }));
  assert_true(throws_invalid([&] { cone_error(I3, q, (Eigen::VectorXd(3) << 0, 0.5, 0.4).finished(), {-1, 0, 0}, z); }));
  // At most two tangents.
  assert_true(throws_invalid([&] {
    cone_error(Eigen::MatrixXd::Identity(4, 4), Eigen::VectorXd::Zero(4), Eigen::VectorXd::Constant(4, 0.5),
               {-1, 0, 0, 0}, Eigen::VectorXd::Zero(4));
  }));
  // A wrong warm start.
  assert_true(throws_invalid([&] {
    solve_frictional_contact(I3, q, mu, {-1, 0, 0}, Eigen::VectorXd::Zero(2), FrictionalSettings{});
  }));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_disk_projection),
      cmocka_unit_test(test_local_solve_hand_solved),
      cmocka_unit_test(test_local_solve_coupled),
      cmocka_unit_test(test_cone_error_sees_violations),
      cmocka_unit_test(test_dense_random_problems),
      cmocka_unit_test(test_unsolved_is_reported),
      cmocka_unit_test(test_stall_stops_early),
      cmocka_unit_test(test_bad_input_throws),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
