// SPDX-License-Identifier: Apache-2.0
// What the simulation thread hands to the servo thread after each step, and how the servo
// thread turns it into a force between steps (mica-method.md, section 5).
//
// Servo path: evaluate() and coupling_force() never allocate, lock, block or make a system
// call. passive_coupling_damping() is for configuration (it may throw).
#pragma once
#include <cstdint>

#include "core/types.hpp"

namespace mica {

// How the servo path computes the force; the values are those of MICA_FORCE_* in mica_device.h.
enum class ForceMode : int32_t {
  LocalModel = 0,  // F0 + H (x - x0)
  Hold = 1,        // F0 (zero-order hold)
  Coupling = 2     // a spring-damper between the device and the simulated tool: coupling_force()
};

// The tool force linearised around the tool position a step used. Scene frame; N, N/m, m, s.
struct ForceModel {
  Vec3 f0 = Vec3::Zero();   // N, the force on the tool at x0
  Mat3 H = Mat3::Zero();    // N/m, dF/dx at x0 (for a stable contact, symmetric negative semidefinite)
  Vec3 x0 = Vec3::Zero();   // m, the tool position the step used
  double published_at = 0;  // s, when the step published this (the clock the safety stage uses)
  bool in_contact = false;  // the tool touched something in that step (drives the filter's reset)
  bool holds = false;       // a grasp: the tissue pulls as well as pushes (no release at the sign change)
  int64_t step = -1;        // the step that published it; -1: nothing published yet

  // The force at tool position x: f0 + H (x - x0) for LocalModel, f0 for Hold. Coupling is not a
  // function of the position alone (see coupling_force()); any mode but LocalModel holds f0.
  // LocalModel: f0 + H (x - x0), or, for a contact (not `holds`), zero once that turns against f0
  // (contact opens: tissue only pushes); Hold and Coupling: f0.
  Vec3 evaluate(const Vec3& x, ForceMode mode) const noexcept;
};

// The model a grasp renders: f0 the force the held tissue puts on the hand (the constraint's
// reaction) at the handle's position x0, H = -k I with k the secant stiffness the tissue showed
// along the handle's last move from `last` (the model published before), within [0, the device's
// nominal stiffness]: stable to render, and zero when the tissue gave way.
ForceModel grasp_force_model(const ForceModel& last, const Vec3& reaction, const Vec3& handle,
                             double nominal_stiffness);

// Virtual coupling: the force on the device from a spring (k, N/m) and damper (b, N s/m) joining
// it to the simulated tool, -k (x_device - x_tool) - b (v_device - v_tool). It pulls the device
// toward the tool; the opposite force acts on the tool.
Vec3 coupling_force(const Vec3& x_device, const Vec3& v_device, const Vec3& x_tool, const Vec3& v_tool,
                    double k, double b) noexcept;

// k T / 2 (N s/m): the damping a sampled spring of stiffness k (N/m) at period T (s) needs to stay
// passive. Colgate and Schenkel's condition for a sampled virtual wall is b > K T / 2 + |B|, with b
// the damping the device provides and B the virtual damping; mica-method.md applies the K T / 2
// bound to the coupling damping. Use the result as a lower bound, not a target. Throws
// Error(InvalidArgument) unless k >= 0 and T > 0 (both finite).
double passive_coupling_damping(double k, double period);

}  // namespace mica
