// SPDX-License-Identifier: Apache-2.0
#include "core/cpu_features.hpp"

#include <cstdlib>

namespace mica::cpu {

namespace {

bool turned_off() {
  static const bool off = std::getenv("MICA_NO_AVX2") != nullptr;
  return off;
}

}  // namespace

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
bool avx2() {
  static const bool has = !turned_off() && __builtin_cpu_supports("avx2");
  return has;
}

bool avx2_fma() {
  static const bool has = avx2() && __builtin_cpu_supports("fma");
  return has;
}
#else
bool avx2() { return false; }
bool avx2_fma() { return false; }
#endif

}  // namespace mica::cpu
