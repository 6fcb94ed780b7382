// SPDX-License-Identifier: Apache-2.0
// Element-level physics: patch test, rigid-motion invariance, stiffness against a finite
// difference of the forces, and mass totals.
#include <Eigen/SVD>
#include <cstdio>
#include <cstring>
#include <functional>
#include <random>

#include "fem/fem_model.hpp"
#include "fem/rotation.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

FemModel cube_model(MassKind mass = MassKind::Consistent, int32_t tets_per_cell = 6) {
  const TetMesh mesh = make_box_grid(Vec3(0, 0, 0), Vec3(1, 0.8, 0.6), {4, 3, 3}, tets_per_cell);
  return build_fem_model(mesh, Material{1e5, 0.3, 1000}, mass, "test");
}

Vec3List forces(const FemModel& m, const Vec3List& x, bool corotational) {
  std::vector<Mat3> R(m.elements.size(), Mat3::Identity());
  if (corotational) compute_rotations(m, x, R);
  Vec3List f(x.size(), Vec3::Zero());
  assemble_elastic(m, x, corotational ? &R : nullptr, 0, nullptr, f);
  return f;
}

Mat3 rotation_about(const Vec3& axis, double angle) { return Eigen::AngleAxisd(angle, axis.normalized()).matrix(); }

// Nodes strictly inside the box: their force has contributions from every side.
std::vector<int32_t> interior_nodes(const FemModel& m) {
  std::vector<int32_t> inside;
  for (int32_t i = 0; i < m.node_count(); ++i) {
    const Vec3& p = m.rest[i];
    if (p.x() > 1e-9 && p.x() < 1 - 1e-9 && p.y() > 1e-9 && p.y() < 0.8 - 1e-9 && p.z() > 1e-9 && p.z() < 0.6 - 1e-9)
      inside.push_back(i);
  }
  return inside;
}

void patch_test(bool corotational, int32_t tets_per_cell) {
  const FemModel m = cube_model(MassKind::Consistent, tets_per_cell);
  Mat3 G;  // an affine map with stretch, shear and (for co-rotation) a rotation
  G << 1.02, 0.01, -0.015, 0.005, 0.99, 0.02, -0.01, 0.012, 1.01;
  if (corotational) G = rotation_about(Vec3(1, 2, 3), 0.7) * G;
  Vec3List x(m.rest.size());
  for (size_t i = 0; i < x.size(); ++i) x[i] = G * m.rest[i] + Vec3(0.3, -0.2, 0.1);
  const Vec3List f = forces(m, x, corotational);
  double scale = 0;  // the typical boundary force, for a relative tolerance
  for (const Vec3& fi : f) scale = std::max(scale, fi.norm());
  assert_true(scale > 0);
  const auto inside = interior_nodes(m);
  assert_true(inside.size() >= 4);
  for (int32_t i : inside) assert_le(f[i].norm(), 1e-10 * scale);
}

}  // namespace

static void test_patch_linear(void**) { patch_test(false, 6); patch_test(false, 5); }
static void test_patch_corotational(void**) { patch_test(true, 6); patch_test(true, 5); }

static void test_rigid_rotation_gives_no_force(void**) {
  const FemModel m = cube_model();
  const Mat3 Q = rotation_about(Vec3(0.3, -1, 0.5), M_PI / 2);  // 90 degrees
  Vec3List x(m.rest.size());
  for (size_t i = 0; i < x.size(); ++i) x[i] = Q * m.rest[i] + Vec3(1, 2, 3);
  const double E = m.materials[0].youngs_modulus;
  double corot = 0, linear = 0;
  for (const Vec3& f : forces(m, x, true)) corot = std::max(corot, f.norm());
  for (const Vec3& f : forces(m, x, false)) linear = std::max(linear, f.norm());
  // Force scale of a unit strain on a 0.25 m cell: E * area ~ E * 0.06 m^2.
  assert_le(corot, 1e-10 * E * 0.06);
  assert_true(linear > 1e-2 * E * 0.06);  // the linear model sees the rotation as strain
}

