// SPDX-License-Identifier: Apache-2.0
#include "haptics/force_safety.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace mica {

namespace {

// |v| without overflow for huge finite components (a plain norm would give inf and lose the direction).
double magnitude(const Vec3& v) { return std::hypot(v.x(), v.y(), v.z()); }

// The fraction of the force kept `age` seconds after the last publish.
double stall_scale(double age, const SafetySettings& s) {
  if (age <= s.stall_timeout) return 1;  // also false for a NaN age: treated as stalled
  const double late = age - s.stall_timeout;
  if (!(late < s.stall_ramp)) return 0;  // past the ramp, a zero-length ramp, or NaN
  return 1 - late / s.stall_ramp;
}

// The point nearest `target` in the capsule {s p + d : s in [0, 1], |d| <= radius}.
Vec3 limit_growth(const Vec3& target, const Vec3& p, double radius, bool& limited) {
  const double pp = p.squaredNorm();
  const double s = pp > 0 ? std::clamp(target.dot(p) / pp, 0.0, 1.0) : 0.0;
  const Vec3 base = s * p;  // the nearest point of the segment [0, p]
  const Vec3 d = target - base;
  const double dn = magnitude(d);
  limited = dn > radius;
  return limited ? Vec3(base + (radius / dn) * d) : target;
}

}  // namespace

ForceSafety::ForceSafety(const SafetySettings& settings) { configure(settings); }

void ForceSafety::configure(const SafetySettings& s) {
  if (!(std::isfinite(s.max_force) && s.max_force > 0))
    fail(Errc::InvalidArgument, "force safety: max_force must be finite and > 0");
  if (!(s.max_rate > 0)) fail(Errc::InvalidArgument, "force safety: max_rate must be > 0");
  if (!(std::isfinite(s.stall_timeout) && s.stall_timeout >= 0))
    fail(Errc::InvalidArgument, "force safety: stall_timeout must be finite and >= 0");
  if (!(std::isfinite(s.stall_ramp) && s.stall_ramp >= 0))
    fail(Errc::InvalidArgument, "force safety: stall_ramp must be finite and >= 0");
  settings_ = s;
  reset();
}

Vec3 ForceSafety::apply(const Vec3& force, double now, double last_publish, double dt,
                        SafetyFlags& flags) noexcept {
  flags = SafetyFlags();
  Vec3 f = force;
  if (!f.allFinite()) {
    flags.non_finite = true;
    f.setZero();
  }

  const double scale = stall_scale(now - last_publish, settings_);
  if (scale < 1) {
    flags.stalled = true;
    f *= scale;
  }

  const double m = magnitude(f);
  if (m > settings_.max_force) {
    flags.clamped = true;
    f *= settings_.max_force / m;
  }

  // Written so that dt = 0 with max_rate = inf gives 0, not NaN.
  const double radius = dt > 0 ? settings_.max_rate * dt : 0.0;
  f = limit_growth(f, previous_, radius, flags.rate_limited);

  // Belt and braces: nothing above should produce a non-finite value, but this must never send one.
  if (!f.allFinite()) {
    flags.non_finite = true;
    f.setZero();
  }
  previous_ = f;
  return f;
}

}  // namespace mica
