// SPDX-License-Identifier: Apache-2.0
// The hand-written supernodal solve (solver/supernodal_solve.hpp) against cholmod_solve2 on the
// same factor: the double solve to round-off, the single- and half-precision ones to their
// precision, the half columns and the solve in halves (also with node turns) against A^-1's columns, and a factor
// of another kind refused.
#include "solver/direct_solver.hpp"  // before cmocka (test_util.hpp)
#include "solver/half_products.hpp"
#include "solver/solver_problem.hpp"
#include "solver/supernodal_solve.hpp"

using namespace mica;
using namespace mica_test;

namespace {

// A factored system of the shared problem (a sheared 8^3-cell cube, its base fixed) and a
// right-hand side.
struct Factored {
  SolverProblem p;
  DirectSolver direct;
  Eigen::VectorXd b;
  explicit Factored(SupernodalSolve::Copy copy, const Material& material = Material{2e4, 0.3, 1000},
                    bool keep_double = true)
      : p(0, 8, false, material) {
    direct.set_copy(copy, keep_double);
    direct.analyze(p.fem.pattern);
    direct.factorize(ProjectedSystem{p.fem.pattern, p.A, p.projection});
    b = Eigen::VectorXd::LinSpaced(3 * p.fem.node_count(), -1, 2).array().sin();
  }
};

double relative(const Eigen::VectorXd& a, const Eigen::VectorXd& b) { return (a - b).norm() / b.norm(); }

using Copy = SupernodalSolve::Copy;
constexpr Copy kCopies[] = {Copy::None, Copy::Single, Copy::Half};

// What the copy a solve kept may differ from the double solve by, and the least it differs when
// the solve did run with that copy (Half falls back to Single on a CPU without F16C).
double allowed(const SupernodalSolve& s) { return s.half() ? 1e-3 : s.single() ? 1e-4 : 1e-13; }
double at_least(const SupernodalSolve& s) { return s.half() ? 1e-6 : s.single() ? 1e-12 : 0; }

// The relative difference of the copy's solve of f.b from cholmod_solve2's.
double copy_difference(Factored& f) {
  Eigen::MatrixXd reference;
  f.direct.solve_raw_cholmod(f.b, reference);
  Eigen::VectorXd x;
  f.direct.solve_one(f.b, x, true);
  return relative(x, reference.col(0));
}

}  // namespace

static void test_double_matches_cholmod(void**) {
  Factored f(Copy::None);
  Eigen::MatrixXd reference, by_hand;
  f.direct.solve_raw_cholmod(f.b, reference);
  f.direct.solve_raw(f.b, by_hand);  // one right-hand side: by hand
  const double d = relative(by_hand.col(0), reference.col(0));
  print_message("by hand against cholmod_solve2: %.3g\n", d);
  assert_true(d <= 1e-13);
  // Without a single-precision copy, a single-precision solve is the double one.
  Eigen::VectorXd x;
  f.direct.solve_one(f.b, x, true);
  assert_true(x == by_hand.col(0));
}

static void test_single_within_its_precision(void**) {
  Factored f(Copy::Single);
  Eigen::MatrixXd reference;
  f.direct.solve_raw_cholmod(f.b, reference);
  Eigen::VectorXd x, exact;
  f.direct.solve_one(f.b, x, true);
  f.direct.solve_one(f.b, exact, false);
  assert_true(relative(exact, reference.col(0)) <= 1e-13);
  const double d = relative(x, reference.col(0));
  print_message("single precision against cholmod_solve2: %.3g\n", d);
  assert_true(d > 1e-12);  // it did solve in single precision
  assert_true(d <= 1e-4);  // float's 6e-8 times the growth in the triangular solves
  // Wide supernodes ran too, as chains of panels.
  print_message("widest supernode: %d columns\n", f.direct.by_hand()->widest_supernode());
  assert_true(f.direct.by_hand()->widest_supernode() > SupernodalSolve::kInvertedWidth);
  // The multi-column solves (the contact columns) stay in double.
  Eigen::MatrixXd B(f.b.size(), 2), X;
  B << f.b, f.b;
  f.direct.solve_raw(B, X);
  assert_true(relative(X.col(1), reference.col(0)) <= 1e-13);
}

