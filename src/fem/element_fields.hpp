// SPDX-License-Identifier: Apache-2.0
// Per-element strain and stress of a body at given positions, as its model sees them: the
// co-rotational model measures strain in each element's rotated frame (a rigid rotation strains
// nothing), the linear model the small strain of the displacement, the neo-Hookean model the Green
// strain (F^T F - I) / 2 and its Cauchy stress.
#pragma once
#include <vector>

#include "fem/fem_model.hpp"

namespace mica {

// Strain per element at x, in the element's rest axes: sym(R^T F) - I with R the rotation of F
// (co-rotational) or I (linear); (F^T F - I) / 2 (neo-Hookean).
void element_strains(const FemModel& m, const Vec3List& x, ElasticModel model, std::vector<Mat3>& strain);

// Von Mises stress per element at x (Pa), of the element's own material (neo-Hookean: of the
// Cauchy stress).
void element_von_mises(const FemModel& m, const Vec3List& x, ElasticModel model, std::vector<double>& out);

}  // namespace mica
