// SPDX-License-Identifier: Apache-2.0
// The stress harness: steps a World and checks after every step what numerical stability means
// here, recording the worst values for the CSV that docs/stability.md is generated from.
//
//  - finite: positions, velocities, contact impulses (per row and per node); a step that throws
//    Error(Numerical) is a failure too;
//  - energy: E = kinetic + elastic (co-rotational, as the model defines it) + gravity potential
//    of the dynamic bodies may not grow, over any interval of converged steps, by more than the
//    work of the drivers plus the documented penetration-recovery allowance (see Monitor);
//  - penetration: scenario-specific (a callback), bounded after the first step with an active
//    contact, on converged steps;
//  - contacts between bodies that claim a penetration must have their point inside the other
//    body; Body::contact_impulse must equal G^T lambda of the step;
//  - inverted elements: counted every step from the signed volumes of the current positions
//    (det F > 0 <=> signed volume > 0); after a release none may be left within a budget;
//  - convergence: steps whose stats().converged is false are counted and reported, never
//    failed; a step reported converged must be solved: its true residual A v - b - G^T lambda
//    (free directions) may not exceed 1000 times the tolerance relative to the terms it balances
//    (hidden non-convergence is a failure); what depends on a solved system (the energy identity, the contact conditions, the
//    recovery time) is measured on them and reported, and asserted on converged steps only.
//
// Core headers come before test_util.hpp: cmocka.h defines a fail() macro.
#pragma once
#include <algorithm>
#include <chrono>
#include <ctime>
#include <climits>
#include <cstdarg>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "collision/closest_point.hpp"
#include "devices/simulated_device.hpp"
#include "mesh/tet_mesh.hpp"
#include "world/world.hpp"

#include "test_util.hpp"

