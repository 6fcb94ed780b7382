// The rows of G: each contact's normal row and, with friction, two tangent rows. A row is a
// velocity component  sum_k coef_k d . v(body_k, node_k)  over the nodes of the touching points.
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
  std::vector<double> bias;       // gap / h (clamped) for normal rows; -t . v_tool for friction rows
  std::vector<int32_t> normal_of; // -1 for a normal row; the normal row of a friction row
  std::vector<double> mu;         // friction coefficient of a friction row
  std::vector<int32_t> contact;   // the contact each row belongs to
  std::vector<uint64_t> key;      // persistent key of the row (contact key and row kind)

  size_t size() const { return direction.size(); }
  void clear();
  // Rows of all contacts; gap / h is clamped at -max_recovery_speed.
  void build(const std::vector<Contact>& contacts, double h, double max_recovery_speed);
};

}  // namespace mica
