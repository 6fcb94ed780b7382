// SPDX-License-Identifier: Apache-2.0
// Co-rotational re-linearisation (K1 in docs/stability.md).
//
// The step A v+ = M v + h (f_R(x) + f_ext) is backward Euler with the element rotations R frozen
// at the step's start. The elastic force f_R(y) = -sum R Ke (R^T y - X) is affine in y, so the
// step is exactly backward Euler on the quadratic energy U_R, and on U_R it never gains energy.
// The model's energy U(y) uses each element's own rotation R(y); when elements turn far within
// one step (a released twist, a flapping thin plate, stiff bodies at long steps), the frozen
// rotations move nodes along straight lines where they should turn, and U(x+) can be far above
// U_R(x+): a released 180-degree twist went from 5.9 J to 420 J in one step.
//
// The check, after every solve of a step with co-rotational bodies: the energy the step gained
// beyond the work done on the bodies (loads, constraints, contacts) is, from the exact energy
// balance of the linearised step,
//   growth = [U(x+) - U_lin(x+)] - [U(x) - U_lin(x)] - dissipation,
// U_lin the quadratic energy the step was linearised with (U_R for the first solve),
// dissipation = |v+ - v|_M^2 / 2 + h^2 v+^T K v+ / 2 + h v+^T C v+ >= 0. Accepted while the
// growth, summed over the steps since the energy last went down (StepResults::debt), stays below
// WorldSettings::relinearise_tolerance times the bodies' energy. The first screen costs one
// rotation and two element energies per element: the rotations at x+ are the next step's start
// rotations (start_rotations reuses them when the positions did not change in between), so the
// check replaces the next step's rotation pass rather than adding one.
//
// The remedy when a step fails the check: Newton iterations of the fully implicit step
//   M (v+ - v) = h (f(x + h v+) + f_ext) - h C v+ + G^T lambda + r,
// i.e. minimising the incremental potential
//   phi(v) = |v - v_n|_M^2 / 2 + U(x + h v) - h f_ext . v + h v^T C v / 2
// over the same contact and projection constraints (their rows are linear in v and stay those of
// the step's start). Each iteration linearises at the current iterate x_k = x + h v_k with its
// rotations R_k = R(x_k) and the projected Hessian of U: the warped stiffness R_k Ke R_k^T plus
// the positive twist stiffness G_k it leaves out (fem/rotation_stiffness.hpp; without G the
// iteration stalls or diverges on stretched thin elements). Since f_R is affine,
// f(x_k) - H (y - x_k) = f_{R_k}(y) - G_k (y - x_k): the pipeline's own assembly with R_k, plus
// h^2 G_k in A and h G_k v_k in f_int. The solution v^ of each linearisation is a full solve of the
// step's complementarity problem; a backtracking line search on phi between the iterate and v^
// (both feasible: the constraint set is convex) chooses the next iterate. The step ends with the
// first solution that passes the check, or after relinearise_max solves with the one that gained
// the least, so the kept velocities, impulses, A and b always belong to one solve (the LPC
// reactions and tool forces come from them).
//
// Neo-Hookean bodies (fem/neo_hookean.hpp) take part in the same iterations. Their force is not
// affine in y, so each solve is a Newton step on phi with the body's own energy U: linearised at
// x_k = x + h v_k with the projected Hessian H_k, f(x_k) - H_k (y - x_k) is the assembly at x_k
// plus h H_k v_k in f_int; the first iterate is the explicit predictor v_0 = v (World::prepare_step),
// which took the nidus press from 1.54 to 1.44 solves per step against linearising at x. Their check is the model's error at the solution: the quadratic model
// U_L the solve minimised, evaluated at x+, against U(x+); |U(x+) - U_L(x+)| <= tol times the
// body's energy. It vanishes as the iterates converge (cubically in the step length) and is
// small for a first solve whose strain changes little in the step. A step with neo-Hookean bodies
// whose solves all miss the check keeps the best one and reports itself not converged
// (WorldStats::converged; mica_step returns MICA_WARN_NOT_CONVERGED).
#include <algorithm>
#include <chrono>
#include <cmath>

