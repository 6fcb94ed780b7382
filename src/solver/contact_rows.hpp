// SPDX-License-Identifier: Apache-2.0
// The rows of G: each contact's normal row and, with friction, two tangent rows. A row is a
// velocity component  sum_k coef_k d . v(body_k, node_k)  over the nodes of the touching points.
// Layout the solvers rely on: a contact's normal row comes first, its two tangent rows (if any)
// right after it, t1 then t2; the tangent pair is projected together onto the friction disk
// |(lambda_t1, lambda_t2)| <= mu lambda_n (friction_cone.hpp).
#pragma once
#include <vector>

#include "collision/contact.hpp"

namespace mica {

struct RowTerm {
  int32_t body;
  int32_t node;
  double coef;  // barycentric weight, negated for the second body of a body-body contact
};

struct ContactRows {
  std::vector<int32_t> start;     // rows + 1 offsets into terms
  std::vector<RowTerm> terms;
  std::vector<Vec3> direction;    // n for a normal row, a unit tangent for a friction row
  std::vector<double> bias;       // normal_bias for normal rows; -t . v_tool for friction rows
  std::vector<int32_t> normal_of; // -1 for a normal row; the normal row of a friction row
  std::vector<double> mu;         // friction coefficient of a friction row
  std::vector<int32_t> contact;   // the contact each row belongs to
  std::vector<uint64_t> key;      // persistent key of the row (contact key and row kind)

  size_t size() const { return direction.size(); }
  // The key of a contact's normal row (its friction rows follow with + 1 and + 2).
  static uint64_t normal_row_key(uint64_t contact_key) { return contact_key * 3; }
  // Row r is the first tangent row of its contact (its pair is r, r + 1).
  bool first_tangent(size_t r) const { return normal_of[r] >= 0 && size_t(normal_of[r]) + 1 == r; }
  void clear();
  // Rows of all contacts; normal rows get normal_bias.
  void build(const std::vector<Contact>& contacts, double h, double max_recovery_speed);
  // Impulses onto their cones: a normal row's onto lambda >= 0, a tangent pair onto the disk of
  // mu lambda_n (friction_cone.hpp).
  void project(std::vector<double>& lambda) const;
  // Adds G^T lambda, row by row: impulse(body) is the body's Vec3List of per-node impulses.
  template <class ImpulseOf>
  void scatter(const std::vector<double>& lambda, ImpulseOf&& impulse) const {
    for (size_t r = 0; r < size(); ++r)
      for (int32_t t = start[r]; t < start[r + 1]; ++t)
        impulse(terms[t].body)[terms[t].node] += terms[t].coef * lambda[r] * direction[r];
  }
};

// The bias of a contact's normal row, n . v + bias >= 0: gap / h, the velocity that closes the gap
// in the step, except that penetration is recovered at no more than max_recovery_speed (more
// injects energy). A tool's contact is measured at the tool's new pose, so its gap includes the
// tool's own approach this step, h n . u (u: the tool's velocity at the point, other_velocity):
// that part is not penetration to recover slowly but motion to make way for, so only the rest,
// gap / h + n . u (the penetration at the step's start), is clamped:
//   bias = max(gap / h + a, -max_recovery_speed) - a,   a = max(n . u, 0)
// (a receding tool, n . u < 0, explains none of the penetration: the plain clamp). The bias is at
// least gap / h, equal to it for a gap >= 0, and at most 0 for a penetrating contact.
double normal_bias(const Contact& contact, double h, double max_recovery_speed);

}  // namespace mica
