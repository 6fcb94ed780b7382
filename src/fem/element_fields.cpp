// SPDX-License-Identifier: Apache-2.0
#include "fem/element_fields.hpp"

#include "fem/rotation.hpp"

namespace mica {

void element_strains(const FemModel& m, const Vec3List& x, bool corotational, std::vector<Mat3>& strain) {
  strain.resize(m.elements.size());
  for (size_t e = 0; e < m.elements.size(); ++e) {
    const Mat3 F = deformation_gradient(m.elements[e], x);
    strain[e] = rotated_strain(corotational ? proper_rotation(F) : Mat3::Identity(), F);
  }
}

void element_von_mises(const FemModel& m, const Vec3List& x, bool corotational, std::vector<double>& out) {
  std::vector<Mat3> strain;
  element_strains(m, x, corotational, strain);
  out.resize(strain.size());
  for (size_t e = 0; e < strain.size(); ++e) out[e] = von_mises(stress(m.lame[e], strain[e]));
}

}  // namespace mica
