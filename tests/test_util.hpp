// SPDX-License-Identifier: Apache-2.0
// cmocka from C++: the headers it needs, and small numeric assertions with messages.
// cmocka.h defines a function-like macro fail(), which breaks any header declaring a
// fail() (libstdc++'s basic_ios, mica::fail) included after it: so every core and standard
// header a test may need is included here first.
#pragma once
#include <algorithm>
#include <cstring>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "mesh/mesh_io.hpp"
#include "world/world.hpp"

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
extern "C" {
#include <cmocka.h>
}
#include <cmath>
#include <cstdio>

// Fails with both values printed when |a - b| > tol.
#define assert_near(a, b, tol)                                                              \
  do {                                                                                      \
    const double a_ = (a), b_ = (b), t_ = (tol);                                            \
    if (!(std::fabs(a_ - b_) <= t_)) {                                                      \
      fail_msg("%s = %.17g, %s = %.17g, |diff| = %.3g > %.3g", #a, a_, #b, b_,               \
               std::fabs(a_ - b_), t_);                                                     \
    }                                                                                       \
  } while (0)

// Fails unless `a` is finite and a <= b.
#define assert_le(a, b)                                                                     \
  do {                                                                                      \
    const double a_ = (a), b_ = (b);                                                        \
    if (!(a_ <= b_)) fail_msg("%s = %.17g is not <= %s = %.17g", #a, a_, #b, b_);             \
  } while (0)
