// SPDX-License-Identifier: Apache-2.0
// Stable neo-Hookean elements (src/fem/neo_hookean.*): the stress against a finite difference of
// the energy, the Hessian against a finite difference of the stress, the projected Hessian positive
// semidefinite and equal to the Hessian where that already is, Hooke's law at small strain, zero
// force under a rigid motion, the patch test, the assembled stiffness against a finite difference of
// the forces, and finite values through inversion.
#include <Eigen/Eigenvalues>

#include "fem/fem_model.hpp"
#include "fem/neo_hookean.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

const NeoHookean kParams = neo_hookean_parameters(lame_parameters(Material{1e5, 0.45, 1000}));

Mat3 rotation_about(const Vec3& axis, double angle) { return Eigen::AngleAxisd(angle, axis.normalized()).matrix(); }

// A few deformation gradients: stretched, compressed, sheared, nearly flat, inverted.
std::vector<Mat3> sample_gradients() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<Mat3> out;
  for (int k = 0; k < 12; ++k) {
    Mat3 F = Mat3::Identity();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) F(i, j) += u(rng);
    out.push_back(F);
  }
  out.push_back(Vec3(0.7, 0.8, 0.75).asDiagonal());  // compressed: twist modes go negative
  out.push_back(Vec3(1.0, 1.0, 0.02).asDiagonal());  // squashed nearly flat
  out.push_back(Vec3(1.0, 1.1, -0.3).asDiagonal());  // inverted
  out.push_back(rotation_about(Vec3(1, 2, 3), 2.0) * Vec3(1.3, 0.9, 0.6).asDiagonal());
  return out;
}

FemModel cube_model(int32_t tets_per_cell = 6, double nu = 0.45) {
  const TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(1, 0.8, 0.6), {4, 3, 3}, tets_per_cell);
  return build_fem_model(mesh, Material{1e5, nu, 1000}, MassKind::Consistent, "test");
}

Vec3List forces(const FemModel& m, const Vec3List& x) {
  Vec3List f(x.size(), Vec3::Zero());
  assemble_neo_hookean(m, x, NeoHookeanAssembly{}, f);
  return f;
}

}  // namespace

static void test_stress_is_the_energy_gradient(void**) {
  const double d = 1e-6;
  for (const Mat3& F : sample_gradients()) {
    const Mat3 P = neo_hookean_stress(kParams, F);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        Mat3 Fp = F, Fm = F;
        Fp(i, j) += d, Fm(i, j) -= d;
        const double fd = (neo_hookean_energy_density(kParams, Fp) - neo_hookean_energy_density(kParams, Fm)) / (2 * d);
        assert_near(P(i, j), fd, 1e-6 * (1 + P.norm()));
      }
  }
}

static void test_hessian_is_the_stress_gradient(void**) {
  const double d = 1e-6;
  for (const Mat3& F : sample_gradients()) {
    const Mat9 H = neo_hookean_hessian(kParams, F);
    for (int c = 0; c < 9; ++c) {
      Mat3 Fp = F, Fm = F;
      Fp(c % 3, c / 3) += d, Fm(c % 3, c / 3) -= d;
      const Mat3 dP = (neo_hookean_stress(kParams, Fp) - neo_hookean_stress(kParams, Fm)) / (2 * d);
      for (int r = 0; r < 9; ++r) assert_near(H(r, c), dP(r % 3, r / 3), 1e-6 * (1 + H.norm()));
    }
  }
}

static void test_projected_hessian_is_psd_and_exact_where_the_hessian_is(void**) {
  int clamped = 0;
  for (const Mat3& F : sample_gradients()) {
    const Mat9 H = neo_hookean_hessian(kParams, F), Hp = neo_hookean_projected_hessian(kParams, F);
    const Eigen::SelfAdjointEigenSolver<Mat9> eh(H), ep(Hp);
    const double scale = eh.eigenvalues().cwiseAbs().maxCoeff();
    assert_true((Hp - Hp.transpose()).norm() <= 1e-12 * scale);
    assert_true(ep.eigenvalues().minCoeff() >= -1e-10 * scale);
    if (eh.eigenvalues().minCoeff() >= 0) {
      assert_true((Hp - H).norm() <= 1e-10 * scale);
    } else {
      ++clamped;
      // Exactly the clamped spectrum: the same positive eigenvalues, the negative ones at zero.
      const Eigen::VectorXd want = eh.eigenvalues().cwiseMax(0.0);
      Eigen::VectorXd got = ep.eigenvalues();
      for (int k = 0; k < 9; ++k) assert_near(got[k], want[k], 1e-9 * scale);
    }
  }
  printf("projected Hessian: %d of %zu sample gradients had negative eigenvalues clamped\n", clamped,
         sample_gradients().size());
  assert_true(clamped >= 3);
}

