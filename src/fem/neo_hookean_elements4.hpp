// SPDX-License-Identifier: Apache-2.0
// The neo-Hookean assembly's kernel: four elements at once, side by side in SIMD lanes.
#pragma once
#include "fem/neo_hookean.hpp"

namespace mica {

// add_neo_hookean_element on elements e[0..3], in AVX2 + FMA lanes where the CPU has them (else
// one after the other): the same contributions, to round-off. The four may share nodes and blocks,
// or be the same element. The SVD's eigensystem in lanes as well (eigensystems4.hpp); only the rare
// lanes that need more (a nearly flat or needle-like element's Jacobi SVD, a scaling block to clamp)
// are solved lane by lane.
void add_neo_hookean_elements4(const FemModel& m, const int32_t e[4], const Vec3List& x_lin,
                               const NeoHookeanAssembly& what, Vec3List& f_int);

}  // namespace mica