#include "fem/linearisation.hpp"
#include "fem/neo_hookean.hpp"
#include "world/world.hpp"

namespace mica {

namespace {

struct BodyTerms {
  double alpha = 0, beta = 0;  // Rayleigh damping, if the body is damped
  bool loads = false;          // f_ext is part of the step
};

struct Eval {
  double growth = 0;  // J gained beyond the work done on the bodies
  double scale = 0;   // J, the bodies' energy
  double phi = 0;     // J, the incremental potential (all dynamic bodies)
  double model_error = 0, model_scale = 0;  // J, neo-Hookean bodies: |U(x+) - U_L(x+)| and their energy
  double model_floor = 0;                   // J, the round-off of model_error
};

// The step's end positions x + h v (next_end.x; its rotations are the caller's to compute).
void end_state(Body& b, const Vec3List& v, double h) {
  Vec3List& x_end = b.next_end.x;
  x_end.resize(b.x.size());
  for (size_t i = 0; i < b.x.size(); ++i) x_end[i] = b.x[i] + h * v[i];
}

// The first screen of the step's solution b.v_next, linearised with b.rotations() (the step's
// start rotations): computes next_end.R and returns [U(x+) - U_R(x+)] (an upper bound of the growth) and
// the scale; caches U(x+) for the next step.
Eval screen(Body& b, double h) {
  const FemModel& m = b.fem;
  end_state(b, b.v_next, h);
  const bool start_known = b.relin.u_start_known;
  const ScreenEnergies u = screen_energies(m, b.x, b.next_end.x, b.rotations(), b.next_end.R, !start_known);
  if (!start_known) b.relin.u_start = u.u_lin_start;
  b.relin.k_start = 0.5 * mass_dot(m, b.v, b.v);
  b.next_end.u = u.u_end;
  Eval out;
  out.growth = u.u_end - u.u_lin_end;
  out.scale = std::max(b.relin.k_start + b.relin.u_start, 0.5 * mass_dot(m, b.v_next, b.v_next) + u.u_end);
  return out;
}

// The full evaluation of velocities v of body b for a step linearised with b.rotations() (and, when
// b.relin.modes is not empty, the twist stiffness at x + h v_lin); R_start the step's start
// rotations (they define the damping in phi). Sets next_end: x, R and U(x).
Eval evaluate(Body& b, const Vec3List& v, double h, const BodyTerms& d, const std::vector<Mat3>& R_start) {
  const FemModel& m = b.fem;
  end_state(b, v, h);
  const LinearisationEnergies u =
      linearisation_energies(m, b.x, b.next_end.x, v, b.settings.corotational() ? &b.rotations() : nullptr, b.next_end.R, &R_start,
                             d.beta != 0, b.relin.modes, b.relin.v_lin);
  // The linearisation is backward Euler on U_L(y) = U_R(y) + (y - x_lin)^T G (y - x_lin) / 2.
  const double U1 = u.u_end, UL1 = u.u_lin_end + 0.5 * h * h * u.gdd, UL0 = u.u_lin_start + 0.5 * h * h * u.gll;
  Vec3List& dv = b.relin.scratch;
  dv.resize(v.size());
  for (size_t i = 0; i < v.size(); ++i) dv[i] = v[i] - b.v[i];
  const double dvMdv = mass_dot(m, dv, dv), vMv = mass_dot(m, v, v);
  const double dissipation = 0.5 * dvMdv + 0.5 * h * h * (u.vKv + u.gvv) + h * (d.alpha * vMv + d.beta * u.vKv);
  const double U0 = b.relin.u_start, K0 = b.relin.k_start;
  Eval out;
  out.growth = (U1 - UL1) - (U0 - UL0) - dissipation;
  // The work done on the body in the step, by the balance of the linearised step.
  const double work = (0.5 * vMv + UL1) - (K0 + UL0) + dissipation;
  out.scale = K0 + U0 + std::fabs(work);
  double fv = 0;
  if (d.loads)
    for (size_t i = 0; i < v.size(); ++i) fv += b.f_ext[i].dot(v[i]);
  out.phi = 0.5 * dvMdv + U1 - h * fv + 0.5 * h * (d.alpha * vMv + d.beta * u.vKv_start);
  b.next_end.u = U1;
  return out;
}

// A neo-Hookean body's velocities v against the quadratic model its system was assembled from
// (at relin.x_lin). Sets next_end.x and next_end.u.
Eval evaluate_neo_hookean(Body& b, const Vec3List& v, double h, const BodyTerms& d) {
  const FemModel& m = b.fem;
  end_state(b, v, h);
  const NeoHookeanModelEnergies u =
      neo_hookean_model_energies(m, b.neo_hookean, b.relin.x_lin, b.next_end.x, &v);
  Vec3List& dv = b.relin.scratch;
  dv.resize(v.size());
  for (size_t i = 0; i < v.size(); ++i) dv[i] = v[i] - b.v[i];
  const double dvMdv = mass_dot(m, dv, dv), vMv = mass_dot(m, v, v);
  double fv = 0;
  if (d.loads)
    for (size_t i = 0; i < v.size(); ++i) fv += b.f_ext[i].dot(v[i]);
  Eval out;
  // The beta part of the damping with the linearisation's H (the co-rotational phi uses the start's K).
  out.phi = 0.5 * dvMdv + u.u_end - h * fv + 0.5 * h * (d.alpha * vMv + d.beta * u.vKv);
  out.model_error = std::fabs(u.u_end - u.u_lin_end);
  out.model_scale = std::max(b.relin.k_start + b.relin.u_start, 0.5 * vMv + u.u_end);
  out.model_floor = b.relin.round_off;
  b.next_end.u = u.u_end;
  return out;
}

// The first screen of a neo-Hookean body's solution b.v_next (linearised at the predictor x + h v):
// also fixes the start's energies, U(x) as the last step found it at its end when x is still there.
Eval screen_neo_hookean(Body& b, double h, const BodyTerms& d) {
  const double u_start = !b.end.x.empty() && b.end.x == b.x ? b.end.u : neo_hookean_energy(b.fem, b.x);
  double stiffness = 0;
  for (size_t e = 0; e < b.fem.elements.size(); ++e)
    stiffness += (b.fem.lame[e].mu + b.fem.lame[e].lambda) * b.fem.elements[e].volume;
  b.relin.u_start = u_start;
  // Energies near rest are differences of terms of order (mu + lambda) V: below this the error is round-off.
  b.relin.round_off = 1e-12 * stiffness;
  b.relin.k_start = 0.5 * mass_dot(b.fem, b.v, b.v);
  return evaluate_neo_hookean(b, b.v_next, h, d);
}

// The linearisation at next_end.x = x + h v_iter (whose rotations b.rotations() are) gains the positive twist
// stiffness G (fem/linearisation.hpp).
void add_twist_stiffness(Body& b, double h) {
  b.relin.v_lin = b.relin.v_iter;
  mica::add_twist_stiffness(b.fem, b.next_end.x, b.relin.v_lin, h, b.relin.modes, b.A, b.f_int);
}

}  // namespace

void World::start_rotations(const StepContext& ctx, Body& b) const {
  // The rotations computed after the last step's solve, if the positions are still those.
  b.relin.u_start_known = !b.end.x.empty() && b.end.x == b.x;
  b.rotations_in = b.relin.u_start_known ? Body::RotationsIn::End : Body::RotationsIn::Own;
  if (b.relin.u_start_known)
    b.relin.u_start = b.end.u;
  else
    compute_rotations(b.fem, b.x, b.own_R, ctx.pool);
  b.next_end.x.clear();
}

void World::relinearise(const StepContext& ctx, StageRunner& stage) {
  const std::vector<Body*>& dynamic = ctx.dynamic;
  const double h = ctx.h;
  const double tol = settings_.relinearise_tolerance;
  const int32_t max_solves = settings_.relinearise_max;
  if (max_solves < 2) return;
  // The debt the last good step left; this step's goes to its results (kept if the step is).
  const double debt = last_.debt;
  auto settle = [&](double growth) { next_.debt = std::max(0.0, debt + growth); };
  auto time_rotations = [&](auto&& f) {  // the rotations and energies of the check
    const auto start = std::chrono::steady_clock::now();
    f();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    StageStats& s = next_.stats.stages[size_t(Stage::Rotations)];
    s.ms_last_step += ms;
    s.ms_total += ms;
  };

  thread_local std::vector<BodyTerms> terms;  // kept: a step allocates nothing here
  terms.assign(dynamic.size(), BodyTerms{});
  for (size_t k = 0; k < dynamic.size(); ++k) {
    const Body& b = *dynamic[k];
    if (needs_damping(b)) terms[k] = {b.settings.rayleigh_alpha, b.settings.rayleigh_beta, false};
    terms[k].loads = needs_loads(b);
  }
  auto passes = [&](const Eval& e) {
    return debt + e.growth <= tol * e.scale && e.model_error <= tol * e.model_scale + e.model_floor;
  };
  // The screen: the rotation update U(x+) - U_R(x+) bounds the growth from above.
  Eval cur;
  bool neo_hookean = false;
  time_rotations([&] {
    for (size_t k = 0; k < dynamic.size(); ++k) {
      Body* b = dynamic[k];
      if (b->settings.neo_hookean()) {
        neo_hookean = true;
        const Eval e = screen_neo_hookean(*b, h, terms[k]);
        cur.model_error += e.model_error;
        cur.model_scale += e.model_scale;
        cur.model_floor += e.model_floor;
      }
      if (!b->settings.corotational()) continue;
      b->relin.modes.clear();
      const Eval e = screen(*b, h);
      cur.growth += e.growth;
      cur.scale += e.scale;
    }
  });
  if (passes(cur)) {
    settle(cur.growth);
    return;
  }

  // The full check, with the step's dissipation.
  auto evaluate_all = [&](bool trial) {  // v_next, or the line search's trial velocities
    Eval sum;
    for (size_t k = 0; k < dynamic.size(); ++k) {
      Body& b = *dynamic[k];
      const Vec3List& v = trial ? b.relin.v_trial : b.v_next;
      if (b.settings.neo_hookean()) {
        const Eval e = evaluate_neo_hookean(b, v, h, terms[k]);
        sum.phi += e.phi;
        sum.model_error += e.model_error;
        sum.model_scale += e.model_scale;
        sum.model_floor += e.model_floor;
        continue;
      }
      const Eval e = evaluate(b, v, h, terms[k], b.relin.R_start);
      sum.phi += e.phi;
      if (!b.settings.corotational()) continue;
      sum.growth += e.growth;
      sum.scale += e.scale;
    }
    return sum;
  };
  for (Body* b : dynamic) {
    b->relin.R_start = b->rotations();
    b->relin.modes.clear();
  }
  time_rotations([&] { cur = evaluate_all(false); });
  if (passes(cur)) {
    settle(cur.growth);
    return;
  }

  // Newton iterations. Linearise at x + h v_iter (next_end holds its positions and rotations:
  // the last evaluation was of the iterate) or at the step's start, and solve.
  auto linearise_and_solve = [&](bool at_start) {
    for (Body* b : dynamic) {
      if (b->settings.neo_hookean()) {  // linearised at x + h v_iter (at the start: the predictor v)
        b->relin.v_lin = at_start ? b->v : b->relin.v_iter;
        for (size_t i = 0; i < b->x.size(); ++i) b->relin.x_lin[i] = b->x[i] + h * b->relin.v_lin[i];
        continue;
      }
      if (!b->settings.corotational()) continue;
      b->own_R = at_start ? b->relin.R_start : b->next_end.R;
      b->rotations_in = Body::RotationsIn::Own;
      b->relin.modes.clear();
    }
    auto relinearised = [](const Body* b) { return b->settings.corotational() || b->settings.neo_hookean(); };
    stage.run(Stage::Elements, true, [&] {
      for (Body* b : dynamic) {
        if (!relinearised(b)) continue;  // the others' A and forces do not change
        assemble_elements(ctx, *b);
        if (!at_start && b->settings.corotational()) add_twist_stiffness(*b, h);
      }
    });
    stage.run(Stage::Damping, std::any_of(dynamic.begin(), dynamic.end(), [&](Body* b) { return needs_damping(*b); }),
              [&] {
                for (Body* b : dynamic)
                  if (relinearised(b) && needs_damping(*b)) add_damping(ctx, *b);
              });
    // The statistics report the solve whose solution the step keeps; iterations add up.
    next_.stats.solver_residual = 0;
    next_.stats.converged = true;
    stage.run(Stage::Solve, true, [&] { solve(ctx); });
  };
  for (Body* b : dynamic) b->relin.v_iter = b->v_next;
  // The best solve gained the least (co-rotational) and missed its model the least (neo-Hookean).
  double phi_iter = cur.phi, best = cur.growth + cur.model_error;
  int32_t best_solve = 1, solves = 1;
  bool solution_evaluated = true;  // the last evaluation was of v_next
  while (solves < max_solves) {
    linearise_and_solve(false);
    ++solves;
    time_rotations([&] { cur = evaluate_all(false); });
    solution_evaluated = true;
    if (passes(cur)) {
      settle(cur.growth);
      return;
    }
    if (cur.growth + cur.model_error < best) {
      best = cur.growth + cur.model_error;
      best_solve = solves;
      for (Body* b : dynamic) b->relin.v_best = b->relin.v_iter;  // the linearisation point
    }
    if (solves == max_solves) break;
    if (cur.phi < phi_iter) {
      for (Body* b : dynamic) b->relin.v_iter = b->v_next;
      phi_iter = cur.phi;
      continue;
    }
    // Backtrack: v_iter + t (v_next - v_iter), t = 1/2, 1/4, ..., 1/64.
    bool moved = false;
    for (double t = 0.5; t > 0.01 && !moved; t *= 0.5) {
      Eval e;
      time_rotations([&] {
        for (Body* b : dynamic) {
          b->relin.v_trial.resize(b->v_next.size());
          for (size_t i = 0; i < b->v_next.size(); ++i)
            b->relin.v_trial[i] = b->relin.v_iter[i] + t * (b->v_next[i] - b->relin.v_iter[i]);
        }
        e = evaluate_all(true);
      });
      solution_evaluated = false;
      if (e.phi < phi_iter) {
        for (Body* b : dynamic) b->relin.v_iter.swap(b->relin.v_trial);
        phi_iter = e.phi;
        moved = true;
      }
    }
    if (!moved) break;  // no descent along the direction: the iteration cannot improve
  }
  // No solve passed: keep the one that gained the least, solving it again if it was not the last.
  if (best_solve != solves) {
    if (best_solve > 1) {
      for (Body* b : dynamic) {
        b->relin.v_iter = b->relin.v_best;
        end_state(*b, b->relin.v_iter, h);
        if (b->settings.corotational()) {
          compute_rotations(b->fem, b->next_end.x, b->next_end.R, ctx.pool);
        }
      }
    }
    linearise_and_solve(best_solve == 1);
    solution_evaluated = false;
  }
  // Whatever is kept, next_end must be of its end positions (the next step's start).
  if (!solution_evaluated) time_rotations([&] { cur = evaluate_all(false); });
  // Neo-Hookean bodies: the step did not converge to its tolerance (co-rotational bodies keep their
  // best solve silently, with its growth in the debt).
  if (neo_hookean && !passes(cur)) next_.stats.converged = false;
  settle(cur.growth);
}

}  // namespace mica