namespace stress {

using namespace mica;

inline std::string format(const char* fmt, ...) {
  char buf[1024];
  va_list args;
  va_start(args, fmt);
  vsnprintf(buf, sizeof buf, fmt, args);
  va_end(args);
  return buf;
}

inline const char* solver_name(SolverKind s) {
  return s == SolverKind::Mica ? "mica" : s == SolverKind::Direct ? "direct" : "pcg";
}

// ---------------------------------------------------------------- geometry of the current state

// Elements whose signed volume at the current positions is not positive (det F <= 0).
inline int count_inverted(const Body& b) {
  int n = 0;
  for (const Tet& t : b.tets)
    if (!(signed_volume(b.x[t[0]], b.x[t[1]], b.x[t[2]], b.x[t[3]]) > 0)) ++n;
  return n;
}

// Deepest intrusion of a sphere into a body's surface: r minus the distance from the centre to
// the nearest surface triangle (nodes, edges and face interiors alike). Triangles for which
// `exclude` is true are left out. 0 when the sphere is clear.
inline double sphere_penetration(const Body& b, const Vec3& c, double r,
                                 const std::function<bool(const Tri&)>& exclude = nullptr) {
  double deepest = 0;
  for (const Tri& t : b.surface) {
    if (exclude && exclude(t)) continue;
    const Vec3 p = closest_on_triangle(c, b.x[t[0]], b.x[t[1]], b.x[t[2]]).point;
    deepest = std::max(deepest, r - (c - p).norm());
  }
  return deepest;
}

// Deepest surface node inside a sphere (centre c, radius r): r - |x_i - c| over the surface nodes
// not excluded. Contact acts on the surface; an interior node can reach the tool only through
// inverted elements, which count_inverted reports.
inline double sphere_node_penetration(const Body& b, const Vec3& c, double r,
                                      const std::vector<uint8_t>* exclude = nullptr) {
  double deepest = 0;
  for (int32_t i : b.surface_node_list)
    if (!exclude || !(*exclude)[i]) deepest = std::max(deepest, r - (b.x[i] - c).norm());
  return deepest;
}

// Deepest node on the wrong side of a plane through p with unit normal n (the body's side is +n).
inline double plane_penetration(const Body& b, const Vec3& p, const Vec3& n) {
  double deepest = 0;
  for (const Vec3& x : b.x) deepest = std::max(deepest, -n.dot(x - p));
  return deepest;
}

inline bool point_in_tet(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double v = signed_volume(a, b, c, d);
  if (!(v > 0)) return false;  // an inverted element has no inside to speak of
  const double eps = -1e-12 * v;
  return signed_volume(p, b, c, d) > eps && signed_volume(a, p, c, d) > eps && signed_volume(a, b, p, d) > eps &&
         signed_volume(a, b, c, p) > eps;
}

// Deepest surface node of `a` inside the volume of `b` (current positions): its distance to the
// surface of b when it lies inside one of b's elements.
inline double body_penetration(const Body& a, const Body& b) {
  Vec3 lo = Vec3::Constant(HUGE_VAL), hi = Vec3::Constant(-HUGE_VAL);
  for (const Vec3& x : b.x) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  double deepest = 0;
  for (int32_t i : a.surface_node_list) {
    const Vec3& p = a.x[i];
    if ((p.array() < lo.array()).any() || (p.array() > hi.array()).any()) continue;
    bool inside = false;
    for (const Tet& t : b.tets)
      if (point_in_tet(p, b.x[t[0]], b.x[t[1]], b.x[t[2]], b.x[t[3]])) {
        inside = true;
        break;
      }
    if (!inside) continue;
    double d = HUGE_VAL;
    for (const Tri& t : b.surface) d = std::min(d, (p - closest_on_triangle(p, b.x[t[0]], b.x[t[1]], b.x[t[2]]).point).norm());
    deepest = std::max(deepest, d);
  }
  return deepest;
}

inline std::vector<int32_t> nodes_where(const Body& b, const std::function<bool(const Vec3&)>& pred) {
  std::vector<int32_t> out;
  for (int32_t i = 0; i < b.fem.node_count(); ++i)
    if (pred(b.fem.rest[i])) out.push_back(i);
  return out;
}

// ---------------------------------------------------------------- energy

struct Energy {
  double kinetic = 0, elastic = 0, potential = 0;  // J; potential = -sum m_i g . x_i
  double total() const { return kinetic + elastic + potential; }
};

inline Energy body_energy(const Body& b, const Vec3& g) {
  Energy e;
  e.kinetic = kinetic_energy(b.fem, b.v);
  e.elastic = elastic_energy(b.fem, b.x, b.settings.model);
  for (size_t i = 0; i < b.x.size(); ++i) e.potential -= b.fem.node_mass[i] * g.dot(b.x[i]);
  return e;
}

// ---------------------------------------------------------------- one run

struct Case {
  char scenario = '?';
  double E = 1e4, nu = 0.3, h = 1e-2;
  SolverKind solver = SolverKind::Mica;
  MicaSweep sweep = MicaSweep::GaussSeidel;  // MICA only
  double tol = 1e-6;
  int max_iter = 200;
  const char* solver_label() const {
    return solver == SolverKind::Mica && sweep == MicaSweep::Factored ? "mica-f" : solver_name(solver);
  }
  std::string label() const {
    return format("[%c E=%.0e nu=%g h=%g %s tol=%.0e cap=%d]", scenario, E, nu, h, solver_label(), tol, max_iter);
  }
};

struct Result {
  Case c;
  std::string scene;            // short description for the table
  int steps = 0;
  int nonconverged = 0;         // steps with stats().converged == false
  int hidden_nonconverged = 0;  // steps reported converged whose true residual says otherwise
  int64_t iterations = 0;       // summed solver iterations
  double energy_ratio = 0;      // worst growth beyond driving work + recovery over intervals of converged steps, / scale (asserted)
  double energy_ratio_all = 0;  // the same over any interval, non-converged steps included (reported only)
  double energy_ratio_solver = 0;  // the frozen-rotation balance alone over converged steps (see Monitor)
  double energy_limit = 0;      // the ratio asserted
  double recovery_ratio = 0;    // penetration-recovery allowance used, / energy scale
  double penetration = 0;       // m, deepest after the first contact step
  double penetration_nonconverged = 0;  // m, deepest after a non-converged step (bounded more loosely)
  double penetration_ref = 0;   // m, what it is measured against (tool radius, slab thickness)
  double penetration_limit = 0; // m, asserted
  int max_contacts = 0;         // active normal rows (lambda > 0) in one step
  int max_rows = 0;             // contact normal rows handed to the solver in one step
  int inverted_start = 0;       // inverted elements before the first step
  int max_inverted = 0;
  int recovery_steps = -1;      // steps after the release until no element is inverted; -1: n/a
  int recovery_budget = 0;
  double max_speed = 0;         // m/s, fastest node
  double max_impulse = 0;       // N s, largest row impulse
  double residual = 0;          // worst true relative residual of a step reported converged
  double cpu_s = 0;             // s of processor time (the machine is shared: wall time says little)
  std::vector<std::string> failures;
  std::string status = "ok";    // ok, FAIL, or known (every failure matches a known library issue)
  std::string notes;

