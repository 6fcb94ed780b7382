// The stress harness: steps a World and checks after every step what numerical stability means
// here, recording the worst values for the CSV that docs/stability.md is generated from.
//
//  - finite: positions, velocities, contact impulses (per row and per node), tool forces, LPC
//    reactions; a step that throws Error(Numerical) counts as a failure too;
//  - energy: E = kinetic + elastic (co-rotational, as the model defines it) + gravity potential
//    of every dynamic body must not grow, over ANY interval of the run, by more than the work
//    the drivers did plus the documented penetration-recovery allowance (see EnergyBound below);
//  - penetration: scenario-specific (a callback), bounded after the first step with an active
//    contact;
//  - inverted elements: counted every step from the signed volumes of the current positions
//    (det F > 0 <=> signed volume > 0); scenarios with a release phase assert that none is left
//    within a budget of steps after the release;
//  - convergence: steps whose stats().converged is false are counted and reported, never failed.
//
// Core headers come before test_util.hpp: cmocka.h defines a fail() macro.
#pragma once
#include <chrono>
#include <climits>
#include <cstdarg>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <string>
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
// `skip` is true are left out. 0 when the sphere is clear.
inline double sphere_penetration(const Body& b, const Vec3& c, double r,
                                 const std::function<bool(const Tri&)>& skip = nullptr) {
  double deepest = 0;
  for (const Tri& t : b.surface) {
    if (skip && skip(t)) continue;
    const Vec3 p = closest_on_triangle(c, b.x[t[0]], b.x[t[1]], b.x[t[2]]).point;
    deepest = std::max(deepest, r - (c - p).norm());
  }
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
  e.elastic = elastic_energy(b.fem, b.x, b.settings.corotational);
  for (size_t i = 0; i < b.x.size(); ++i) e.potential -= b.fem.node_mass[i] * g.dot(b.x[i]);
  return e;
}

// ---------------------------------------------------------------- one run

struct Case {
  char scenario = '?';
  double E = 1e4, nu = 0.3, h = 1e-2;
  SolverKind solver = SolverKind::Mica;
  double tol = 1e-6;
  int max_iter = 200;
  std::string label() const {
    return format("[%c E=%.0e nu=%g h=%g %s tol=%.0e cap=%d]", scenario, E, nu, h, solver_name(solver), tol, max_iter);
  }
};

struct Result {
  Case c;
  std::string scene;            // short description for the table
  int steps = 0;
  int nonconverged = 0;         // steps with stats().converged == false
  int64_t iterations = 0;       // summed solver iterations
  double energy_ratio = 0;      // worst interval growth beyond driving work + recovery, / energy scale
  double energy_limit = 0;      // the ratio asserted
  double recovery_ratio = 0;    // penetration-recovery allowance used, / energy scale
  double penetration = 0;       // m, deepest after the first contact step
  double penetration_ref = 0;   // m, what it is measured against (tool radius, slab thickness)
  double penetration_limit = 0; // m, asserted
  int max_contacts = 0;         // active normal rows (lambda > 0) in one step
  int inverted_start = 0;       // inverted elements before the first step
  int max_inverted = 0;
  int recovery_steps = -1;      // steps after the release until no element is inverted; -1: n/a
  int recovery_budget = 0;
  double max_speed = 0;         // m/s, fastest node
  double max_impulse = 0;       // N s, largest row impulse
  double wall_s = 0;
  std::vector<std::string> failures;
  std::string notes;

