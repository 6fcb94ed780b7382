// SPDX-License-Identifier: Apache-2.0
// The neo-Hookean assembly's four-wide kernel (src/fem/neo_hookean_elements4.*, AVX2 where the CPU
// has it) against the plain per-element reference add_neo_hookean_element: every output (forces
// with the linearisation term, stiffness blocks, rotations, the per-element quadratic model) on
// chosen and random deformation gradients, inverted, flat and needle-like ones included; the
// scatter when the four share nodes and blocks; its eigensystems (src/fem/eigensystems4.hpp)
// against Eigen's computeDirect; and the quadratic model's energies four at a time
// (src/fem/neo_hookean_energies4.*) against their per-element reference.
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "fem/eigensystems4.hpp"
#include "fem/fem_model.hpp"
#include "fem/neo_hookean.hpp"
#include "fem/neo_hookean_elements4.hpp"
#include "fem/neo_hookean_energies4.hpp"
#include "fem/rotation_variant_svd.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

Mat3 rotation_about(const Vec3& axis, double angle) { return Eigen::AngleAxisd(angle, axis.normalized()).matrix(); }

// Deformation gradients of every kind the kernel treats differently: near rest, moderate and wild
// (often inverted) random ones, compressed (twist modes clamped), flat (the scaling block clamped),
// needle-like (the SVD by Jacobi), inverted, rotations and the identity (equal singular values).
std::vector<Mat3> gradients() {
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(-1, 1);
  auto noisy = [&](double amplitude) {
    Mat3 F = Mat3::Identity();
    for (int q = 0; q < 9; ++q) F(q) += amplitude * u(rng);
    return F;
  };
  auto turned = [&](const Vec3& s) {
    const Mat3 A = rotation_about(Vec3(u(rng), u(rng), u(rng)), 3 * u(rng));
    const Mat3 B = rotation_about(Vec3(u(rng), u(rng), u(rng)), 3 * u(rng));
    return Mat3(A * s.asDiagonal() * B);
  };
  std::vector<Mat3> F;
  for (int k = 0; k < 12; ++k) F.push_back(noisy(0.05));
  for (int k = 0; k < 12; ++k) F.push_back(noisy(0.3));
  for (int k = 0; k < 12; ++k) F.push_back(noisy(1.0));
  for (const Vec3& s : {Vec3(0.7, 0.8, 0.75), Vec3(0.5, 0.6, 0.9), Vec3(1, 1, 0.1), Vec3(1, 1, 0.02),
                        Vec3(1.2, 0.9, 1e-6), Vec3(1, 5e-4, 1e-3), Vec3(2, 1e-4, -1e-4), Vec3(1.0, 1.1, -0.3),
                        Vec3(0.9, -0.8, -0.2), Vec3(1.5, 1.2, 1.1), Vec3(1, 1, 1), Vec3(1, 1, 1.2)})
    for (int k = 0; k < 3; ++k) F.push_back(turned(s));
  F.push_back(Mat3::Identity());
  F.push_back(Vec3(0.7, 0.8, 0.75).asDiagonal());
  return F;  // 74: groups of four and a tail of two
}

// One tet per gradient, apart from the others, each its own shape and material; x deforms tet t by
// F[t] exactly, v moves its nodes at random.
struct Scene {
  FemModel model;
  Vec3List x, v;
};

Scene disjoint_tets(const std::vector<Mat3>& F) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-0.2, 0.2), E(1e3, 1e6), nu(0.0, 0.49);
  TetMesh mesh;
  std::vector<Material> materials;
  Vec3List x;
  const Vec3 corner[4] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  for (size_t t = 0; t < F.size(); ++t) {
    const Vec3 offset(3.0 * double(t), 0, 0);
    Tet tet;
    for (int a = 0; a < 4; ++a) {
      const Vec3 X = 0.01 * (corner[a] + Vec3(u(rng), u(rng), u(rng)));
      tet[a] = int32_t(mesh.nodes.size());
      mesh.nodes.push_back(offset + X);
      x.push_back(offset + F[t] * X);
    }
    mesh.tets.push_back(tet);
    materials.push_back(Material{E(rng), nu(rng), 1000});
  }
  Scene s{build_fem_model(mesh, materials, MassKind::Consistent, "test"), x, Vec3List(x.size())};
  std::normal_distribution<double> normal;
  for (Vec3& vi : s.v) vi = Vec3(normal(rng), normal(rng), normal(rng));
  return s;
}