static void test_small_strain_tangent_is_hookes_law(void**) {
  const Material mat{2e4, 0.3, 1000};
  const Lame L = lame_parameters(mat);
  const NeoHookean p = neo_hookean_parameters(L);
  const Mat9 H = neo_hookean_hessian(p, Mat3::Identity());
  Mat3 eps;
  eps << 0.3, 0.1, -0.2, 0.1, -0.4, 0.05, -0.2, 0.05, 0.2;
  const Eigen::Matrix<double, 9, 1> dF = Eigen::Map<const Eigen::Matrix<double, 9, 1>>(eps.data());
  const Eigen::Matrix<double, 9, 1> dP = H * dF;
  const Mat3 sigma = stress(L, eps);  // Hooke's law
  for (int k = 0; k < 9; ++k) assert_near(dP[k], sigma(k % 3, k / 3), 1e-9 * mat.youngs_modulus);
  assert_near(neo_hookean_energy_density(p, Mat3::Identity()), 0.0, 1e-12 * mat.youngs_modulus);
  assert_true(neo_hookean_stress(p, Mat3::Identity()).norm() <= 1e-12 * mat.youngs_modulus);
}

static void test_rigid_motion_gives_no_force(void**) {
  const FemModel m = cube_model();
  const Mat3 Q = rotation_about(Vec3(0.3, -1, 0.5), 2.1);
  Vec3List x(m.rest.size());
  for (size_t i = 0; i < x.size(); ++i) x[i] = Q * m.rest[i] + Vec3(1, 2, 3);
  double largest = 0;
  for (const Vec3& f : forces(m, x)) largest = std::max(largest, f.norm());
  const double scale = m.materials[0].youngs_modulus * 0.06;  // E times a cell face, N
  printf("rigid motion: largest node force %.2e N, %.2e of E A\n", largest, largest / scale);
  assert_le(largest, 1e-10 * scale);
}

static void test_patch_uniform_stretch_gives_uniform_stress(void**) {
  for (int32_t tets_per_cell : {5, 6}) {
    const FemModel m = cube_model(tets_per_cell);
    Mat3 G;  // a large affine map: stretch, shear, a rotation
    G << 1.25, 0.1, -0.05, 0.02, 0.85, 0.12, -0.04, 0.06, 1.1;
    G = rotation_about(Vec3(1, 2, 3), 0.7) * G;
    Vec3List x(m.rest.size());
    for (size_t i = 0; i < x.size(); ++i) x[i] = G * m.rest[i] + Vec3(0.3, -0.2, 0.1);
    const Vec3List f = forces(m, x);
    double scale = 0;
    for (const Vec3& fi : f) scale = std::max(scale, fi.norm());
    assert_true(scale > 0);
    for (int32_t i = 0; i < m.node_count(); ++i) {
      const Vec3& p = m.rest[i];
      const bool inside =
          p.x() > 1e-9 && p.x() < 1 - 1e-9 && p.y() > 1e-9 && p.y() < 0.8 - 1e-9 && p.z() > 1e-9 && p.z() < 0.6 - 1e-9;
      if (inside) assert_le(f[i].norm(), 1e-10 * scale);
    }
    // Every element has the same Cauchy stress.
    const Mat3 want = neo_hookean_cauchy(neo_hookean_parameters(m.lame[0]), G);
    for (const TetElement& e : m.elements) {
      const Mat3 got = neo_hookean_cauchy(neo_hookean_parameters(m.lame[0]), deformation_gradient(e, x));
      assert_true((got - want).norm() <= 1e-10 * want.norm());
    }
  }
}

