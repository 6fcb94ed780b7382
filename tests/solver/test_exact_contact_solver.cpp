// The exact contact solve through the Delassus matrix, given a problem out of double precision
// (issue 16: dt = 5e-324 with DIRECT made gap / h infinite, and Lemke's own argument check
// surfaced as MICA_ERR_INVALID_ARGUMENT "solve_lcp_lemke: M or q has a non-finite entry"):
// it is the step's numerical failure, Errc::Numerical with a message for the user.
#include "solver/exact_contact_solver.hpp"
#include "test_util.hpp"

using namespace mica;

namespace {

struct OneTet {
  FemModel fem;
  BlockValues A;
  Projection projection;
  DirectSolver direct;
  Vec3List b, v;
};

void make(OneTet& t) {
  TetMesh mesh;
  mesh.nodes = {Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0, 0.1, 0), Vec3(0, 0, 0.1)};
  mesh.tets = {Tet{0, 1, 2, 3}};
  t.fem = build_fem_model(mesh, Material{}, MassKind::Consistent, "tet");
  t.A.assign(t.fem.pattern.block_count(), Mat3::Zero());
  set_scaled_mass(t.fem, 1.0, t.A);
  t.projection.reset(4);
  t.direct.analyze(t.fem.pattern);
  t.direct.factorize(ProjectedSystem{t.fem.pattern, t.A, t.projection});
  t.b.assign(4, Vec3::Zero());
  t.v.assign(4, Vec3::Zero());
}

// One frictionless normal row on node 3, pushing along +z, with the given bias.
ContactRows one_row(double bias) {
  ContactRows rows;
  rows.start = {0, 1};
  rows.terms = {RowTerm{0, 3, 1.0}};
  rows.direction = {Vec3::UnitZ()};
  rows.bias = {bias};
  rows.normal_of = {-1};
  rows.mu = {0};
  rows.contact = {0};
  rows.key = {3};
  return rows;
}

Errc solve_code(OneTet& t, const ContactRows& rows, std::string& message) {
  std::vector<ExactBody> bodies = {ExactBody{&t.fem.pattern, &t.A, &t.b, &t.projection, &t.direct, &t.v, {}}};
  std::vector<double> lambda, diagonal;
  try {
    solve_contact_delassus(bodies, rows, lambda, diagonal);
  } catch (const Error& e) {
    message = e.what();
    return e.code();
  }
  message.clear();
  return Errc::Internal;  // "no error"
}

}  // namespace

static void test_finite_problem_is_solved(void**) {
  OneTet t;
  make(t);
  std::vector<ExactBody> bodies = {ExactBody{&t.fem.pattern, &t.A, &t.b, &t.projection, &t.direct, &t.v, {}}};
  std::vector<double> lambda, diagonal;
  solve_contact_delassus(bodies, one_row(-0.5), lambda, diagonal);  // node 3 must move up at 0.5 m/s
  assert_int_equal(lambda.size(), 1);
  assert_true(lambda[0] > 0);
  assert_near(t.v[3].z(), 0.5, 1e-9);
}

static void test_non_finite_problem_is_a_numerical_failure(void**) {
  OneTet t;
  make(t);
  std::string message;
  // gap / h with h = 5e-324: an infinite bias.
  assert_true(solve_code(t, one_row(-HUGE_VAL), message) == Errc::Numerical);
  assert_true(message.find("not finite") != std::string::npos);
  assert_true(message.find("lemke") == std::string::npos);
  // A NaN in the right-hand side (the free velocities).
  t.b[3] = Vec3(0, 0, NAN);
  assert_true(solve_code(t, one_row(-0.5), message) == Errc::Numerical);
  assert_true(message.find("lemke") == std::string::npos);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_finite_problem_is_solved),
      cmocka_unit_test(test_non_finite_problem_is_a_numerical_failure),
  };
  return cmocka_run_group_tests(tests, nullptr, nullptr);
}