// Everything the step's assembly asks for.
struct Outputs {
  BlockValues K;
  Vec3List f;
  std::vector<Mat3> R;
  NeoHookeanLinearisation lin;
  NeoHookeanAssembly what;
  // Blocks and forces start non-zero: the assembly must add to them.
  Outputs(const FemModel& m, const Vec3List& v)
      : K(m.pattern.block_count(), Mat3::Identity()), f(v.size(), Vec3::Ones()), R(m.elements.size(), Mat3::Zero()) {
    lin.resize(m.elements.size());
    what.k_scale = 1e-4;
    what.K = &K;
    what.v_lin = &v;
    what.h = 0.01;
    what.R = &R;
    what.lin = &lin;
  }
};

#ifdef MICA_LANES4
// symmetric_eigensystems on four matrices.
MICA_AVX2 void lane_eigensystems(const Mat3 C[4], Vec3 lambda[4], Mat3 E[4]) {
  __m256d c[6], l[3], e[9];
  const int row[6] = {0, 1, 2, 1, 2, 2}, col[6] = {0, 1, 2, 0, 0, 1};
  for (int q = 0; q < 6; ++q)
    c[q] = _mm256_setr_pd(C[0](row[q], col[q]), C[1](row[q], col[q]), C[2](row[q], col[q]), C[3](row[q], col[q]));
  lanes4::symmetric_eigensystems(c, l, e);
  for (int k = 0; k < 4; ++k) {
    lambda[k] = Vec3(l[0][k], l[1][k], l[2][k]);
    for (int q = 0; q < 9; ++q) E[k](q) = e[q][k];
  }
}
#endif

}  // namespace

// Random symmetric matrices of every scale, the F^T F of the test's gradients, and matrices with
// double and triple eigenvalues. Where the eigenvalues are apart: the same eigenvalues and (up to
// sign) eigenvectors as Eigen's computeDirect; everywhere: an orthonormal eigensystem of C, as
// accurate as the closed form is (about the square root of the round-off at a double eigenvalue).
static void test_eigensystems_match_eigen(void**) {
#ifdef MICA_LANES4
  if (!lanes4::supported()) skip();
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Mat3> C;
  for (int k = 0; k < 400; ++k) {
    Mat3 A;
    for (int q = 0; q < 9; ++q) A(q) = u(rng);
    C.push_back(std::pow(10.0, 6 * u(rng)) * (A + A.transpose()));
  }
  for (const Mat3& F : gradients()) C.push_back(F.transpose() * F);
  const std::vector<Vec3> spectra = {Vec3(1, 1, 2), Vec3(2, 1, 1), Vec3(1, 1, 1), Vec3(0, 0, 0), Vec3(0, 0, 1),
                                     Vec3(-3, 1, 1), Vec3(1e-9, 1e-9, 1), Vec3(5, 5, 5 + 1e-12)};
  for (const Vec3& d : spectra) {
    C.push_back(d.asDiagonal());
    for (int k = 0; k < 7; ++k) {
      const Mat3 Q = rotation_about(Vec3(u(rng), u(rng), u(rng)), 3 * u(rng));
      C.push_back(Q * d.asDiagonal() * Q.transpose());
    }
  }
  while (C.size() % 4) C.push_back(Mat3::Identity());
  double worst_apart = 0, worst_residual = 0;
  for (size_t k = 0; k < C.size(); k += 4) {
    Vec3 lambda[4];
    Mat3 E[4];
    lane_eigensystems(&C[k], lambda, E);
    for (int l = 0; l < 4; ++l) {
      const Mat3& c = C[k + l];
      Eigen::SelfAdjointEigenSolver<Mat3> ref;
      ref.computeDirect(c);
      const double scale = std::max(c.cwiseAbs().maxCoeff(), 1e-300);
      assert_le((E[l].transpose() * E[l] - Mat3::Identity()).norm(), 1e-7);
      const double residual = (c * E[l] - E[l] * lambda[l].asDiagonal()).norm() / scale;
      assert_le(residual, 1e-7);
      worst_residual = std::max(worst_residual, residual);
      const Vec3& want = ref.eigenvalues();
      const double gap = std::min(want[1] - want[0], want[2] - want[1]) / scale;
      if (gap < 1e-3) continue;
      for (int i = 0; i < 3; ++i) {
        assert_le(std::fabs(lambda[l][i] - want[i]), 1e-13 * scale);
        const Vec3 e = E[l].col(i), e_ref = ref.eigenvectors().col(i);
        const double difference = std::min((e - e_ref).norm(), (e + e_ref).norm());
        assert_le(difference, 1e-12 / gap);
        worst_apart = std::max(worst_apart, std::max(std::fabs(lambda[l][i] - want[i]) / scale, difference * gap));
      }
    }
  }
  std::printf("%zu matrices: apart, worst difference from computeDirect %.1e; worst residual |C E - E L| %.1e\n",
              C.size(), worst_apart, worst_residual);
#else
  skip();
#endif
}

