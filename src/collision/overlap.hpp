// SPDX-License-Identifier: Apache-2.0
// How deep one body lies inside another: bodies placed overlapping. Contacts between bodies look
// for penetrations of about one surface edge (SurfaceView::depth); a node deeper than that is
// not seen, and a pair that overlaps so deep tangles instead of separating.
#pragma once
#include "collision/contact.hpp"

namespace mica {

struct Penetration {
  double depth = 0;   // m: how far the deepest surface node of a lies inside b (0: none inside)
  int32_t node = -1;  // that node of a; -1 when no node of a is inside b
};

// The surface nodes of a inside b, each measured to its nearest point of b's surface at any
// distance (inside or outside by b's pseudo-normal there): the deepest. b's surface must be
// closed and wound outwards (as a body's is). Costs a nearest-point query per node of a within
// b's bounds, each as wide as that node is deep.
Penetration deepest_penetration(const SurfaceView& a, const SurfaceView& b);

}  // namespace mica