  std::string phase = "run";     // the scenario's current phase, named in failure messages
  std::string after;            // appended to later failures once a step has gone wrong in a known way

  void failure(int step, const std::string& what) {
    if (failures.size() < 8)
      failures.push_back(c.label() + " step " + std::to_string(step) + " (" + phase + "): " + what + after);
  }
};

// The energy bound. With the step's linear system A v+ = M v + h (f(x) + f_ext) + G^T lambda + r
// (A = M + h C + h^2 K, r the projection impulse, nonzero only in the constrained directions),
// the discrete energy identity of (linearised) backward Euler is
//   dE = -(v+ - v)^T M (v+ - v)/2 - h^2 v+^T K v+/2 - h v+^T C v+  +  lambda^T G v+  +  r^T v+
// with E = kinetic + elastic + gravity potential (exact for the linear model, up to the frozen
// rotation's linearisation error for the co-rotational one, and up to the solver's residual).
// So E grows only through
//   W_drive = sum over tool rows  lambda_r d_r . u_r   (u_r: the tool's velocity at the point:
//             the work of the prescribed tool motion; 0 for a tool at rest)
//           + sum over constrained nodes  r_i . v+_i   (the work of prescribed velocities and
//             handle targets; 0 for fixed nodes)
// and through the body side of a contact row doing more work than the tool: lambda_r (-bias_r
// - d_r . u_r), positive only when the row pushes a point out of a penetration that existed at
// the start of the step, at most lambda_r * max_recovery_speed (mica-method.md section 2: the
// clamp of psi / h). That is the recovery allowance W_rec = sum lambda_r max(0, -bias_r - n.u_r).
// The check: for every interval [s, t] of converged steps,
//   E(t) - E(s) <= W_drive(s, t) + W_rec(s, t) + limit * S(t),
// S(t) = max (kinetic + elastic) so far + max |potential change| so far + sum |W_drive| so far,
// the energy scale of the run; `limit` absorbs round-off and the solver's tolerance. Checked as
// growth(t) = a(t) - min_{s <= t} a(s) with a = E - E(0) - W_drive - W_rec, the minimum taken
// anew after each non-converged step (the identity needs a solved system; such steps are
// counted and their energy growth reported as energy_ratio_all, not failed).
//
// The co-rotational step is linear in frozen rotations: it is backward Euler on the quadratic
// energy U_R(x) = sum_e 1/2 (R_e^T x - X)^T Ke (R_e^T x - X) with the rotations R_e of the step's
// start (Body::R), for which the identity is exact. The model's energy U(x+) uses the new
// rotations; the difference U(x+) - U_R(x+) is the energy of the rotation update, a property of
// the method (mica-method.md section 2), not of the solver. It is accumulated separately, so a
// failure says which part grew: "solver" (contacts, constraints, the solve: a bug) or "rotation
// update" (large rotation increments per step: the method's linearisation).
class Monitor {
 public:
  using Penetration = std::function<double()>;

