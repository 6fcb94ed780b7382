// SPDX-License-Identifier: Apache-2.0
// The geometric stiffness of a tool contact on a surface triangle.
//
// A contact row is the gap's gradient at the step's start: the body point (weights w) pushed
// along the normal n. When a triangle tilts under a rounded tool, its point closest to the
// tool's core runs across it (under a sphere of radius R, by R per radian of tilt), a
// second-order effect the row does not see. Solved with the row alone, a pressed triangle
// overshoots: its next closest point lies on the other side, and a tool held still feels the
// contact flip between faces and edges every step (a period-2 chatter whose gain grows like
// R depth / edge^2). An implicit step must also linearise the contact force f = F grad g: its
// change F H dx (H the gap's Hessian) holds the tilt, as in Newton's method on the contact.
#pragma once
#include <Eigen/Dense>

#include "collision/contact.hpp"
#include "collision/core_features.hpp"

namespace mica {

using Mat9 = Eigen::Matrix<double, 9, 9>;

// The stiffening part of -H for contact c (a pair of a core feature and a feature of triangle t,
// corners at x), in the 9 coordinates of t's corners: the positive semidefinite part of minus the
// gap's Hessian, by central differences of the gradient w_k n, which the feature pair gives
// exactly. Times the contact's force (N) it is a stiffness (N/m) for the triangle's blocks of K.
// False (K untouched) for a core without rounding (its curvature is that of a corner, nil at a
// touch) and where a difference point leaves the pair's feature (an edge pair at an end).
bool contact_curvature(const ToolCore& core, const Contact& c, const Tri& t, const Vec3List& x, Mat9& K);

}  // namespace mica