// The half-precision copy (every panel in 16 bits, each scaled into half's range) against
// cholmod_solve2, where the CPU has F16C.
static void test_half_within_its_precision(void**) {
  Factored f(Copy::Half);
  if (!half_products_supported()) {
    assert_false(f.direct.by_hand()->half());  // the single copy serves
    assert_true(f.direct.by_hand()->single());
    skip();
  }
  assert_true(f.direct.by_hand()->half());
  const double d = copy_difference(f);
  print_message("half precision against cholmod_solve2: %.3g\n", d);
  assert_true(d > 1e-6);  // it did solve in half precision (single's difference is ~1e-7)
  assert_true(d <= SupernodalSolve::kHalfAgreement);
  // Wide supernodes ran too, as chains of panels.
  assert_true(f.direct.by_hand()->widest_supernode() > SupernodalSolve::kInvertedWidth);
}

// A nearly incompressible, very stiff body (E = 1e9 Pa, nu = 0.499): the half copy's solve agrees
// with the double one to 1e-3 on the probe, but its residual is far above the probe, and the
// conjugate gradients it preconditions took hundreds of iterations (the stress matrix's scenario
// a). It is refused, and the single copy serves.
static void test_half_refused_where_its_residual_is_large(void**) {
  Factored soft(Copy::Half), stiff(Copy::Half, Material{1e9, 0.499, 1000});
  if (!half_products_supported()) skip();
  assert_true(soft.direct.by_hand()->half());
  assert_false(stiff.direct.by_hand()->half());
  assert_true(stiff.direct.by_hand()->single());
  const double d = copy_difference(stiff);
  print_message("stiff body: the single copy against cholmod_solve2 %.3g\n", d);
  assert_true(d > 1e-12 && d <= SupernodalSolve::kSingleAgreement);
}

// The half products against the same products in double from the same halves.
static void test_half_products(void**) {
  if (!half_products_supported()) skip();
  // Rows not a multiple of 8 or 16: 32 + 5 and 32 + 8 + 5 (the block of 8 and the scalar tail run too).
  for (const int rows : {37, 45}) {
    const int ld = 49, nc = 7;
    std::vector<float> B(size_t(ld) * nc), x(nc), y(rows), out(nc), back(size_t(ld) * nc);
    for (size_t q = 0; q < B.size(); ++q) B[q] = float(std::sin(0.37 * double(q)));
    for (int j = 0; j < nc; ++j) x[size_t(j)] = float(std::cos(1.1 * j));
    for (int i = 0; i < rows; ++i) y[size_t(i)] = float(std::sin(0.9 * i + 0.2));
    std::vector<uint16_t> H(B.size());
    to_half(B.data(), B.size(), 64.0f, H.data());
    const float s = 1.0f / 64;
    // The halves themselves: within half's rounding of the scaled values (2^-11 relative).
    std::vector<float> ones(1, 1.0f), unit(1);
    for (size_t q = 0; q < B.size(); ++q) {
      half_product(H.data() + q, 1, 1, 1, ones.data(), s, unit.data());
      back[q] = unit[0];
      assert_true(std::fabs(back[q] - B[q]) <= std::ldexp(std::fabs(B[q]), -11) + 1e-12);
    }
    half_product(H.data(), ld, rows, nc, x.data(), s, y.data());
    half_transposed_product(H.data(), ld, rows, nc, y.data(), s, out.data());
    // Each result against the same sum in double of the stored halves, to float's rounding.
    auto check = [](float got, int count, auto term) {
      double expected = 0, size = 0;
      for (int k = 0; k < count; ++k) {
        expected += term(k);
        size += std::fabs(term(k));
      }
      assert_true(std::fabs(got - expected) <= 1e-6 * size);
    };
    auto entry = [&](int i, int j) { return double(back[size_t(j) * ld + size_t(i)]); };
    for (int i = 0; i < rows; ++i) check(y[size_t(i)], nc, [&](int j) { return entry(i, j) * x[size_t(j)]; });
    for (int j = 0; j < nc; ++j) check(out[size_t(j)], rows, [&](int i) { return entry(i, j) * y[size_t(i)]; });
  }
}