// assemble_neo_hookean (the kernel on each four, the reference on the tail) against the reference
// on every element. The tets are apart, so each output is one element's: compared element by
// element, to 1e-12 of its own scale where the squared singular values are apart (by 1e-3 of the
// largest). Closer, both SVDs are only as accurate as the closed-form eigenvalues of F^T F: the
// round-off over the gap, and about its square root at a double eigenvalue (two singular values
// equal: the reference itself changes by 1e-8 for a change of F in its last bit); so 1e-15 over the
// gap there, within [1e-12, 1e-7].
static void test_kernel_matches_reference(void**) {
  const std::vector<Mat3> F = gradients();
  const Scene s = disjoint_tets(F);
  const FemModel& m = s.model;
  Outputs fast(m, s.v), ref(m, s.v);
  assemble_neo_hookean(m, s.x, fast.what, fast.f);
  for (Vec3& fi : ref.f) fi.setZero();  // as assemble_neo_hookean starts
  for (int32_t e = 0; e < int32_t(m.elements.size()); ++e) add_neo_hookean_element(m, e, s.x, ref.what, ref.f);
  std::mt19937 rng(37);
  std::normal_distribution<double> normal;
  // Forces, blocks, rotations, energy and stress, H : dF; singular values apart, and close or equal.
  double worst[2][5] = {{0, 0, 0, 0, 0}, {0, 0, 0, 0, 0}};
  int32_t close = 0;
  for (size_t e = 0; e < m.elements.size(); ++e) {
    const TetElement& el = m.elements[e];
    const NeoHookean p = neo_hookean_parameters(m.lame[e]);
    Mat3 U, V;
    Vec3 sv;
    rotation_variant_svd(F[e], U, sv, V);
    const Vec3 s2 = sv.cwiseAbs2();
    const double gap =
        std::min({std::fabs(s2[0] - s2[1]), std::fabs(s2[1] - s2[2]), std::fabs(s2[0] - s2[2])}) / s2.maxCoeff();
    const bool apart = gap >= 1e-3;
    close += !apart;
    const double tolerance = apart ? 1e-12 : std::clamp(1e-15 / gap, 1e-12, 1e-7);
    auto check = [&](double difference, double scale, int what) {
      assert_le(difference, tolerance * scale);
      worst[!apart][what] = std::max(worst[!apart][what], difference / scale);
    };
    const double stiffness = p.mu + p.lambda;  // Pa, the scale of P and of H
    double g = 0;
    for (const Vec3& ga : el.grad) g = std::max(g, ga.norm());
    const double growth = 1 + F[e].squaredNorm();  // P grows as |F|^2 (cofactors), H as |F|
    double f_scale = stiffness * el.volume * g * growth, k_scale = 1e-4 * stiffness * el.volume * g * g * growth;
    for (int a = 0; a < 4; ++a) f_scale = std::max(f_scale, ref.f[el.nodes[a]].norm());
    for (int32_t slot : m.slots[e]) k_scale = std::max(k_scale, ref.K[slot].norm());
    for (int a = 0; a < 4; ++a) check((fast.f[el.nodes[a]] - ref.f[el.nodes[a]]).norm(), f_scale, 0);
    for (int32_t slot : m.slots[e]) check((fast.K[slot] - ref.K[slot]).norm(), k_scale, 1);
    // U V^T is as well conditioned as the polar factor: to 1 / (s_1 + s_2) (s_2 signed).
    check((fast.R[e] - ref.R[e]).norm(), std::max(1.0, std::fabs(sv[0]) / std::fabs(sv[1] + sv[2])), 2);
    check(std::fabs(fast.lin.energy[e] - ref.lin.energy[e]), stiffness * el.volume * growth * growth, 3);
    check((fast.lin.stress[e] - ref.lin.stress[e]).norm(), stiffness * growth, 3);
    // The frames may differ (U and V are not unique), the projected Hessian they make may not.
    for (int k = 0; k < 3; ++k) {
      Mat3 dF;
      for (int q = 0; q < 9; ++q) dF(q) = normal(rng);
      const Mat3 want = ref.lin.frame[e].apply(dF);
      check((fast.lin.frame[e].apply(dF) - want).norm(), std::max(want.norm(), stiffness * dF.norm() * growth), 4);
      check(std::fabs(fast.lin.frame[e].quadratic(dF) - ref.lin.frame[e].quadratic(dF)),
            stiffness * dF.squaredNorm() * growth, 4);
    }
  }
  for (int d = 0; d < 2; ++d)
    std::printf("%s: worst relative differences from the reference: forces %.1e, blocks %.1e, rotations %.1e, "
                "energy and stress %.1e, H : dF %.1e\n",
                d ? "singular values close or equal" : "singular values apart", worst[d][0], worst[d][1],
                worst[d][2], worst[d][3], worst[d][4]);
  std::printf("(%zu elements, %d with singular values close or equal)\n", m.elements.size(), close);
}

