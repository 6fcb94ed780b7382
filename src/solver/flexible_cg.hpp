// SPDX-License-Identifier: Apache-2.0
// The conjugate-gradient recurrence of the projected solves, on one body's velocities (Vec3List:
// PcgSolver) or on every body's of a solve at once (BodyVectors: the factored sweep's solve with
// its contact rows held as equalities, factored_mica_active_set.cpp). The search directions take
// Polak-Ribiere's beta, (r_k.z_k - r_k.z_k-1) / r_k-1.z_k-1 (flexible CG, Notay 2000): the same as
// Fletcher-Reeves' r_k.z_k / r_k-1.z_k-1 for a fixed linear preconditioner, and not stalled by one
// that rounds. A single-precision factor is not quite the same linear map at every step, and
// Fletcher-Reeves' beta then stalled near float's precision (1.2e-7 on test_friction_physics).
#pragma once
#include <utility>
#include <vector>

#include "core/types.hpp"

namespace mica {

// One Vec3List per body of a solve.
using BodyVectors = std::vector<Vec3List>;

// a.b of the flat 3n entries (Eigen's dot).
inline double dot(const Vec3List& a, const Vec3List& b) { return flat(a).dot(flat(b)); }
// The bodies' dots, added in body order.
inline double dot(const BodyVectors& a, const BodyVectors& b) {
  double s = 0;
  for (size_t k = 0; k < a.size(); ++k) s += dot(a[k], b[k]);
  return s;
}

// r.z and r.z_last (0 on the first step, which has no last z). The order of the sums is part of
// the results, which replays compare bit for bit: one body's are two dots, several bodies' one
// pass over their nodes.
inline std::pair<double, double> residual_dots(const Vec3List& r, const Vec3List& z, const Vec3List& z_last,
                                               bool first) {
  return {dot(r, z), first ? 0.0 : dot(r, z_last)};
}
inline std::pair<double, double> residual_dots(const BodyVectors& r, const BodyVectors& z, const BodyVectors& z_last,
                                               bool first) {
  double rz = 0, rz_last = 0;
  for (size_t k = 0; k < r.size(); ++k)
    for (size_t i = 0; i < r[k].size(); ++i) {
      rz += r[k][i].dot(z[k][i]);
      if (!first) rz_last += r[k][i].dot(z_last[k][i]);
    }
  return {rz, rz_last};
}

// p = z + beta p.
inline void next_direction(Vec3List& p, const Vec3List& z, double beta) {
  for (size_t i = 0; i < p.size(); ++i) p[i] = z[i] + beta * p[i];
}
inline void next_direction(BodyVectors& p, const BodyVectors& z, double beta) {
  for (size_t k = 0; k < p.size(); ++k) next_direction(p[k], z[k], beta);
}

// y += alpha p, r -= alpha q.
inline void move_along(Vec3List& y, Vec3List& r, const Vec3List& p, const Vec3List& q, double alpha) {
  for (size_t i = 0; i < y.size(); ++i) {
    y[i] += alpha * p[i];
    r[i] -= alpha * q[i];
  }
}
inline void move_along(BodyVectors& y, BodyVectors& r, const BodyVectors& p, const BodyVectors& q, double alpha) {
  for (size_t k = 0; k < y.size(); ++k) move_along(y[k], r[k], p[k], q[k], alpha);
}

// The recurrence's vectors and state for A y = b, sized by the caller. A solve calls start(),
// keeps r = b - A y, and before each step() writes z = M^-1 r, every entry of it (the last z is
// swapped out, not copied).
template <class Field>
struct FlexibleCg {
  Field r, z, p, q;  // the residual, its preconditioned z, the search direction, A p
  Field z_last;      // the last step's z

  void start() { first_ = true; }
  // The search direction from z, q = A p by apply(p, q), then y += alpha p and r -= alpha q.
  // False at a breakdown (p.A p not positive: A is not positive definite where p points), with y
  // and r as they were.
  template <class Apply>
  bool step(Field& y, Apply&& apply) {
    const auto [rz, rz_last] = residual_dots(r, z, z_last, first_);
    if (first_) p = z;
    else next_direction(p, z, (rz - rz_last) / rz_);
    first_ = false;
    rz_ = rz;
    z_last.swap(z);
    apply(static_cast<const Field&>(p), q);
    const double pq = dot(p, q);
    if (!(pq > 0)) return false;
    move_along(y, r, p, q, rz_ / pq);
    return true;
  }

 private:
  double rz_ = 0;  // r.z of the last step
  bool first_ = true;
};

}  // namespace mica
