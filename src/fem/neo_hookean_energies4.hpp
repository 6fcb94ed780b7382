// SPDX-License-Identifier: Apache-2.0
// The neo-Hookean quadratic model's energies (neo_hookean_model_energies), four elements at once.
#pragma once
#include "fem/neo_hookean.hpp"

namespace mica {

// add_neo_hookean_model_energies on elements 0, 1, ... four at a time, in AVX2 + FMA lanes where
// the CPU has them: adds their terms to out (the same sums to round-off, in another order) and
// returns how many it took (a multiple of four; 0 on other CPUs), the rest for the caller.
int32_t add_neo_hookean_model_energies4(const FemModel& m, const NeoHookeanLinearisation& lin, const Vec3List& x_lin,
                                        const Vec3List& x_end, const Vec3List* v, NeoHookeanModelEnergies& out);

}  // namespace mica