static void test_rotation_is_proper_for_inverted_elements(void**) {
  Mat3 F;
  F << 0.5, 0.2, 0.0, -0.1, 0.8, 0.3, 0.05, 0.1, -0.7;  // det < 0: inverted
  assert_true(F.determinant() < 0);
  const Mat3 R = proper_rotation(F);
  assert_near(R.determinant(), 1.0, 1e-12);
  assert_near((R.transpose() * R - Mat3::Identity()).norm(), 0.0, 1e-12);
  const Mat3 collapsed = Vec3(1, 0, 0) * Vec3(0, 1, 0).transpose();  // rank 1
  assert_near(proper_rotation(collapsed).determinant(), 1.0, 1e-12);
  const Mat3 Q = rotation_about(Vec3(1, 1, 0), 2.0);
  assert_near((proper_rotation(Q * Vec3(1.1, 0.9, 1.0).asDiagonal()) - Q).norm(), 0.0, 1e-12);
}

// The polar factor against the SVD's U V^T (the oracle), table-driven over what the solver feeds
// it: elements' deformation gradients (small and large stretch, turned) and nodes' summed element
// rotations (a rotation scaled by the node's valence, slightly spread).
static void test_rotation_matches_the_svd_polar_factor(void**) {
  struct Case {
    const char* name;
    double scale, stretch;  // F = scale * Q * (I + symmetric noise of norm `stretch`)
  } cases[] = {
      {"small strain", 1.0, 1e-3}, {"strain 5 %", 1.0, 0.05},  {"strain 30 %", 1.0, 0.3},
      {"node sum", 20.0, 1e-3},     {"node sum, spread", 14.0, 0.05}, {"tiny scale", 1e-3, 0.05},
  };
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  for (const Case& c : cases) {
    double worst = 0;
    for (int trial = 0; trial < 200; ++trial) {
      const Mat3 Q = rotation_about(Vec3(normal(rng), normal(rng), normal(rng)), 3 * normal(rng));
      Mat3 noise;
      for (int k = 0; k < 9; ++k) noise(k / 3, k % 3) = normal(rng);
      const Mat3 sym = noise + noise.transpose();
      const Mat3 F = c.scale * Q * (Mat3::Identity() + (c.stretch / sym.norm()) * sym);  // stretches within 1 +- stretch
      Eigen::JacobiSVD<Mat3> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
      const Mat3 polar = svd.matrixU() * svd.matrixV().transpose();
      worst = std::max(worst, (proper_rotation(F) - polar).lpNorm<Eigen::Infinity>());
    }
    std::printf("  %-18s worst entry difference from the SVD's polar factor %.1e\n", c.name, worst);
    assert_true(worst < 1e-13);
  }
}

// proper_rotations takes two at a time, each lane exactly as proper_rotation alone: paired with a
// partner that converges sooner or later, inverted (the SVD lane) or collapsed, and with itself.
static void test_paired_rotations_match_single(void**) {
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  std::vector<Mat3> F;
  for (double stretch : {0.0, 1e-3, 0.05, 0.3}) {
    for (int trial = 0; trial < 10; ++trial) {
      const Mat3 Q = rotation_about(Vec3(normal(rng), normal(rng), normal(rng)), 3 * normal(rng));
      Mat3 noise;
      for (int k = 0; k < 9; ++k) noise(k / 3, k % 3) = normal(rng);
      F.push_back(Q * (Mat3::Identity() + stretch * noise));
    }
  }
  F.push_back(Vec3(1, 1, -0.5).asDiagonal());                                     // inverted
  F.push_back(Mat3::Zero());                                                       // collapsed
  F.push_back(20 * rotation_about(Vec3(1, 2, 3), 0.4));                            // a node's sum
  F.push_back(rotation_about(Vec3(0, 1, 0), 1.0) * Vec3(1.3, 1.2, 1.1).asDiagonal());  // det 1.7: cbrt
  for (size_t i = 0; i < F.size(); ++i)
    for (size_t j = 0; j < F.size(); ++j) {
      Mat3 Ri, Rj;
      proper_rotations(F[i], F[j], Ri, Rj);
      assert_true(Ri == proper_rotation(F[i]));
      assert_true(Rj == proper_rotation(F[j]));
    }
  Mat3 R;
  proper_rotations(F[3], F[3], R, R);
  assert_true(R == proper_rotation(F[3]));
}

