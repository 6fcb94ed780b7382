// SPDX-License-Identifier: Apache-2.0
// Isotropic linear elastic material.
#pragma once
#include <cstdint>

namespace mica {

// The elastic model of a body. The values are those the saved state and recordings store (0 and 1
// were the co-rotational flag before 0.8).
enum class ElasticModel : uint8_t {
  Linear = 0,        // small strain, constant stiffness
  Corotational = 1,  // small strain in each element's rotated frame
  NeoHookean = 2,    // stable neo-Hookean (fem/neo_hookean.hpp): large strain, Newton steps
};

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