  Monitor(World& world, std::vector<Id> bodies, Result& result, double energy_limit)
      : world_(world), bodies_(std::move(bodies)), r_(result) {
    r_.energy_limit = energy_limit;
    e0_ = energy();
    pe0_ = potential();
    // The smallest energy scale that means anything: the strain energy of a 1e-6 strain.
    for (Id id : bodies_) {
      const Body& b = world_.body(id);
      for (size_t q = 0; q < b.fem.elements.size(); ++q)
        floor_ += 1e-12 * b.fem.materials[q].youngs_modulus * b.fem.elements[q].volume;
    }
    for (Id id : bodies_) r_.inverted_start += count_inverted(world_.body(id));
    r_.max_inverted = r_.inverted_start;
    start_ = std::clock();
  }

  // Penetration after a converged step must stay below `limit`. After a non-converged step the
  // contact problem was only partly solved: its penetration is recorded (penetration_nonconverged)
  // and reported, not failed, like the non-convergence itself.
  void set_penetration(Penetration p, double ref, double limit) {
    penetration_ = std::move(p);
    r_.penetration_ref = ref;
    r_.penetration_limit = limit;
  }
  void phase(const char* name) { r_.phase = name; }
  // Inverted elements must be gone within `budget` steps from now (call at the release).
  void expect_recovery(int budget) {
    recovery_from_ = r_.steps;
    r_.recovery_budget = budget;
    r_.recovery_steps = count_all_inverted() == 0 ? 0 : -2;
  }
  // An interval with no driving starts now: its energy may not grow (the general check covers
  // it; this is kept for the record).
  int steps() const { return r_.steps; }
  bool ok() const { return r_.failures.empty(); }

  // One step; false once the run should stop (a step threw or results are not finite).
  bool step(double h) {
    const int k = r_.steps;
    before_.clear();
    world_.for_each_body([&](Id id, const Body& b) { before_.emplace_back(id, b.x); });
    try {
      world_.step(h);
    } catch (const std::exception& e) {
      r_.failure(k, std::string("step threw: ") + e.what());
      return false;
    }
    r_.steps += 1;
    const WorldStats& st = world_.stats();
    r_.iterations += st.solver_iterations;
    if (!st.converged) r_.nonconverged += 1;
    if (!check_finite(k)) return false;
    account_work(h);
    // A step counts as solved when the solver says so and its true residual agrees; one that
    // claims convergence with a large residual is a failure (hidden non-convergence), and like
    // a reported one it does not take part in the checks that need a solved system.
    bool solved = st.converged;
    if (st.converged) {
      r_.residual = std::max(r_.residual, step_residual);
      if (!(step_residual <= 1e3 * world_.settings().tolerance)) {
        solved = false;
        r_.hidden_nonconverged += 1;
        if (r_.hidden_nonconverged <= 2)
          r_.failure(k, format("the step reported converged (%d iterations, residual %.3g) but its true relative "
                               "residual |A v - b - G^T lambda| / |A v, b, G^T lambda| is %.3g (tolerance %.0e): hidden "
                               "non-convergence",
                               st.solver_iterations, st.solver_residual, step_residual, world_.settings().tolerance));
      }
    }
    if (!solved && r_.recovery_budget > 0) nonconverged_since_release_ += 1;
    check_energy(k, solved);
    check_body_contacts(k);
    int inverted = count_all_inverted();
    r_.max_inverted = std::max(r_.max_inverted, inverted);
    if (r_.recovery_steps == -2 && inverted == 0) r_.recovery_steps = r_.steps - recovery_from_;
    if (penetration_) {
      if (contact_seen_) {
        const double p = penetration_();
        if (solved)
          r_.penetration = std::max(r_.penetration, p);
        else
          r_.penetration_nonconverged = std::max(r_.penetration_nonconverged, p);
        if (!std::isfinite(p) || (solved && !(p <= r_.penetration_limit) && penetration_failures_++ < 2))
          r_.failure(k, format("penetration %.3g m > limit %.3g m (%.2f of %.3g m)", p, r_.penetration_limit,
                               p / r_.penetration_ref, r_.penetration_ref));
      }
      if (active_rows_ > 0) contact_seen_ = true;
    }
    return true;
  }