// proper_rotations4 (AVX2 where the CPU has it) against proper_rotation lane by lane, bit for bit
// (memcmp: -0 is not +0), table-driven: each kind alone in all four lanes, then mixed so that lanes
// converge at different steps or take the SVD beside Newton lanes, in place (R = F), and the tail
// helper proper_rotations(F, R, count) for counts 1 to 4.
static void test_four_rotations_match_single(void**) {
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  auto rotation = [&] { return rotation_about(Vec3(normal(rng), normal(rng), normal(rng)), 3 * normal(rng)); };
  auto noise = [&] {
    Mat3 N;
    for (int k = 0; k < 9; ++k) N(k) = normal(rng);
    return N;
  };
  struct Case {
    const char* name;
    std::function<Mat3()> make;
  } cases[] = {
      {"random", [&] { return noise(); }},  // det < 0 about half the time
      {"rotation", [&] { return rotation(); }},
      {"near-rotation", [&] { return Mat3(rotation() * (Mat3::Identity() + 1e-3 * noise())); }},
      {"strain 5 %", [&] { return Mat3(rotation() * (Mat3::Identity() + 0.05 * noise())); }},
      {"strain 30 %", [&] { return Mat3(rotation() * (Mat3::Identity() + 0.3 * noise())); }},
      {"node sum", [&] { return Mat3(20 * rotation() * (Mat3::Identity() + 1e-3 * noise())); }},
      {"tiny scale", [&] { return Mat3(1e-3 * rotation()); }},  // cbrt scaling
      {"det 1.1", [&] { return Mat3(rotation() * Vec3(1.1, 1.0, 1.0).asDiagonal()); }},  // the cubic
      {"inverted", [&] { return Mat3(rotation() * Vec3(1, 1 + 0.1 * normal(rng), -0.5).asDiagonal()); }},
      {"rank 2", [&] { return Mat3(rotation() * Vec3(1, 0.8, 0).asDiagonal() * rotation()); }},
      {"rank 1", [&] { return Mat3(Vec3(normal(rng), normal(rng), normal(rng)) * Vec3(normal(rng), normal(rng), normal(rng)).transpose()); }},
      {"nearly collapsed", [&] { return Mat3(rotation() * Vec3(1, 1, 1e-4).asDiagonal()); }},
      {"flat but Newton", [&] { return Mat3(rotation() * Vec3(1, 1, 0.02).asDiagonal()); }},  // det just above the SVD's bound
      {"zero", [&] { return Mat3(Mat3::Zero()); }},
  };
  const auto same_bits = [](const Mat3& a, const Mat3& b) { return std::memcmp(a.data(), b.data(), sizeof(Mat3)) == 0; };
  const auto check = [&](const Mat3 F[4], const char* name) {
    Mat3 R[4];
    proper_rotations4(F, R);
    Mat3 in_place[4] = {F[0], F[1], F[2], F[3]};
    proper_rotations4(in_place, in_place);
    for (int l = 0; l < 4; ++l) {
      const Mat3 single = proper_rotation(F[l]);
      if (!same_bits(R[l], single) || !same_bits(in_place[l], single)) std::printf("  %s: lane %d differs\n", name, l);
      assert_true(same_bits(R[l], single));
      assert_true(same_bits(in_place[l], single));
    }
    for (int count = 0; count <= 4; ++count) {
      Mat3 Rc[4];
      proper_rotations(F, Rc, count);
      for (int l = 0; l < count; ++l) assert_true(same_bits(Rc[l], proper_rotation(F[l])));
    }
  };
  std::vector<Mat3> pool;
  for (const Case& c : cases) {
    for (int trial = 0; trial < 12; ++trial) pool.push_back(c.make());
    for (size_t i = pool.size() - 12; i < pool.size(); i += 4) check(&pool[i], c.name);  // one kind in all lanes
  }
  for (size_t i = 0; i < pool.size(); ++i) {  // mixed kinds, each matrix in each lane
    const Mat3 F[4] = {pool[i], pool[(i + 13) % pool.size()], pool[(i + 50) % pool.size()], pool[(i + 97) % pool.size()]};
    check(F, "mixed");
  }
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  std::printf("  %zu matrices, AVX2 %s\n", pool.size(), __builtin_cpu_supports("avx2") ? "used" : "absent (pairs)");
#endif
}

