// SPDX-License-Identifier: Apache-2.0
// The isotropic Coulomb cone of one contact, shared by every contact solver: an impulse
// (l_n, l_t1, l_t2) on a normal and two orthonormal tangents is admissible when
//     l_n >= 0   and   |(l_t1, l_t2)| <= mu l_n.
// Bounding each tangent row on its own (a box) would allow mu sqrt(2) l_n along a diagonal.
#pragma once
#include <cmath>

#include "core/types.hpp"

namespace mica {

// The tangent pair onto the disk of `radius` (radius <= 0: the origin): scaled down radially,
// its direction kept, when outside; unchanged inside. Not the Euclidean projection onto the 3-D
// cone: the normal impulse is the solvers' to set, the disk follows it.
inline void project_onto_disk(double radius, double& t1, double& t2) {
  if (!(radius > 0)) {
    t1 = t2 = 0;
    return;
  }
  const double norm = std::hypot(t1, t2);
  if (norm > radius) {
    const double scale = radius / norm;
    t1 *= scale;
    t2 *= scale;
  }
}

// The whole impulse of a contact onto its cone: l_n onto [0, inf), then the pair onto the disk
// of radius mu l_n. A negative normal impulse gives zero.
inline void project_onto_cone(double mu, double& n, double& t1, double& t2) {
  n = std::max(n, 0.0);
  project_onto_disk(mu * n, t1, t2);
}

// The Coulomb law of one contact with everything else held: the row velocities are
// u = W l + q (W symmetric positive definite, rows normal, t1, t2), and l must satisfy
//     separation: l = 0, u_n >= 0;
//     sticking:   l_n > 0, |l_t| <= mu l_n, u = 0;
//     sliding:    l_n > 0, |l_t| = mu l_n, u_n = 0, u_t = -beta l_t with beta > 0
//                 (the friction impulse opposes the slip: maximal dissipation).
// Solved exactly (to round-off): separation if q_n >= 0; else the sticking solution -W^-1 q if
// it lies in the cone; else sliding. Sliding means (W + beta E_t) l = -q with E_t = diag(0, 1, 1),
// so l(beta) is known in closed form for each slip ratio beta = |u_t| / |l_t|, and beta is
// the root of f(beta) = |l_t(beta)| - mu l_n(beta): f(0) > 0 (the sticking solution is outside
// the cone) and f -> mu q_n / W_nn < 0 as beta grows, so a bracketed 1-D root find settles it.
// A tangent row the contact does not have is passed as a decoupled row (W = its diagonal, q = 0):
// its impulse comes out zero.
Vec3 solve_contact_coulomb(const Mat3& W, const Vec3& q, double mu);

}  // namespace mica