// add_neo_hookean_elements4 against add_neo_hookean_element on each of the four, on a box with its
// nodes moved at random (some tets inverted), table-driven over the groups: neighbours (which share
// nodes, so blocks and forces), one element twice and four times, and strangers; with everything
// and with forces only.
static void test_four_elements_share_nodes_and_blocks(void**) {
  const TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(1, 0.8, 0.6), {4, 3, 3}, 6);
  const FemModel m = build_fem_model(mesh, Material{1e5, 0.45, 1000}, MassKind::Consistent, "test");
  const int32_t n = int32_t(m.elements.size());
  std::mt19937 rng(41);
  std::normal_distribution<double> normal;
  Vec3List x(m.rest.size()), v(m.rest.size());
  const Mat3 Q = rotation_about(Vec3(-0.5, 1, 2), 2.3);
  for (size_t i = 0; i < x.size(); ++i) {
    x[i] = Q * m.rest[i] + 0.06 * Vec3(normal(rng), normal(rng), normal(rng));
    v[i] = Vec3(normal(rng), normal(rng), normal(rng));
  }
  int32_t inverted = 0;
  for (const TetElement& el : m.elements) inverted += deformation_gradient(el, x).determinant() < 0;
  std::printf("%d of %d tets inverted\n", inverted, n);
  assert_true(inverted > 0);
  struct Case {
    const char* name;
    int32_t step[4];  // the group's elements: e0 + step[l] (mod n), for e0 along the model
  } cases[] = {
      {"neighbours", {0, 1, 2, 3}},
      {"one element twice", {0, 1, 0, 5}},
      {"one element four times", {0, 0, 0, 0}},
      {"strangers", {0, n / 4, n / 2, 3 * n / 4}},
  };
  for (const Case& c : cases) {
    double worst = 0;
    for (int32_t e0 = 0; e0 < n; e0 += 7) {
      int32_t group[4];
      for (int l = 0; l < 4; ++l) group[l] = (e0 + c.step[l]) % n;
      for (bool everything : {true, false}) {
        Outputs fast(m, v), ref(m, v);
        if (!everything) fast.what = ref.what = NeoHookeanAssembly{};
        add_neo_hookean_elements4(m, group, x, fast.what, fast.f);
        for (int32_t e : group) add_neo_hookean_element(m, e, x, ref.what, ref.f);
        double k_scale = 0, f_scale = 0;
        for (const Mat3& k : ref.K) k_scale = std::max(k_scale, (k - Mat3::Identity()).norm());
        for (const Vec3& fi : ref.f) f_scale = std::max(f_scale, (fi - Vec3::Ones()).norm());
        assert_true(f_scale > 0);
        for (size_t q = 0; q < ref.K.size(); ++q) {  // without K: k_scale is 0, K must be untouched
          assert_le((fast.K[q] - ref.K[q]).norm(), 1e-12 * k_scale);
          if (everything) worst = std::max(worst, (fast.K[q] - ref.K[q]).norm() / k_scale);
        }
        for (size_t i = 0; i < ref.f.size(); ++i) {
          assert_le((fast.f[i] - ref.f[i]).norm(), 1e-12 * f_scale);
          worst = std::max(worst, (fast.f[i] - ref.f[i]).norm() / f_scale);
        }
        if (!everything) continue;
        for (int32_t e : group) {
          assert_le((fast.R[e] - ref.R[e]).norm(), 1e-10);
          assert_le((fast.lin.stress[e] - ref.lin.stress[e]).norm(), 1e-12 * (1 + ref.lin.stress[e].norm()));
          assert_le(std::fabs(fast.lin.energy[e] - ref.lin.energy[e]), 1e-12 * (1e-9 + std::fabs(ref.lin.energy[e])));
        }
      }
    }
    std::printf("  %-22s worst relative difference from the reference %.1e\n", c.name, worst);
  }
}

