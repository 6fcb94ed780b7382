// SPDX-License-Identifier: Apache-2.0
#include "solver/contact_rows.hpp"

#include <algorithm>

#include "solver/friction_cone.hpp"

namespace mica {

void ContactRows::clear() {
  start.assign(1, 0);
  terms.clear();
  direction.clear();
  bias.clear();
  normal_of.clear();
  mu.clear();
  contact.clear();
  key.clear();
}

void ContactRows::project(std::vector<double>& lambda) const {
  for (size_t r = 0; r < size(); ++r)
    if (normal_of[r] < 0) lambda[r] = std::max(lambda[r], 0.0);
    else if (first_tangent(r)) project_onto_disk(mu[r] * lambda[normal_of[r]], lambda[r], lambda[r + 1]);
}

double normal_bias(const Contact& contact, double h, double max_recovery_speed) {
  // A receding tool explains none of the penetration: approach >= 0.
  const double approach = contact.tool >= 0 ? std::max(contact.normal.dot(contact.other_velocity), 0.0) : 0.0;
  return std::max(contact.gap / h + approach, -max_recovery_speed) - approach;
}

void ContactRows::build(const std::vector<Contact>& contacts, double h, double max_recovery_speed) {
  clear();
  auto add_row = [&](size_t c, const Vec3& d, double b, int32_t normal_row, double friction, uint64_t kind) {
    const Contact& ct = contacts[c];
    for (int k = 0; k < ct.a.count; ++k) terms.push_back({ct.a.body, ct.a.nodes[k], ct.a.weights[k]});
    for (int k = 0; k < ct.b.count; ++k) terms.push_back({ct.b.body, ct.b.nodes[k], -ct.b.weights[k]});
    start.push_back(int32_t(terms.size()));
    direction.push_back(d);
    bias.push_back(b);
    normal_of.push_back(normal_row);
    mu.push_back(friction);
    contact.push_back(int32_t(c));
    key.push_back(normal_row_key(ct.key) + kind);
  };
  for (size_t c = 0; c < contacts.size(); ++c) {
    const Contact& ct = contacts[c];
    const int32_t normal_row = int32_t(direction.size());
    add_row(c, ct.normal, normal_bias(ct, h, max_recovery_speed), -1, 0.0, 0);
    if (ct.friction <= 0) continue;
    // Any orthonormal tangent pair: the cone is isotropic. Right after the normal row, t1 then t2
    // (the layout the solvers rely on, contact_rows.hpp).
    const Vec3 t1 = ct.normal.unitOrthogonal(), t2 = ct.normal.cross(t1);
    // Sticking moves the body point with the tool: t . v = t . v_tool.
    add_row(c, t1, -t1.dot(ct.other_velocity), normal_row, ct.friction, 1);
    add_row(c, t2, -t2.dot(ct.other_velocity), normal_row, ct.friction, 2);
  }
}

}  // namespace mica