  // The recovery budget is physical time (wave crossings): it binds only when the solver
  // converged on every step after the release; otherwise the count is reported, not failed.
  void finish() {
    const bool late = r_.recovery_steps == -2 || r_.recovery_steps > r_.recovery_budget;
    if (r_.recovery_budget > 0 && late && nonconverged_since_release_ == 0)
      r_.failure(r_.steps, format("%d elements still inverted %d steps after the release (budget %d)",
                                  count_all_inverted(), r_.steps - recovery_from_, r_.recovery_budget));
    if (r_.recovery_budget > 0 && late && nonconverged_since_release_ > 0)
      r_.notes += format(" %d elements still inverted %d steps after the release (%d of them not converged);",
                         count_all_inverted(), r_.steps - recovery_from_, nonconverged_since_release_);
    r_.cpu_s = double(std::clock() - start_) / CLOCKS_PER_SEC;
  }

  // Largest |Body::contact_impulse - G^T lambda| seen (N s): 0 unless the library leaves a stale value.
  double contact_impulse_mismatch() const { return contact_impulse_mismatch_; }

  double energy() const {
    double e = 0;
    for (Id id : bodies_) e += body_energy(world_.body(id), world_.settings().gravity).total();
    return e;
  }
  int active_rows() const { return active_rows_; }

 private:
  double potential() const {
    double e = 0;
    for (Id id : bodies_) e += body_energy(world_.body(id), world_.settings().gravity).potential;
    return e;
  }
  int count_all_inverted() const {
    int n = 0;
    for (Id id : bodies_) n += count_inverted(world_.body(id));
    return n;
  }

  bool check_finite(int k) {
    for (Id id : bodies_) {
      const Body& b = world_.body(id);
      if (!flat(b.x).allFinite() || !flat(b.v).allFinite() || !flat(b.contact_impulse).allFinite()) {
        r_.failure(k, b.name + ": non-finite positions, velocities or contact impulses");
        return false;
      }
      for (const Vec3& v : b.v) r_.max_speed = std::max(r_.max_speed, v.norm());
    }
    for (double l : world_.impulses()) {
      if (!std::isfinite(l)) {
        r_.failure(k, "non-finite contact impulse");
        return false;
      }
      r_.max_impulse = std::max(r_.max_impulse, std::fabs(l));
    }
    return true;
  }

