// SPDX-License-Identifier: Apache-2.0
// Which vector extensions the hand-written kernels may use (the library is built for any x86-64;
// each kernel has a generic path and, compiled for AVX2 (+ FMA), a faster one it calls where the
// CPU has them). The environment variable MICA_NO_AVX2, set to anything, sends every kernel down
// its generic path: the tests run some suites so, to check those paths on machines with AVX2.
#pragma once

namespace mica::cpu {

bool avx2();      // AVX2, and not turned off
bool avx2_fma();  // AVX2 and FMA, and not turned off

}  // namespace mica::cpu
