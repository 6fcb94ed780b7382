// SPDX-License-Identifier: Apache-2.0
// Isotropic linear elastic material.
#pragma once

namespace mica {

struct Material {
  double youngs_modulus = 1e4;  // Pa
  double poisson_ratio = 0.3;
  double density = 1000;        // kg/m^3
};

struct Lame {
  double lambda;
  double mu;
};

inline Lame lame_parameters(const Material& m) {
  const double E = m.youngs_modulus, nu = m.poisson_ratio;
  return {E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))};
}

}  // namespace mica