// elastic_energies, two frames side by side, against elastic_energy in each.
static void test_paired_energies_match_single(void**) {
  const FemModel m = cube_model();
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 20; ++trial) {
    const TetElement& el = m.elements[size_t(trial) * 11 % m.elements.size()];
    const Mat3 Qa = rotation_about(Vec3(normal(rng), normal(rng), normal(rng)), 3 * normal(rng));
    const Mat3 Qb = rotation_about(Vec3(normal(rng), normal(rng), normal(rng)), 0.1 * normal(rng)) * Qa;
    Mat3 noise;
    for (int k = 0; k < 9; ++k) noise(k / 3, k % 3) = normal(rng);
    const Mat3 F = Qa * (Mat3::Identity() + 0.02 * noise);
    const std::array<double, 2> u = elastic_energies(el, m.lame[0], Qa, Qb, F);
    const double ua = elastic_energy(el, m.lame[0], Qa, F), ub = elastic_energy(el, m.lame[0], Qb, F);
    assert_near(u[0], ua, 1e-12 * ua);
    assert_near(u[1], ub, 1e-12 * ub);
  }
}

// -d f / d x against the assembled K, by central differences along random directions.
static void check_stiffness(const FemModel& m, const Vec3List& x, bool corotational, double rel_tol) {
  std::vector<Mat3> R(m.elements.size(), Mat3::Identity());
  if (corotational) compute_rotations(m, x, R);
  BlockValues K(m.pattern.block_count(), Mat3::Zero());
  Vec3List f(x.size());
  assemble_elastic(m, x, corotational ? &R : nullptr, 1.0, &K, f);
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 3; ++trial) {
    Vec3List dx(x.size()), Kdx(x.size());
    for (Vec3& d : dx) d = Vec3(normal(rng), normal(rng), normal(rng));
    block_multiply(m.pattern, K, dx, Kdx);
    const double eps = 1e-6;
    Vec3List xp = x, xm = x;
    for (size_t i = 0; i < x.size(); ++i) {
      xp[i] += eps * dx[i];
      xm[i] -= eps * dx[i];
    }
    const Vec3List fp = forces(m, xp, corotational), fm = forces(m, xm, corotational);
    double err = 0, ref = 0;
    for (size_t i = 0; i < x.size(); ++i) {
      err += (-(fp[i] - fm[i]) / (2 * eps) - Kdx[i]).squaredNorm();
      ref += Kdx[i].squaredNorm();
    }
    assert_le(std::sqrt(err / ref), rel_tol);
  }
}

static void test_stiffness_matches_finite_difference(void**) {
  const FemModel m = cube_model();
  Vec3List x(m.rest.size());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.01, 0.01);
  for (size_t i = 0; i < x.size(); ++i) x[i] = m.rest[i] + Vec3(jitter(rng), jitter(rng), jitter(rng));
  check_stiffness(m, x, false, 1e-7);  // linear: K is the exact Jacobian
  // Co-rotational K = R Ke R^T drops dR/dx, which vanishes at zero strain: exact on a
  // rigidly rotated body, first order in the strain otherwise.
  const Mat3 Q = rotation_about(Vec3(1, -2, 0.5), 1.1);
  Vec3List rotated(m.rest.size());
  for (size_t i = 0; i < x.size(); ++i) rotated[i] = Q * m.rest[i];
  check_stiffness(m, rotated, true, 1e-7);
}

