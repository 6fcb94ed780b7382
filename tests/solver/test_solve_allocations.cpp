// SPDX-License-Identifier: Apache-2.0
// The factored MICA solver's solve makes no heap allocation once warm: the whole
// VelocitySolver::solve call (the iteration loop, the factor's columns, W and its equalities'
// decomposition, the small frictional problems) on a step whose contact rows are no more than
// those of the steps before and whose factor is not made anew. Counted as the servo path's tests
// count (haptics/alloc_counter.hpp), and with malloc counted too: Eigen allocates with malloc.
//
// Scenes on the solver problem's sheared cube (solver_problem.hpp), stepped a few times
// (x += h v; A, b, contact gaps afresh, the same contact nodes):
//  - press: a sphere pressed into the top face, on several nodes, friction mu 0.3;
//  - grasp + press: two jaws squeezing the sides' upper nodes, and the sphere.
// Each runs both loops (SolverSettings::active_set) with the factor current (a linear body: the
// factor is A), lagged (a co-rotational body: A re-assembled every step from its rotations, the
// first step's factor warped) and refreshed (the same, the factor made anew in the background
// every other step: the counted steps launch and adopt refreshes, and remake the half columns).
// Each solve is a step that may be undone (begin_step .. commit_step), as World::step runs it. The sphere's contact curvature is in A on a face of pressed
// nodes, a little larger every step (SolverBody::extra_stiffness: Woodbury's correction).
// malloc is counted too, except in a sanitizer build: the sanitizer owns malloc (replacing it
// there aborts at start-up), and only operator new is counted.
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define MICA_TEST_COUNT_MALLOC
#endif
#include "haptics/alloc_counter.hpp"
#include "solver/factored_mica.hpp"  // before cmocka (test_util.hpp)
#include "solver/solver_problem.hpp"

using namespace mica;
using namespace mica_test;

namespace {

constexpr double kMu = 0.3;
constexpr int kWarmSteps = 6, kCountedSteps = 4;  // refreshed: warm-up adopts into each of two column maps

// A contact plane or sphere touching chosen nodes of the cube.
struct Tool {
  bool sphere;
  Vec3 centre;   // the sphere's centre, or a point of the plane
  Vec3 normal;   // the plane's: the direction it pushes the body
  double radius; // the sphere's
  Vec3 velocity;
  std::vector<int32_t> nodes;
};

struct Scene {
  SolverProblem p{kMu, 4, false};
  std::vector<Tool> tools;
  bool corotational = true;
  int32_t steps = 0;

  explicit Scene(bool grasp, bool corotational_body) : corotational(corotational_body) {
    // A sphere of 20 cm radius 5 mm into the middle of the (sheared) top face and coming down at
    // 5 cm/s: it presses the middle node and the eight around it.
    const Vec3 top(0.05 + 0.08 * 0.01, 0.1, 0.05 + 0.03 * 0.1);
    Tool sphere{true, top + Vec3(0, 0.2 - 0.005, 0), Vec3::Zero(), 0.2, Vec3(0.01, -0.05, 0), {}};
    for (int32_t i = 0; i < p.fem.node_count(); ++i)
      if (p.fem.rest[i].y() > 0.1 - 1e-9 && (p.fem.rest[i] - Vec3(0.05, 0.1, 0.05)).norm() < 0.04)
        sphere.nodes.push_back(i);
    tools.push_back(sphere);
    // The curvature's place: a face of three pressed nodes (a tet's).
    for (const TetElement& el : p.fem.elements) {
      std::vector<int32_t> pressed;
      for (int32_t i : el.nodes)
        if (std::count(sphere.nodes.begin(), sphere.nodes.end(), i)) pressed.push_back(i);
      if (pressed.size() < 3) continue;
      p.extra.push_back({{pressed[0], pressed[1], pressed[2]}, Eigen::Matrix<double, 9, 9>::Zero()});
      break;
    }
    add_curvature();
    // Jaws 2 mm inside the sides, on their upper halves' nodes, squeezing and lifting.
    if (grasp)
      for (double side : {0.0, 0.1}) {
        const Vec3 inward(side == 0 ? 1 : -1, 0, 0);
        Tool jaw{false, Vec3(side, 0, 0) + 0.002 * inward, inward, 0, 0.02 * inward + Vec3(0, 0.01, 0), {}};
        for (int32_t i = 0; i < p.fem.node_count(); ++i)
          if (std::fabs(p.fem.rest[i].x() - side) < 1e-9 && p.fem.rest[i].y() > 0.05 - 1e-9) jaw.nodes.push_back(i);
        tools.push_back(jaw);
      }
    build_rows();
  }

  // h^2 F K_c-like: positive semidefinite, of rank 3, a tenth of a node's diagonal block and
  // growing by a tenth each step (its values change, its nodes do not), added to A.
  void add_curvature() {
    TriangleStiffness& e = p.extra[0];
    Eigen::Matrix<double, 9, 3> B;
    for (int k = 0; k < 27; ++k) B(k / 3, k % 3) = std::sin(1.0 + k);
    const double s = 0.1 * (1 + 0.1 * steps) * p.A[size_t(p.fem.pattern.find(e.nodes[0], e.nodes[0]))].norm();
    e.K = (s / B.squaredNorm()) * B * B.transpose();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) p.A[size_t(p.fem.pattern.find(e.nodes[r], e.nodes[c]))] += e.K.block<3, 3>(3 * r, 3 * c);
  }

