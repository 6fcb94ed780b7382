// Co-rotational re-linearisation (K1 in docs/stability.md).
//
// The step A v+ = M v + h (f_R(x) + f_ext) is backward Euler with the element rotations R frozen
// at the step's start: the elastic force f_R(y) = -sum R Ke (R^T y - X) is affine in y, so
// f_R(x + h v+) = f_R(x) - h K_R v+ exactly. On the quadratic energy U_R the step is exactly
// dissipative; but when elements turn far within the step (a released twist, a flapping thin
// plate, stiff bodies at long steps) the model's energy U(x+) at the new rotations can be far
// higher: the frozen rotations move nodes along straight lines where they should turn.
//
// The remedy: after the solve, compute the rotations at the step's end x+ = x + h v+. Where an
// element turned more than WorldSettings::relinearise_angle from the rotation the step used,
// solve the step again with R = R(x+). Since f_R is affine, re-linearising the force at x+ with
// its rotations is the same step with other rotations (f(x+) + K (y - x+) = f_{R(x+)}(y)): this is
// the fixed-point (Newton without dR/dx, the warped-stiffness Newton) iteration of the fully
// implicit step M (v+ - v) = h (f(x+) + f_ext) + G^T lambda + r, whose solution no longer gains
// energy from the rotation update. The contacts and the projection constraints stay those of the
// step's start (their rows are linear in v+: every pass solves the same complementarity problem
// with another A and b).
//
// Cost when no element turns that far: the rotations of x+ are the next step's start rotations,
// so they are computed here once instead of at the next step's start (start_rotations reuses them
// when the positions did not change in between): no extra work but a comparison per element.
// Their time is added to the Rotations stage's (its run count stays one a step); each extra pass
// counts one more run of the Elements (and Damping) and Solve stages.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "world/world.hpp"

namespace mica {

void World::start_rotations(Body& b) const {
  // The rotations computed after the last step's solve, if the positions are still those.
  if (!b.x_end.empty() && b.x_end == b.x) {
    std::swap(b.R, b.R_end);
  } else {
    compute_rotations(b.fem, b.x, b.R);
  }
  b.x_end.clear();
}

void World::relinearise(const std::vector<Body*>& dynamic, double h, StageRunner& stage,
                        const std::function<void()>& solve) {
  double angle = settings_.relinearise_angle; int32_t max_passes = settings_.relinearise_max;
  if (getenv("RELIN_ANGLE")) angle = atof(getenv("RELIN_ANGLE"));
  if (getenv("RELIN_MAX")) max_passes = atoi(getenv("RELIN_MAX"));
  if (!(angle > 0)) return;
  // An element turned further than the angle when tr(R^T R_end) = 1 + 2 cos(angle) is below this.
  const double min_trace = 1 + 2 * std::cos(std::min(angle, M_PI));
  std::vector<Body*>& turned = relinearised_;
  for (int32_t pass = 0;; ++pass) {
    // The rotations at the end of the step as solved (timed with the Rotations stage).
    const auto start = std::chrono::steady_clock::now();
    turned.clear();
    for (Body* b : dynamic) {
      if (!b->settings.corotational) continue;
      b->x_end.resize(b->x.size());
      for (size_t i = 0; i < b->x.size(); ++i) b->x_end[i] = b->x[i] + h * b->v_next[i];
      compute_rotations(b->fem, b->x_end, b->R_end);
      double worst = 3;
      for (size_t e = 0; e < b->R.size(); ++e) worst = std::min(worst, (b->R[e].array() * b->R_end[e].array()).sum());
      if (getenv("RELIN_TRACE")) fprintf(stderr, "step %ld pass %d max angle %.4g\n", (long)stats_.step_count, pass, std::acos(std::max(-1.0, std::min(1.0, (worst - 1) / 2))));
      if (worst < min_trace) turned.push_back(b);
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    StageStats& s = stats_.stages[size_t(Stage::Rotations)];
    s.ms_last_step += ms;
    s.ms_total += ms;
    if (turned.empty() || pass >= max_passes) return;
    // Solve the step again, linearised at the end rotations of the bodies that turned.
    for (Body* b : turned) b->R = b->R_end;
    stage.run(Stage::Elements, true, [&] {
      for (Body* b : turned) assemble_elements(*b, h, needs_damping(*b));
    });
    stage.run(Stage::Damping, std::any_of(turned.begin(), turned.end(), [&](Body* b) { return needs_damping(*b); }),
              [&] {
                for (Body* b : turned)
                  if (needs_damping(*b)) add_damping(*b, h);
              });
    // The solve reports on the system whose solution the step keeps: the last one.
    stats_.solver_residual = 0;
    stats_.converged = true;
    stage.run(Stage::Solve, true, solve);
  }
}

}  // namespace mica
