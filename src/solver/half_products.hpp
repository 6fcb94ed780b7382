// SPDX-License-Identifier: Apache-2.0
// Products with a dense block stored in IEEE half precision (16 bits), for the preconditioner's
// copy of the factor (supernodal_solve.hpp). The single-precision triangular pair is bound by
// reading the factor, so half the bytes is a faster pair. Written by hand: converting halves is one
// instruction per eight with F16C and dozens without, and the library is built for any x86-64,
// so these are compiled for AVX2 + FMA + F16C and called only where the CPU has them
// (half_products_supported()); Eigen decides its vector width when it is compiled.
#pragma once
#include <cstddef>
#include <cstdint>

namespace mica {

// True when this CPU runs the functions below (x86-64 with AVX2, FMA and F16C).
bool half_products_supported();

// out[q] = half(in[q] * scale), rounded to nearest.
void to_half(const float* in, size_t n, float scale, uint16_t* out);

// y[0, rows) = s B x, B stored rows x nc column-major with leading dimension ld.
void half_product(const uint16_t* B, int ld, int rows, int nc, const float* x, float s, float* y);

// out[j] = s B[:, j] . y for j < nc (B as above).
void half_transposed_product(const uint16_t* B, int ld, int rows, int nc, const float* y, float s, float* out);

}  // namespace mica
