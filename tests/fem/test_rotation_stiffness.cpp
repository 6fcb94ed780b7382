// SPDX-License-Identifier: Apache-2.0
// The co-rotational energy's derivatives: the element force is its exact gradient, and the warped
// stiffness R Ke R^T plus the twist modes is its exact Hessian (fem/rotation_stiffness.hpp), both
// against central finite differences of the energy; the projected twist stiffness is positive
// semidefinite and vanishes at rest.
#include <Eigen/Eigenvalues>

#include "fem/rotation.hpp"
#include "fem/rotation_stiffness.hpp"
#include "fem/tet_element.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

using Mat12 = Eigen::Matrix<double, 12, 12>;

struct Element {
  Vec3List rest;
  TetElement el;
  Lame lame{3.0e4, 1.0e4};
};

Element make_element(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Element e;
  e.rest = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  for (Vec3& p : e.rest) p = 0.1 * (p + 0.1 * Vec3(u(rng), u(rng), u(rng)));
  e.el = make_tet_element(e.rest, Tet{0, 1, 2, 3});
  return e;
}

// Turned by up to ~2 rad and deformed by `strain` (relative), optionally inverted (node 3 through the
// opposite face).
Vec3List deformed(const Element& e, std::mt19937& rng, double strain, bool invert) {
  std::uniform_real_distribution<double> u(-1, 1);
  const Mat3 R = Eigen::AngleAxisd(2 * u(rng), Vec3(u(rng), u(rng), u(rng)).normalized()).matrix();
  Vec3List x = e.rest;
  if (invert) x[3] = Vec3(0.03, 0.03, -0.05);
  for (Vec3& p : x) p = R * (p + 0.1 * strain * Vec3(u(rng), u(rng), u(rng)));
  return x;
}

double energy(const Element& e, const Vec3List& x) {
  const Mat3 F = deformation_gradient(e.el, x);
  return elastic_energy(e.el, e.lame, proper_rotation(F), F);
}

Mat12 hessian(const Element& e, const Vec3List& x, bool positive_only, bool twist) {
  const Mat3 F = deformation_gradient(e.el, x);
  Mat3 K[16];
  rotated_stiffness(e.el, e.lame, proper_rotation(F), 1.0, K);
  const TwistModes t = twist_modes(e.el, e.lame, F, positive_only);
  Mat12 H;
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) {
      Mat3 block = K[4 * a + b];
      for (int q = 0; twist && q < t.count; ++q) block += t.weight[q] * t.q[q][a] * t.q[q][b].transpose();
      H.block<3, 3>(3 * a, 3 * b) = block;
    }
  return H;
}

Mat12 hessian_by_differences(const Element& e, const Vec3List& x) {
  const double d = 1e-6;
  Mat12 H;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j) {
      auto at = [&](double di, double dj) {
        Vec3List y = x;
        y[i / 3][i % 3] += di;
        y[j / 3][j % 3] += dj;
        return energy(e, y);
      };
      H(i, j) = (at(d, d) - at(d, -d) - at(-d, d) + at(-d, -d)) / (4 * d * d);
    }
  return H;
}

}  // namespace

static void test_force_is_the_energy_gradient(void**) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 8; ++trial) {
    const Element e = make_element(rng);
    const Vec3List x = deformed(e, rng, trial < 4 ? 0.05 : 0.3, trial % 4 == 3);
    Vec3List f(4, Vec3::Zero());
    const Mat3 F = deformation_gradient(e.el, x);
    add_elastic_forces(e.el, e.lame, proper_rotation(F), F, f);
    double err = 0, scale = 0;
    for (int i = 0; i < 12; ++i) {
      const double d = 1e-7;
      Vec3List p = x, m = x;
      p[i / 3][i % 3] += d;
      m[i / 3][i % 3] -= d;
      const double grad = (energy(e, p) - energy(e, m)) / (2 * d);
      err = std::max(err, std::fabs(f[i / 3][i % 3] + grad));
      scale = std::max(scale, std::fabs(grad));
    }
    assert_le(err, 1e-6 * scale);
  }
}

static void test_warped_stiffness_plus_twists_is_the_hessian(void**) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 8; ++trial) {
    const Element e = make_element(rng);
    const Vec3List x = deformed(e, rng, trial < 4 ? 0.05 : 0.3, trial % 4 == 3);
    const Mat12 fd = hessian_by_differences(e, x);
    const double exact = (hessian(e, x, false, true) - fd).norm() / fd.norm();
    const double warped = (hessian(e, x, false, false) - fd).norm() / fd.norm();
    print_message("trial %d: |K + G - H_fd| / |H_fd| = %.2e, |K - H_fd| / |H_fd| = %.2e\n", trial, exact, warped);
    assert_le(exact, 1e-4);
    assert_true(warped > 10 * exact);  // the twists are what the warped stiffness misses
  }
}

static void test_projected_twists_are_positive_and_vanish_at_rest(void**) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Element e = make_element(rng);
    const Vec3List x = deformed(e, rng, 0.4, trial % 5 == 4);
    const TwistModes t = twist_modes(e.el, e.lame, deformation_gradient(e.el, x));
    for (int q = 0; q < t.count; ++q) assert_true(t.weight[q] > 0);
    const Eigen::SelfAdjointEigenSolver<Mat12> eig(hessian(e, x, true, true));
    assert_true(eig.eigenvalues().minCoeff() >= -1e-9 * eig.eigenvalues().maxCoeff());
  }
  // At rest (and turned rigidly) every twist eigenvalue is zero: nothing to add.
  const Element e = make_element(rng);
  Vec3List x = e.rest;
  const Mat3 R = Eigen::AngleAxisd(1.3, Vec3(1, -2, 0.5).normalized()).matrix();
  for (Vec3& p : x) p = R * p;
  const TwistModes t = twist_modes(e.el, e.lame, deformation_gradient(e.el, x));
  for (int q = 0; q < t.count; ++q) assert_le(t.weight[q], 1e-9 * e.el.volume * e.lame.mu);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_force_is_the_energy_gradient),
      cmocka_unit_test(test_warped_stiffness_plus_twists_is_the_hessian),
      cmocka_unit_test(test_projected_twists_are_positive_and_vanish_at_rest),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