  // Work of the drivers in the step just taken, and the recovery allowance.
  void account_work(double h) {
    (void)h;
    const ContactRows& rows = world_.contact_rows();
    const std::vector<double>& lambda = world_.impulses();
    const std::vector<Contact>& contacts = world_.contacts();
    // G^T lambda per node, from the rows (a row's body is its index among the step's dynamic
    // bodies, in the world's order), to check against Body::contact_impulse.
    std::vector<Id> dynamic;
    world_.for_each_body([&](Id id, const Body& b) {
      if (b.is_dynamic()) dynamic.push_back(id);
    });
    std::vector<Vec3List> impulse(dynamic.size());
    for (size_t k = 0; k < dynamic.size(); ++k) impulse[k].assign(world_.body(dynamic[k]).x.size(), Vec3::Zero());
    for (size_t r = 0; r < rows.size() && r < lambda.size(); ++r)
      for (int32_t t = rows.start[r]; t < rows.start[r + 1]; ++t)
        impulse[rows.terms[t].body][rows.terms[t].node] += rows.terms[t].coef * lambda[r] * rows.direction[r];
    double w = 0, rec = 0;
    step_residual = 0;
    for (size_t k = 0; k < dynamic.size(); ++k) {
      const Body& b = world_.body(dynamic[k]);
      double scale = 0, diff = 0;
      for (size_t i = 0; i < b.x.size(); ++i) {
        scale = std::max(scale, impulse[k][i].norm());
        diff = std::max(diff, (impulse[k][i] - b.contact_impulse[i]).norm());
      }
      if (diff > 1e-9 * scale + 1e-300) {
        if (contact_impulse_mismatch_ == 0)
          r_.failure(r_.steps - 1, format("%s: Body::contact_impulse differs from G^T lambda of the step by %.3g N s "
                                          "(%zu contact rows this step): a stale value",
                                          b.name.c_str(), diff, rows.size()));
        contact_impulse_mismatch_ = std::max(contact_impulse_mismatch_, diff);
      }
      // Projection impulses r_i = (I - S_i)(A v+ - b - G^T lambda)_i on the constrained nodes, and
      // the residual S_i (A v+ - b - G^T lambda)_i everywhere, relative to the size of the terms
      // it balances (A v, b, G^T lambda; floor: the momentum of 1 um/s per node). Not D^-1 r: a stalled
      // Gauss-Seidel leaves smooth residuals that D^-1 makes look small, which is how the
      // solver's own test misses them.
      if (std::find(bodies_.begin(), bodies_.end(), dynamic[k]) == bodies_.end()) continue;
      const Projection& P = b.projection;
      const bool constrained = P.active() && P.is_constrained.size() == b.x.size();
      double res2 = 0, scale2 = 0;
      for (int32_t i = 0; i < b.fem.node_count(); ++i) {
        Vec3 Av = Vec3::Zero();
        for (int32_t q = b.fem.pattern.row_start[i]; q < b.fem.pattern.row_start[i + 1]; ++q)
          Av += b.A[q] * b.v[b.fem.pattern.col[q]];
        const Vec3 r = Av - b.b[i] - impulse[k][i];
        if (constrained && P.is_constrained[i]) {
          w += ((Mat3::Identity() - P.S[i]) * r).dot(b.v[i]);
          res2 += (P.S[i] * r).squaredNorm();
        } else {
          res2 += r.squaredNorm();
        }
        const double floor = 1e-6 * b.fem.node_mass[i];
        scale2 += std::max({b.b[i].squaredNorm(), impulse[k][i].squaredNorm(), Av.squaredNorm(), floor * floor});
      }
      step_residual = std::max(step_residual, std::sqrt(res2 / scale2));
    }
    // Contact rows: the tool's work, and the body side's excess (recovery).
    active_rows_ = 0;
    int normal_rows = 0;
    for (size_t r = 0; r < rows.size() && r < lambda.size(); ++r) {
      const Contact& c = contacts[rows.contact[r]];
      const Vec3 u = c.tool >= 0 ? c.other_velocity : Vec3::Zero();
      w += lambda[r] * rows.direction[r].dot(u);
      if (rows.normal_of[r] < 0) {
        ++normal_rows;
        if (lambda[r] > 0) ++active_rows_;
        rec += lambda[r] * std::max(0.0, -rows.bias[r] - rows.direction[r].dot(u));
      }
    }
    r_.max_contacts = std::max(r_.max_contacts, active_rows_);
    r_.max_rows = std::max(r_.max_rows, normal_rows);
    work_ += w;
    abs_work_ += std::fabs(w);
    recovery_ += rec;
  }

