// SPDX-License-Identifier: Apache-2.0
#include "fem/element_fields.hpp"

#include "fem/neo_hookean.hpp"
#include "fem/rotation.hpp"

namespace mica {

void element_strains(const FemModel& m, const Vec3List& x, ElasticModel model, std::vector<Mat3>& strain) {
  strain.resize(m.elements.size());
  for (size_t e = 0; e < m.elements.size(); ++e) {
    const Mat3 F = deformation_gradient(m.elements[e], x);
    if (model == ElasticModel::NeoHookean)
      strain[e] = 0.5 * (F.transpose() * F - Mat3::Identity());
    else
      strain[e] = rotated_strain(model == ElasticModel::Corotational ? proper_rotation(F) : Mat3::Identity(), F);
  }
}

void element_von_mises(const FemModel& m, const Vec3List& x, ElasticModel model, std::vector<double>& out) {
  out.resize(m.elements.size());
  if (model == ElasticModel::NeoHookean) {
    for (size_t e = 0; e < m.elements.size(); ++e)
      out[e] = von_mises(neo_hookean_cauchy(neo_hookean_parameters(m.lame[e]), deformation_gradient(m.elements[e], x)));
    return;
  }
  std::vector<Mat3> strain;
  element_strains(m, x, model, strain);
  for (size_t e = 0; e < strain.size(); ++e) out[e] = von_mises(stress(m.lame[e], strain[e]));
}

}  // namespace mica