// Half columns H = L^-1 P E of two nodes: H_a^T H_b against the block of A^-1 that cholmod_solve2
// gives; they are sparse (a path up the elimination tree); and the solve in halves with half
// columns added between them is A^-1 (b + E f), with what it gives along E as H^T of what was
// between them (dot), in double and, to their precision, with the single and the half copies.
static void test_half_columns_and_halves(void**) {
  for (Copy copy : kCopies) {
    Factored f(copy);
    const int32_t n = f.p.fem.node_count(), b = n - 2;  // free nodes (the base is fixed): a inside, b on top
    int32_t a = n / 2;
    while (f.p.projection.is_constrained[a]) ++a;
    const SupernodalSolve& halves = *f.direct.by_hand();
    SupernodalSolve::HalfColumns Ha, Hb;
    halves.half_columns(3 * a, Ha);
    halves.half_columns(3 * b, Hb);
    Eigen::MatrixXd E = Eigen::MatrixXd::Zero(3 * n, 3), columns;
    E.middleRows<3>(3 * b).setIdentity();
    f.direct.solve_raw_cholmod(E, columns);  // A^-1 E_b
    const Mat3 block = columns.middleRows<3>(3 * a), ab = SupernodalSolve::product(Ha, Hb);
    // With a copy they are the copy's: its compliance, to float's rounding, and A^-1's to the
    // copy's precision.
    Eigen::VectorXd copy_column(3 * n);
    Mat3 copy_block;
    for (int c = 0; c < 3; ++c) {
      halves.solve_single(E.col(c).data(), copy_column.data());
      copy_block.col(c) = copy_column.segment<3>(3 * a);
    }
    const double d_exact = (ab - block).norm() / block.norm(), d_copy = (ab - copy_block).norm() / copy_block.norm();
    print_message("copy %d: H_a^T H_b against A^-1's block %.2g, the copy's %.2g (rows kept: %ld and %ld of %d)\n",
                  int(copy), d_exact, d_copy, long(Ha.values.rows()), long(Hb.values.rows()), 3 * n);
    assert_true(block.norm() > 0 && d_exact <= (halves.single() ? allowed(halves) : 1e-12));
    assert_true(d_copy <= (halves.single() ? 1e-5 : 1e-12));
    assert_true(Ha.values.rows() < 3 * n / 2);
    const Vec3 f_b(0.3, -1, 2);
    halves.forward(f.b.data(), true);
    const Vec3 along = halves.dot(Hb) + SupernodalSolve::product(Hb, Hb) * f_b;
    halves.add(Hb, f_b);
    Eigen::VectorXd x(3 * n), reference;
    halves.backward(x.data());
    Eigen::MatrixXd solved;
    f.direct.solve_raw_cholmod(f.b + E * f_b, solved);
    reference = solved.col(0);
    const double d = relative(x, reference), d_along = (x.segment<3>(3 * b) - along).norm() / along.norm();
    print_message("  in halves against cholmod_solve2 %.2g; along E_b against H^T w %.2g\n", d, d_along);
    assert_true(d <= allowed(halves));
    assert_true(d_along <= allowed(halves));
    assert_true(d >= at_least(halves));  // it did run with the copy
  }
}