  void check_energy(int k, bool converged) {
    double kin_el = 0, pe = 0, e = 0;
    for (Id id : bodies_) {
      const Body& b = world_.body(id);
      const Energy en = body_energy(b, world_.settings().gravity);
      kin_el += en.kinetic + en.elastic;
      pe += en.potential;
      e += en.total();
      if (b.settings.corotational()) {
        double frozen = 0;
        for (size_t q = 0; q < b.fem.elements.size(); ++q) {
          const TetElement& el = b.fem.elements[q];
          frozen += elastic_energy(el, b.fem.lame[q], b.rotations()[q], deformation_gradient(el, b.x));
        }
        rotation_update_ += en.elastic - frozen;
      }
    }
    if (!std::isfinite(e)) {
      r_.failure(k, "non-finite energy");
      return;
    }
    max_kin_el_ = std::max(max_kin_el_, kin_el);
    max_dpe_ = std::max(max_dpe_, std::fabs(pe - pe0_));
    const double scale = std::max(max_kin_el_ + max_dpe_ + abs_work_, floor_);
    const double a = e - e0_ - work_ - recovery_;
    const double a_solver = a - rotation_update_;  // the frozen-rotation energy's balance
    min_a_all_ = std::min(min_a_all_, a);
    r_.energy_ratio_all = std::max(r_.energy_ratio_all, (a - min_a_all_) / scale);
    r_.recovery_ratio = std::max(r_.recovery_ratio, recovery_ / scale);
    // The identity holds only for a solved step: a non-converged one starts a new interval.
    if (!converged) {
      min_a_ = a;
      min_a_solver_ = a_solver;
      return;
    }
    min_a_ = std::min(min_a_, a);
    min_a_solver_ = std::min(min_a_solver_, a_solver);
    const double ratio = (a - min_a_) / scale, solver_ratio = (a_solver - min_a_solver_) / scale;
    r_.energy_ratio = std::max(r_.energy_ratio, ratio);
    r_.energy_ratio_solver = std::max(r_.energy_ratio_solver, solver_ratio);
    if (!(ratio <= r_.energy_limit) && !energy_failed_) {
      energy_failed_ = true;  // report the first time only; the ratio keeps its maximum
      const bool solver = !(solver_ratio <= r_.energy_limit);
      r_.failure(k, format("energy grew by %.3g J beyond the driving work over converged steps (%.3g of the energy "
                           "scale %.3g J; E = %.6g J, E0 = %.6g J, W = %.3g J, W_rec = %.3g J); %s: the frozen-rotation "
                           "balance grew %.3g of the scale, the rotation updates added %.3g J in all",
                           a - min_a_, ratio, scale, e, e0_, work_, recovery_,
                           solver ? "energy [solver]" : "energy [rotation update]", solver_ratio, rotation_update_));
    }
  }

  // Contacts between bodies that report a penetration (gap < 0) must have their point inside
  // the other body (checked on the positions the contact was found on: the step's start).
  void check_body_contacts(int k) {
    std::vector<Id> dynamic;
    world_.for_each_body([&](Id id, const Body& b) {
      if (b.is_dynamic()) dynamic.push_back(id);
    });
    for (const Contact& c : world_.contacts()) {
      if (c.tool >= 0 || !(c.gap < -1e-4) || c.a.count != 1) continue;
      const Id a = dynamic[c.a.body];
      const auto own = std::find_if(before_.begin(), before_.end(), [&](const auto& e) { return e.first == a; });
      const Vec3& p = own->second[c.a.nodes[0]];
      bool inside = false;
      for (const auto& [id, x] : before_) {
        if (id == a) continue;
        for (const Tet& t : world_.body(id).tets)
          if (point_in_tet(p, x[t[0]], x[t[1]], x[t[2]], x[t[3]])) {
            inside = true;
            break;
          }
        if (inside) break;
      }
      if (!inside && false_contacts_++ == 0) {
        r_.failure(k, format("a contact reports node %d of %s at (%.4g, %.4g, %.4g) %.3g m deep in another body, "
                             "but it lies outside every other body (normal (%.2f, %.2f, %.2f))",
                             c.a.nodes[0], world_.body(a).name.c_str(), p.x(), p.y(), p.z(), -c.gap, c.normal.x(),
                             c.normal.y(), c.normal.z()));
        // What follows is pushed by a contact that should not exist: later failures say so.
        r_.after = " [after a false body contact]";
      }
    }
  }