// The assembly's kernel (add_element) against its reference, rotated_stiffness, on one element
// turned and strained at random: the same blocks, in the right slots (each its own here, so a
// block written to its transpose's slot shows), and the forces of add_elastic_forces at that F.
static void test_fused_element_matches_reference(void**) {
  const FemModel m = cube_model();
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 20; ++trial) {
    const TetElement& el = m.elements[size_t(trial) * 7 % m.elements.size()];
    const Mat3 Q = rotation_about(Vec3(normal(rng), normal(rng), normal(rng)), 3 * normal(rng));
    Vec3List x(m.rest.size(), Vec3::Zero());
    for (int32_t i : el.nodes) x[i] = Q * m.rest[i] + 0.01 * Vec3(normal(rng), normal(rng), normal(rng));
    const Mat3 R = proper_rotation(deformation_gradient(el, x));
    const double scale = 1e-4;
    std::array<int32_t, 16> slots;
    BlockValues K(16), K_ref(16);
    for (int q = 0; q < 16; ++q) {
      slots[q] = (q * 5 + 3) % 16;  // a permutation: every block its own slot
      K[q] = K_ref[q] = Mat3::Random();
    }
    Vec3List f(x.size(), Vec3::Ones()), f_ref = f;
    add_element(el, m.lame[0], R, x, scale, slots, K.data(), f);
    Mat3 Ke[16];
    rotated_stiffness(el, m.lame[0], R, scale, Ke);
    for (int q = 0; q < 16; ++q) K_ref[slots[q]] += Ke[q];
    add_elastic_forces(el, m.lame[0], R, deformation_gradient(el, x), f_ref);
    double k_scale = 0, f_scale = 0;
    for (int q = 0; q < 16; ++q) k_scale = std::max(k_scale, Ke[q].norm());
    for (int32_t i : el.nodes) f_scale = std::max(f_scale, (f_ref[i] - Vec3::Ones()).norm());
    for (int q = 0; q < 16; ++q) assert_le((K[q] - K_ref[q]).norm(), 1e-12 * k_scale);
    for (int32_t i : el.nodes) assert_le((f[i] - f_ref[i]).norm(), 1e-12 * f_scale);
  }
}

// add_elements, two elements side by side, against add_element on each: pairs that share nodes
// (so blocks and forces), with their own rotations, into the model's real slots; and forces only.
static void test_paired_elements_match_single(void**) {
  const FemModel m = cube_model();
  std::mt19937 rng(9);
  std::normal_distribution<double> normal;
  Vec3List x(m.rest.size());
  const Mat3 Q = rotation_about(Vec3(1, -2, 0.5), 1.1);
  for (size_t i = 0; i < x.size(); ++i) x[i] = Q * m.rest[i] + 0.01 * Vec3(normal(rng), normal(rng), normal(rng));
  std::vector<Mat3> R(m.elements.size());
  compute_rotations(m, x, R);
  for (size_t e0 = 0; e0 + 1 < m.elements.size(); e0 += 7) {
    for (size_t e1 : {e0 + 1, (e0 * 13 + 5) % m.elements.size()}) {
      if (e1 == e0) continue;
      for (bool with_K : {true, false}) {
        BlockValues K(m.pattern.block_count(), Mat3::Identity()), K_ref = K;
        Vec3List f(x.size(), Vec3::Ones()), f_ref = f;
        const TetElement* el[2] = {&m.elements[e0], &m.elements[e1]};
        const Lame* lame[2] = {&m.lame[e0], &m.lame[e1]};
        const Mat3* rot[2] = {&R[e0], &R[e1]};
        const std::array<int32_t, 16>* slots[2] = {&m.slots[e0], &m.slots[e1]};
        add_elements(el, lame, rot, x, 1e-4, slots, with_K ? K.data() : nullptr, f);
        for (size_t e : {e0, e1})
          add_element(m.elements[e], m.lame[e], R[e], x, 1e-4, m.slots[e], with_K ? K_ref.data() : nullptr, f_ref);
        double k_scale = 0, f_scale = 0;
        for (const Mat3& k : K_ref) k_scale = std::max(k_scale, (k - Mat3::Identity()).norm());
        for (const Vec3& v : f_ref) f_scale = std::max(f_scale, (v - Vec3::Ones()).norm());
        for (size_t q = 0; q < K.size(); ++q) assert_le((K[q] - K_ref[q]).norm(), 1e-12 * k_scale);
        for (size_t i = 0; i < f.size(); ++i) assert_le((f[i] - f_ref[i]).norm(), 1e-12 * f_scale);
      }
    }
  }
}