// neo_hookean_model_energies (four at a time, then the tail) against the sum of
// add_neo_hookean_model_energies over the elements, on the gradients' tets linearised at x and
// evaluated at x moved at random: each sum to 1e-12 of the sum of its terms' magnitudes.
static void test_model_energies_match_reference(void**) {
  const Scene s = disjoint_tets(gradients());
  const FemModel& m = s.model;
  Outputs at_x(m, s.v);
  assemble_neo_hookean(m, s.x, at_x.what, at_x.f);
  std::mt19937 rng(47);
  std::normal_distribution<double> normal;
  Vec3List x_end = s.x;
  for (Vec3& xi : x_end) xi += 1e-3 * Vec3(normal(rng), normal(rng), normal(rng));
  for (const Vec3List* v : {&s.v, static_cast<const Vec3List*>(nullptr)}) {
    const NeoHookeanModelEnergies fast = neo_hookean_model_energies(m, at_x.lin, s.x, x_end, v);
    NeoHookeanModelEnergies ref, magnitude;
    for (int32_t e = 0; e < int32_t(m.elements.size()); ++e) {
      NeoHookeanModelEnergies one;
      add_neo_hookean_model_energies(m, e, at_x.lin, s.x, x_end, v, one);
      ref.u_end += one.u_end, ref.u_lin_end += one.u_lin_end, ref.vKv += one.vKv;
      magnitude.u_end += std::fabs(one.u_end), magnitude.u_lin_end += std::fabs(one.u_lin_end);
      magnitude.vKv += std::fabs(one.vKv);
    }
    assert_true(magnitude.u_end > 0 && magnitude.u_lin_end > 0 && (v == nullptr) == (magnitude.vKv == 0));
    assert_le(std::fabs(fast.u_end - ref.u_end), 1e-12 * magnitude.u_end);
    assert_le(std::fabs(fast.u_lin_end - ref.u_lin_end), 1e-12 * magnitude.u_lin_end);
    assert_le(std::fabs(fast.vKv - ref.vKv), 1e-12 * magnitude.vKv);
    std::printf("%s v: relative differences from the reference %.1e, %.1e, %.1e\n", v ? "with" : "without",
                std::fabs(fast.u_end - ref.u_end) / magnitude.u_end,
                std::fabs(fast.u_lin_end - ref.u_lin_end) / magnitude.u_lin_end,
                v ? std::fabs(fast.vKv - ref.vKv) / magnitude.vKv : 0.0);
  }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_eigensystems_match_eigen),
      cmocka_unit_test(test_kernel_matches_reference),
      cmocka_unit_test(test_four_elements_share_nodes_and_blocks),
      cmocka_unit_test(test_model_energies_match_reference),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
