// SPDX-License-Identifier: Apache-2.0
#include "solver/friction_cone.hpp"

#include <algorithm>

namespace mica {

namespace {

// l(beta) = -(W + beta E_t)^-1 q; a 3x3 symmetric positive definite solve.
Vec3 sliding_impulse(const Mat3& W, const Vec3& q, double beta) {
  Mat3 K = W;
  K(1, 1) += beta;
  K(2, 2) += beta;
  return -K.ldlt().solve(q);
}

double cone_excess(const Vec3& l, double mu) { return std::hypot(l(1), l(2)) - mu * l(0); }

}  // namespace

Vec3 solve_contact_coulomb(const Mat3& W, const Vec3& q, double mu) {
  if (q(0) >= 0) return Vec3::Zero();  // separating: no impulse needed
  if (!(mu > 0)) return Vec3(-q(0) / W(0, 0), 0, 0);
  const Vec3 stick = -W.ldlt().solve(q);
  if (stick(0) > 0 && cone_excess(stick, mu) <= 0) return stick;

  // Sliding: bracket the root of f(beta) = cone_excess(l(beta)), then Illinois false position
  // (superlinear, and it keeps the bracket, so it cannot wander to beta < 0).
  double lo = 0, f_lo = cone_excess(stick, mu);
  double hi = std::max({W(1, 1), W(2, 2), 1e-300}), f_hi = cone_excess(sliding_impulse(W, q, hi), mu);
  for (int k = 0; k < 2000 && f_hi > 0; ++k) {  // f(inf) < 0: ends within a few hundred doublings
    lo = hi;
    f_lo = f_hi;
    hi *= 2;
    f_hi = cone_excess(sliding_impulse(W, q, hi), mu);
  }
  int side = 0;  // which end stayed put last time (Illinois halves its value)
  for (int k = 0; k < 200 && f_hi < 0 && f_lo > 0 && hi - lo > 4e-16 * hi; ++k) {
    double beta = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
    if (!(beta > lo && beta < hi)) beta = 0.5 * (lo + hi);
    const double f = cone_excess(sliding_impulse(W, q, beta), mu);
    if (f > 0) {
      lo = beta;
      f_lo = f;
      if (side == -1) f_hi *= 0.5;
      side = -1;
    } else if (f < 0) {
      hi = beta;
      f_hi = f;
      if (side == 1) f_lo *= 0.5;
      side = 1;
    } else {
      lo = hi = beta;
    }
  }
  Vec3 l = sliding_impulse(W, q, hi);
  l(0) = std::max(l(0), 0.0);
  // Onto the rim exactly: at the root |l_t| = mu l_n up to the bracket's round-off.
  const double norm = std::hypot(l(1), l(2));
  if (norm > 0) l.tail<2>() *= mu * l(0) / norm;
  return l;
}

}  // namespace mica