// add_elements4 (its AVX2 kernel where the CPU has AVX2 and FMA), four elements side by side,
// against add_element on each, table-driven over the groups: neighbours (which share nodes, so
// blocks and forces), one element twice and four times (every node and block shared), and
// strangers; with K and forces only, into the model's real slots, each element with its own
// rotation.
static void test_four_elements_match_single(void**) {
  const FemModel m = cube_model();
  const size_t n = m.elements.size();
  std::mt19937 rng(13);
  std::normal_distribution<double> normal;
  Vec3List x(m.rest.size());
  const Mat3 Q = rotation_about(Vec3(-0.5, 1, 2), 2.3);
  for (size_t i = 0; i < x.size(); ++i) x[i] = Q * m.rest[i] + 0.01 * Vec3(normal(rng), normal(rng), normal(rng));
  std::vector<Mat3> R(n);
  compute_rotations(m, x, R);
  struct Case {
    const char* name;
    size_t step[4];  // the group's elements: e0 + step[l] (mod n), for e0 along the model
  } cases[] = {
      {"neighbours", {0, 1, 2, 3}},
      {"one element twice", {0, 1, 0, 5}},
      {"one element four times", {0, 0, 0, 0}},
      {"strangers", {0, n / 4, n / 2, 3 * n / 4}},
  };
  for (const Case& c : cases) {
    double worst = 0;
    for (size_t e0 = 0; e0 < n; e0 += 5) {
      size_t g[4];
      for (int l = 0; l < 4; ++l) g[l] = (e0 + c.step[l]) % n;
      for (bool with_K : {true, false}) {
        BlockValues K(m.pattern.block_count(), Mat3::Identity()), K_ref = K;
        Vec3List f(x.size(), Vec3::Ones()), f_ref = f;
        const TetElement* el[4];
        const Lame* lame[4];
        const Mat3* rot[4];
        const std::array<int32_t, 16>* slots[4];
        for (int l = 0; l < 4; ++l) {
          el[l] = &m.elements[g[l]];
          lame[l] = &m.lame[g[l]];
          rot[l] = &R[g[l]];
          slots[l] = &m.slots[g[l]];
        }
        add_elements4(el, lame, rot, x, 1e-4, slots, with_K ? K.data() : nullptr, f);
        for (size_t e : g)
          add_element(m.elements[e], m.lame[e], R[e], x, 1e-4, m.slots[e], with_K ? K_ref.data() : nullptr, f_ref);
        double k_scale = 0, f_scale = 0;
        for (const Mat3& k : K_ref) k_scale = std::max(k_scale, (k - Mat3::Identity()).norm());
        for (const Vec3& v : f_ref) f_scale = std::max(f_scale, (v - Vec3::Ones()).norm());
        assert_true(f_scale > 0);
        for (size_t q = 0; q < K.size(); ++q) {  // without K: k_scale is 0, K must be untouched
          assert_le((K[q] - K_ref[q]).norm(), 1e-12 * k_scale);
          if (with_K) worst = std::max(worst, (K[q] - K_ref[q]).norm() / k_scale);
        }
        for (size_t i = 0; i < f.size(); ++i) {
          assert_le((f[i] - f_ref[i]).norm(), 1e-12 * f_scale);
          worst = std::max(worst, (f[i] - f_ref[i]).norm() / f_scale);
        }
      }
    }
    std::printf("  %-22s worst relative difference from add_element %.1e\n", c.name, worst);
  }
}

static void test_total_mass(void**) {
  for (MassKind kind : {MassKind::Consistent, MassKind::Lumped})
    for (int32_t tpc : {5, 6}) {
      const FemModel m = cube_model(kind, tpc);
      assert_near(m.total_mass(), 1000 * (1 * 0.8 * 0.6), 1e-9);
      // M is symmetric and its blocks sum to the total (each tet's mass matrix sums to rho V).
      double sum = 0;
      for (double v : m.mass) sum += v;
      assert_near(sum, m.total_mass(), 1e-9);
    }
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_patch_linear),
      cmocka_unit_test(test_patch_corotational),
      cmocka_unit_test(test_rigid_rotation_gives_no_force),
      cmocka_unit_test(test_rotation_is_proper_for_inverted_elements),
      cmocka_unit_test(test_rotation_matches_the_svd_polar_factor),
      cmocka_unit_test(test_paired_rotations_match_single),
      cmocka_unit_test(test_four_rotations_match_single),
      cmocka_unit_test(test_paired_energies_match_single),
      cmocka_unit_test(test_stiffness_matches_finite_difference),
      cmocka_unit_test(test_fused_element_matches_reference),
      cmocka_unit_test(test_paired_elements_match_single),
      cmocka_unit_test(test_four_elements_match_single),
      cmocka_unit_test(test_total_mass),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