  // Contacts of the tools at the nodes' current positions (the same nodes every step).
  void build_rows() {
    p.contacts.clear();
    for (size_t k = 0; k < tools.size(); ++k) {
      const Tool& t = tools[k];
      for (int32_t i : t.nodes) {
        const Vec3 normal = t.sphere ? Vec3((p.x[i] - t.centre).normalized()) : t.normal;
        const double gap = t.sphere ? (p.x[i] - t.centre).norm() - t.radius : normal.dot(p.x[i] - t.centre);
        p.contacts.push_back(
            Contact{uint64_t(1000 * (k + 1) + i), node_point(0, i), BodyPoint{}, normal, p.x[i], gap, kMu, t.velocity});
        p.contacts.back().tool = int32_t(k);
      }
    }
    p.rows.build(p.contacts, SolverProblem::kH, 1.0);
    p.lambda.resize(p.rows.size(), 0.0);  // the same rows every step: the last impulses are the warm start
  }

  // The step after a solve: positions move by h v, the tools by h times theirs; the system (of
  // the new rotations for a co-rotational body; a linear body's A stays) and contacts afresh.
  void advance() {
    const double h = SolverProblem::kH;
    for (size_t i = 0; i < p.x.size(); ++i) p.x[i] += h * p.v[i];
    for (Tool& t : tools) t.centre += h * t.velocity;
    ++steps;
    if (corotational) {
      compute_rotations(p.fem, p.x, p.R);
      set_scaled_mass(p.fem, 1.0, p.A);
      assemble_elastic(p.fem, p.x, &p.R, h * h, &p.A, p.f_int);
      add_curvature();
    } else {
      assemble_elastic(p.fem, p.x, &p.R, h * h, nullptr, p.f_int);  // linear about the first rotations
    }
    const size_t n = p.x.size();
    Vec3List Mv(n), g(n, Vec3(0, -9.81, 0)), Mg(n);
    mass_multiply(p.fem, p.v, Mv);
    mass_multiply(p.fem, g, Mg);
    for (size_t i = 0; i < n; ++i) p.b[i] = Mv[i] + h * (p.f_int[i] + Mg[i]);
    build_rows();
  }

  SolverBody body() {
    SolverBody s = p.body();
    if (!corotational) s.rotation = nullptr;  // linear: the factor is A itself
    return s;
  }
};

enum class Factor { Current, Lagged, Refreshed };
const char* const kFactorName[] = {"current", "lagged", "refreshed every 2 solves"};

void check_no_allocation(bool grasp, bool active_set, Factor factor) {
  Scene scene(grasp, factor != Factor::Current);
  SolverSettings settings;
  settings.active_set = active_set;
  settings.refactor_interval = factor == Factor::Refreshed ? 2 : 0;
  FactoredMicaSolver solver(settings);
  std::vector<SolverBody> bodies{scene.body()};
  int active = 0;
  for (int step = 0; step < kWarmSteps + kCountedSteps; ++step) {
    const bool counted = step >= kWarmSteps;
    if (counted) start_counting_allocations();
    solver.begin_step();
    const SolveReport r = solver.solve({}, bodies, scene.p.rows, scene.p.lambda);
    solver.commit_step();
    const int64_t allocations = counted ? stop_counting_allocations() : 0;
    active = 0;
    for (size_t q = 0; q < scene.p.rows.size(); ++q) active += scene.p.rows.normal_of[q] < 0 && scene.p.lambda[q] > 0;
    print_message("%s, %s loop, factor %s, step %d: %d iterations, %d of %d contacts pressing, %lld allocations%s\n",
                  grasp ? "grasp + press" : "press", active_set ? "active-set" : "alternating",
                  kFactorName[int(factor)], step, r.iterations, active, int(scene.p.contacts.size()),
                  (long long)allocations, counted ? "" : " (warm-up, not counted)");
    assert_true(r.converged);
    check_solution(scene.p, 1e-6);
    assert_int_equal(allocations, 0);
    scene.advance();
  }
  // What the region claims: the factor of the first step throughout (current: A never changed;
  // lagged: warped to every later A) or one more launched every other solve (refreshed), and
  // contacts that press (a real contact problem).
  const int64_t steps = kWarmSteps + kCountedSteps;
  assert_int_equal(solver.factorizations(1), factor == Factor::Refreshed ? 1 + steps / 2 : 1);
  assert_true(active >= 3);
}

}  // namespace

static void test_press_does_not_allocate(void**) {
  for (bool active_set : {true, false})
    for (Factor factor : {Factor::Current, Factor::Lagged, Factor::Refreshed}) check_no_allocation(false, active_set, factor);
}

static void test_grasp_and_press_do_not_allocate(void**) {
  for (bool active_set : {true, false})
    for (Factor factor : {Factor::Current, Factor::Lagged, Factor::Refreshed}) check_no_allocation(true, active_set, factor);
}

int main(void) {
  const struct CMUnitTest tests[] = {
      cmocka_unit_test(test_press_does_not_allocate),
      cmocka_unit_test(test_grasp_and_press_do_not_allocate),
  };
  return cmocka_run_group_tests(tests, NULL, NULL);
}
