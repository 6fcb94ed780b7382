// SPDX-License-Identifier: Apache-2.0
// The energies of a co-rotational model along a step, and the twist stiffness its linearisation
// leaves out: the FEM side of the re-linearisation check (world/relinearise.cpp).
//
// A step linearised with element rotations R (a frozen-rotation step) is backward Euler on the
// quadratic energy U_R(y) = sum over elements of the energy of F(y) in the frame R; the model's
// own energy U(y) takes each element's rotation of F(y). With the twist stiffness G of the
// linearisation point x_lin added (Newton on the projected Hessian), the quadratic energy is
// U_L(y) = U_R(y) + (y - x_lin)^T G (y - x_lin) / 2.
#pragma once
#include <vector>

#include "fem/fem_model.hpp"
#include "fem/rotation_stiffness.hpp"

namespace mica {

// The energies of the first screen of a step: U(x_end) (each element's own rotation, written to
// R_end), U_R(x_end), and U_R(x) when `with_start` (else 0).
struct ScreenEnergies {
  double u_end = 0, u_lin_end = 0, u_lin_start = 0;  // J
};
ScreenEnergies screen_energies(const FemModel& m, const Vec3List& x, const Vec3List& x_end, const std::vector<Mat3>& R,
                               std::vector<Mat3>& R_end, bool with_start);

// What the full check of a step's velocities v (x_end = x + h v) takes from the elements.
struct LinearisationEnergies {
  double u_end = 0;          // U(x_end)
  double u_lin_end = 0;      // U_R(x_end), without the twist term
  double u_lin_start = 0;    // U_R(x)
  double vKv = 0;            // v^T (R Ke R^T) v, the stiffness of the linearisation (without G)
  double vKv_start = 0;      // v^T (R_s Ke R_s^T) v with the step's start rotations (if asked for)
  double gvv = 0, gdd = 0, gll = 0;  // v^T G v, (v - v_lin)^T G (v - v_lin), v_lin^T G v_lin
};
// R: the linearisation's rotations (null: the linear model, R = I; then R_end is not written);
// R_start: the step's start rotations for vKv_start (null: not computed; ignored for the linear
// model, whose start rotations are I); modes and v_lin: the twist stiffness G at the
// linearisation point (modes empty: none).
LinearisationEnergies linearisation_energies(const FemModel& m, const Vec3List& x, const Vec3List& x_end,
                                             const Vec3List& v, const std::vector<Mat3>* R, std::vector<Mat3>& R_end,
                                             const std::vector<Mat3>* R_start, bool with_start_stiffness,
                                             const std::vector<TwistModes>& modes, const Vec3List& v_lin);

// The twist stiffness at positions x_lin (x_lin = x + h v_lin, v_lin the linearisation's
// velocities) into the step's system: modes receives G per element, A += h^2 G, and
// f_int += h G v_lin (f(x_lin) - H (y - x_lin) = f_R(y) - G (y - x_lin)).
void add_twist_stiffness(const FemModel& m, const Vec3List& x_lin, const Vec3List& v_lin, double h,
                         std::vector<TwistModes>& modes, BlockValues& A, Vec3List& f_int);

}  // namespace mica