static void test_assembled_stiffness_matches_force_difference(void**) {
  // At a state where no eigenvalue is clamped the projected Hessian is the Hessian: K = -df/dx.
  const FemModel m = cube_model(6, 0.3);
  Mat3 G;
  G << 1.05, 0.02, 0.0, 0.01, 1.03, -0.02, 0.0, 0.01, 1.04;  // mild stretch: the tangent is definite
  Vec3List x(m.rest.size());
  for (size_t i = 0; i < x.size(); ++i) x[i] = G * m.rest[i];
  BlockValues K(m.pattern.block_count(), Mat3::Zero());
  Vec3List f(x.size(), Vec3::Zero());
  NeoHookeanAssembly what;
  what.k_scale = 1;
  what.K = &K;
  assemble_neo_hookean(m, x, what, f);
  const double d = 1e-7;
  double worst = 0, scale = 0;
  for (int32_t j : {0, 7, 23, m.node_count() - 1})
    for (int c = 0; c < 3; ++c) {
      Vec3List xp = x, xm = x;
      xp[j][c] += d, xm[j][c] -= d;
      const Vec3List fp = forces(m, xp), fm = forces(m, xm);
      for (int32_t i = 0; i < m.node_count(); ++i) {
        const int32_t k = m.pattern.find(i, j);
        const Vec3 want = -(fp[i] - fm[i]) / (2 * d);
        const Vec3 got = k >= 0 ? Vec3(K[k].col(c)) : Vec3::Zero();
        worst = std::max(worst, (got - want).norm());
        scale = std::max(scale, want.norm());
      }
    }
  printf("assembled stiffness against -df/dx: %.2e relative\n", worst / scale);
  assert_le(worst, 1e-5 * scale);
}

static void test_linearised_force_term(void**) {
  // f(x_lin) + h H v_lin is what the step adds for a linearisation at x + h v_lin.
  const FemModel m = cube_model(6, 0.3);
  Vec3List x(m.rest.size()), v(m.rest.size());
  for (size_t i = 0; i < x.size(); ++i) {
    x[i] = m.rest[i] * 0.9;
    v[i] = Vec3(std::sin(double(i)), std::cos(3.0 * i), 0.5 * std::sin(2.0 * i));
  }
  BlockValues K(m.pattern.block_count(), Mat3::Zero());
  Vec3List f0(x.size()), f1(x.size());
  NeoHookeanAssembly with_k;
  with_k.k_scale = 1;
  with_k.K = &K;
  assemble_neo_hookean(m, x, with_k, f0);
  NeoHookeanAssembly with_v;
  with_v.v_lin = &v;
  with_v.h = 0.01;
  assemble_neo_hookean(m, x, with_v, f1);
  for (int32_t i = 0; i < m.node_count(); ++i) {
    Vec3 Kv = Vec3::Zero();
    for (int32_t k = m.pattern.row_start[i]; k < m.pattern.row_start[i + 1]; ++k) Kv += K[k] * v[m.pattern.col[k]];
    assert_true((f1[i] - (f0[i] + 0.01 * Kv)).norm() <= 1e-9 * (1 + f0[i].norm() + 0.01 * Kv.norm()));
  }
}

static void test_inverted_and_flat_elements_stay_finite_and_push_back(void**) {
  const FemModel m = cube_model();
  for (double squash : {0.0, -0.5}) {  // flat, then inverted through the z = 0 plane
    Vec3List x(m.rest.size());
    for (size_t i = 0; i < x.size(); ++i) x[i] = Vec3(m.rest[i].x(), m.rest[i].y(), squash * m.rest[i].z());
    const Vec3List f = forces(m, x);
    for (const Vec3& fi : f) assert_true(fi.allFinite());
    BlockValues K(m.pattern.block_count(), Mat3::Zero());
    Vec3List g(x.size());
    NeoHookeanAssembly what;
    what.k_scale = 1;
    what.K = &K;
    assemble_neo_hookean(m, x, what, g);
    for (const Mat3& k : K) assert_true(k.allFinite());
    // The force on the top layer points up (back toward the rest shape).
    double up = 0;
    for (int32_t i = 0; i < m.node_count(); ++i)
      if (m.rest[i].z() > 0.6 - 1e-9) up += f[i].z();
    printf("squash %.1f: net force on the top face %.3g N (up is positive)\n", squash, up);
    assert_true(up > 0);
  }
}

int main(int argc, char** argv) {
  (void)argc, (void)argv;
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_stress_is_the_energy_gradient),
      cmocka_unit_test(test_hessian_is_the_stress_gradient),
      cmocka_unit_test(test_projected_hessian_is_psd_and_exact_where_the_hessian_is),
      cmocka_unit_test(test_small_strain_tangent_is_hookes_law),
      cmocka_unit_test(test_rigid_motion_gives_no_force),
      cmocka_unit_test(test_patch_uniform_stretch_gives_uniform_stress),
      cmocka_unit_test(test_assembled_stiffness_matches_force_difference),
      cmocka_unit_test(test_linearised_force_term),
      cmocka_unit_test(test_inverted_and_flat_elements_stay_finite_and_push_back),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