  World& world_;
  std::vector<Id> bodies_;
  Result& r_;
  Penetration penetration_;
  bool contact_seen_ = false;
  int active_rows_ = 0;
  int recovery_from_ = 0;
  double e0_ = 0, pe0_ = 0;
  double work_ = 0, abs_work_ = 0, recovery_ = 0;
  double max_kin_el_ = 0, max_dpe_ = 0, min_a_ = 0, min_a_all_ = 0, min_a_solver_ = 0, floor_ = 0;
  double rotation_update_ = 0;  // J, sum of U(x+) - U_R(x+) over the steps
  std::vector<std::pair<Id, Vec3List>> before_;  // every body's positions at the start of the step
  int false_contacts_ = 0;
  int penetration_failures_ = 0;
  double step_residual = 0;     // this step's true relative residual (see account_work)
  int nonconverged_since_release_ = 0;
  bool energy_failed_ = false;
  double contact_impulse_mismatch_ = 0;
  std::clock_t start_;
};

// Steps of a phase lasting `seconds`, kept within [lo, hi].
inline int phase_steps(double seconds, double h, int lo, int hi) {
  const double n = std::ceil(seconds / h - 1e-9);
  return int(std::clamp(n, double(lo), double(hi)));
}

// ---------------------------------------------------------------- the CSV

inline const char* kCsvHeader =
    "scenario,scene,solver,E,nu,h,tol,max_iter,steps,nonconverged,hidden_nonconverged,iterations_per_step,energy_ratio,energy_ratio_all,"
    "energy_ratio_solver,residual,"
    "energy_limit,recovery_ratio,penetration,penetration_nonconverged,penetration_ref,penetration_limit,max_contacts,max_rows,"
    "inverted_start,max_inverted,"
    "recovery_steps,recovery_budget,max_speed,max_impulse,cpu_s,status,notes\n";

class Csv {
 public:
  void open(const std::string& path) {
    if (path.empty()) return;
    f_ = std::fopen(path.c_str(), "w");
    if (!f_) {
      std::fprintf(stderr, "stress: cannot write %s\n", path.c_str());
      return;
    }
    std::fputs(kCsvHeader, f_);
    std::fflush(f_);
  }
  ~Csv() {
    if (f_) std::fclose(f_);
  }
  void write(const Result& r) {
    if (!f_) return;
    auto quote = [](std::string t) {
      for (char& ch : t)
        if (ch == '"' || ch == '\n') ch = '\'';
      return '"' + t + '"';
    };
    const std::string scene = quote(r.scene), notes = quote(r.notes);
    std::fprintf(f_, "%c,%s,%s,%.3g,%g,%g,%.0e,%d,%d,%d,%d,%.1f,%.4g,%.4g,%.4g,%.3g,%.3g,%.4g,%.4g,%.4g,%.4g,%.4g,%d,%d,%d,%d,%d,%d,%.4g,%.4g,%.3f,%s,%s\n",
                 r.c.scenario, scene.c_str(), r.c.solver_label(), r.c.E, r.c.nu, r.c.h, r.c.tol, r.c.max_iter,
                 r.steps, r.nonconverged, r.hidden_nonconverged, r.steps ? double(r.iterations) / r.steps : 0.0, r.energy_ratio,
                 r.energy_ratio_all, r.energy_ratio_solver, r.residual, r.energy_limit, r.recovery_ratio, r.penetration, r.penetration_nonconverged, r.penetration_ref,
                 r.penetration_limit, r.max_contacts, r.max_rows, r.inverted_start, r.max_inverted, r.recovery_steps, r.recovery_budget, r.max_speed,
                 r.max_impulse, r.cpu_s, r.status.c_str(), notes.c_str());
    std::fflush(f_);
  }

 private:
  std::FILE* f_ = nullptr;
};

}  // namespace stress