  void failure(int step, const std::string& what) {
    if (failures.size() < 8) failures.push_back(c.label() + " step " + std::to_string(step) + ": " + what);
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
// The check: for every interval [s, t] of the run,
//   E(t) - E(s) <= W_drive(s, t) + W_rec(s, t) + limit * S(t),
// S(t) = max (kinetic + elastic) so far + max |potential change| so far + sum |W_drive| so far,
// the energy scale of the run; `limit` absorbs round-off, the solver's tolerance and the
// co-rotational linearisation. Checked as growth(t) = a(t) - min_{s <= t} a(s) with
// a = E - E(0) - W_drive - W_rec.
class Monitor {
 public:
  using Penetration = std::function<double()>;

  Monitor(World& world, std::vector<Id> bodies, Result& result, double energy_limit)
      : world_(world), bodies_(std::move(bodies)), r_(result) {
    r_.energy_limit = energy_limit;
    e0_ = energy();
    pe0_ = potential();
    for (Id id : bodies_) r_.inverted_start += count_inverted(world_.body(id));
    r_.max_inverted = r_.inverted_start;
    start_ = std::chrono::steady_clock::now();
  }

  void set_penetration(Penetration p, double ref, double limit) {
    penetration_ = std::move(p);
    r_.penetration_ref = ref;
    r_.penetration_limit = limit;
  }
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
    check_energy(k);
    int inverted = count_all_inverted();
    r_.max_inverted = std::max(r_.max_inverted, inverted);
    if (r_.recovery_steps == -2 && inverted == 0) r_.recovery_steps = r_.steps - recovery_from_;
    if (penetration_) {
      if (contact_seen_) {
        const double p = penetration_();
        r_.penetration = std::max(r_.penetration, p);
        if (!(p <= r_.penetration_limit))
          r_.failure(k, format("penetration %.3g m > limit %.3g m (%.2f of %.3g m)", p, r_.penetration_limit,
                               p / r_.penetration_ref, r_.penetration_ref));
      }
      if (active_rows_ > 0) contact_seen_ = true;
    }
    return true;
  }

  // Call at the end: checks the recovery budget, stamps the wall time.
  void finish() {
    if (r_.recovery_budget > 0 && (r_.recovery_steps == -2 || r_.recovery_steps > r_.recovery_budget))
      r_.failure(r_.steps, format("%d elements still inverted %d steps after the release (budget %d)",
                                  count_all_inverted(), r_.steps - recovery_from_, r_.recovery_budget));
    r_.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

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
    double w = 0, rec = 0;
    // Projection impulses r_i = (I - S_i)(A v+ - b - G^T lambda)_i on the constrained nodes.
    for (Id id : bodies_) {
      const Body& b = world_.body(id);
      const Projection& P = b.projection;
      for (int32_t i : P.nodes) {
        Vec3 Av = Vec3::Zero();
        for (int32_t k = b.fem.pattern.row_start[i]; k < b.fem.pattern.row_start[i + 1]; ++k)
          Av += b.A[k] * b.v[b.fem.pattern.col[k]];
        const Vec3 r = (Mat3::Identity() - P.S[i]) * (Av - b.b[i] - b.contact_impulse[i]);
        w += r.dot(b.v[i]);
      }
    }
    // Contact rows: the tool's work, and the body side's excess (recovery).
    const ContactRows& rows = world_.contact_rows();
    const std::vector<double>& lambda = world_.impulses();
    const std::vector<Contact>& contacts = world_.contacts();
    active_rows_ = 0;
    for (size_t r = 0; r < rows.size() && r < lambda.size(); ++r) {
      const Contact& c = contacts[rows.contact[r]];
      const Vec3 u = c.tool >= 0 ? c.other_velocity : Vec3::Zero();
      w += lambda[r] * rows.direction[r].dot(u);
      if (rows.normal_of[r] < 0) {
        if (lambda[r] > 0) ++active_rows_;
        rec += lambda[r] * std::max(0.0, -rows.bias[r] - rows.direction[r].dot(u));
      }
    }
    r_.max_contacts = std::max(r_.max_contacts, active_rows_);
    work_ += w;
    abs_work_ += std::fabs(w);
    recovery_ += rec;
  }

  void check_energy(int k) {
    double kin_el = 0, pe = 0, e = 0;
    for (Id id : bodies_) {
      const Energy en = body_energy(world_.body(id), world_.settings().gravity);
      kin_el += en.kinetic + en.elastic;
      pe += en.potential;
      e += en.total();
    }
    if (!std::isfinite(e)) {
      r_.failure(k, "non-finite energy");
      return;
    }
    max_kin_el_ = std::max(max_kin_el_, kin_el);
    max_dpe_ = std::max(max_dpe_, std::fabs(pe - pe0_));
    const double scale = std::max(max_kin_el_ + max_dpe_ + abs_work_, 1e-300);
    const double a = e - e0_ - work_ - recovery_;
    min_a_ = std::min(min_a_, a);
    const double ratio = (a - min_a_) / scale;
    r_.energy_ratio = std::max(r_.energy_ratio, ratio);
    r_.recovery_ratio = std::max(r_.recovery_ratio, recovery_ / scale);
    if (!(ratio <= r_.energy_limit) && !energy_failed_) {
      energy_failed_ = true;  // report the first time only; the ratio keeps its maximum
      r_.failure(k, format("energy grew by %.3g J beyond the driving work (%.3g of the energy scale %.3g J; "
                           "E = %.6g J, E0 = %.6g J, W = %.3g J, W_rec = %.3g J)",
                           a - min_a_, ratio, scale, e, e0_, work_, recovery_));
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
  double max_kin_el_ = 0, max_dpe_ = 0, min_a_ = 0;
  bool energy_failed_ = false;
  std::chrono::steady_clock::time_point start_;
};

// Steps of a phase lasting `seconds`, kept within [lo, hi].
inline int phase_steps(double seconds, double h, int lo, int hi) {
  const double n = std::ceil(seconds / h - 1e-9);
  return int(std::clamp(n, double(lo), double(hi)));
}

// ---------------------------------------------------------------- the CSV

inline const char* kCsvHeader =
    "scenario,scene,solver,E,nu,h,tol,max_iter,steps,nonconverged,iterations_per_step,energy_ratio,energy_limit,"
    "recovery_ratio,penetration,penetration_ref,penetration_limit,max_contacts,inverted_start,max_inverted,"
    "recovery_steps,recovery_budget,max_speed,max_impulse,wall_s,status,notes\n";

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
    std::string notes = r.notes;
    for (char& ch : notes)
      if (ch == ',' || ch == '\n') ch = ';';
    std::fprintf(f_, "%c,%s,%s,%.3g,%g,%g,%.0e,%d,%d,%d,%.1f,%.4g,%.3g,%.4g,%.4g,%.4g,%.4g,%d,%d,%d,%d,%d,%.4g,%.4g,%.3f,%s,%s\n",
                 r.c.scenario, r.scene.c_str(), solver_name(r.c.solver), r.c.E, r.c.nu, r.c.h, r.c.tol, r.c.max_iter,
                 r.steps, r.nonconverged, r.steps ? double(r.iterations) / r.steps : 0.0, r.energy_ratio,
                 r.energy_limit, r.recovery_ratio, r.penetration, r.penetration_ref, r.penetration_limit,
                 r.max_contacts, r.inverted_start, r.max_inverted, r.recovery_steps, r.recovery_budget, r.max_speed,
                 r.max_impulse, r.wall_s, r.failures.empty() ? "ok" : "FAIL", notes.c_str());
    std::fflush(f_);
  }

 private:
  std::FILE* f_ = nullptr;
};

}  // namespace stress