// The halves with node turns Q (the warped preconditioner's): backward(forward(b, Q), Q) is
// Q A^-1 Q^T b, in double to round-off and with the copies to their precision.
static void test_turned_halves(void**) {
  for (Copy copy : kCopies) {
    Factored f(copy);
    const int32_t n = f.p.fem.node_count();
    std::vector<Mat3> turn(static_cast<size_t>(n));
    Eigen::VectorXd turned_b(3 * n);
    for (int32_t i = 0; i < n; ++i) {
      turn[size_t(i)] = Eigen::AngleAxisd(0.1 * i, Vec3(1, 2, 3 + i % 5).normalized()).toRotationMatrix();
      turned_b.segment<3>(3 * i) = turn[size_t(i)].transpose() * f.b.segment<3>(3 * i);
    }
    Eigen::MatrixXd solved;
    f.direct.solve_raw_cholmod(turned_b, solved);
    Eigen::VectorXd reference(3 * n), x(3 * n);
    for (int32_t i = 0; i < n; ++i) reference.segment<3>(3 * i) = turn[size_t(i)] * solved.col(0).segment<3>(3 * i);
    const SupernodalSolve& halves = *f.direct.by_hand();
    halves.forward(f.b.data(), true, turn.data());
    halves.backward(x.data(), turn.data());
    const double d = relative(x, reference);
    print_message("copy %d: turned halves against Q A^-1 Q^T b %.2g\n", int(copy), d);
    assert_true(d <= allowed(halves));
    assert_true(d >= at_least(halves));
  }
}

// A factorization that keeps only its copy: CHOLMOD's values freed, every solve and half column
// from the copy, the same bits as with the double kept; and the next factorization fills the
// factor again.
static void test_released_double(void**) {
  for (Copy copy : {Copy::Single, Copy::Half}) {
    Factored kept(copy), released(copy, Material{2e4, 0.3, 1000}, false);
    const SupernodalSolve &k = *kept.direct.by_hand(), &r = *released.direct.by_hand();
    assert_true(k.double_kept());
    assert_false(r.double_kept());
    assert_true(r.single() && r.half() == k.half());
    for (int round = 0; round < 2; ++round) {
      Eigen::VectorXd from_kept, from_released, exact;
      kept.direct.solve_one(kept.b, from_kept, true);
      released.direct.solve_one(released.b, from_released, false);  // asked in double: the copy answers
      assert_true(from_released == from_kept);
      SupernodalSolve::HalfColumns hk, hr;
      const int32_t node = released.p.fem.node_count() - 2;
      k.half_columns(3 * node, hk);
      r.half_columns(3 * node, hr);
      assert_true(hr.start == hk.start && hr.values == hk.values);
      kept.direct.solve_one(kept.b, exact, false);
      print_message("copy %d, factorization %d: released against the double solve %.2g\n", int(copy), round + 1,
                    relative(from_released, exact));
      assert_true(relative(from_released, exact) <= allowed(r));
      released.direct.factorize(ProjectedSystem{released.p.fem.pattern, released.p.A, released.p.projection});
      assert_false(released.direct.by_hand()->double_kept());
    }
  }
}

// A simplicial factor is not a supernodal one: bind refuses it.
static void test_other_factors_refused(void**) {
  struct Simplicial : Eigen::CholmodSimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> {
    cholmod_factor* factor() const { return m_cholmodFactor; }
  } simplicial;
  Eigen::SparseMatrix<double> A(3, 3);
  for (int i = 0; i < 3; ++i) A.insert(i, i) = 2.0 + i;
  simplicial.compute(A);
  assert_true(simplicial.info() == Eigen::Success);
  SupernodalSolve solve;
  assert_false(solve.bind(simplicial.factor(), Copy::None));
  assert_false(solve.bound());
  assert_false(solve.bind(nullptr, Copy::Half));
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_double_matches_cholmod),
      cmocka_unit_test(test_single_within_its_precision),
      cmocka_unit_test(test_half_within_its_precision),
      cmocka_unit_test(test_half_products),
      cmocka_unit_test(test_half_refused_where_its_residual_is_large),
      cmocka_unit_test(test_half_columns_and_halves),
      cmocka_unit_test(test_turned_halves),
      cmocka_unit_test(test_released_double),
      cmocka_unit_test(test_other_factors_refused),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
