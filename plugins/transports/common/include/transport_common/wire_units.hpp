// SPDX-License-Identifier: Apache-2.0
// Units at the wire. Inside ÜberSim everything is SI (m, rad, rad/s); the league's messages use
// mm (vision), degrees (grSim replacement) and rpm (some robot commands). Convert only here.
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

namespace ubersim::transport {

/// m → mm.
constexpr double MetresToMm(double m) { return m * 1000.0; }
/// mm → m.
constexpr double MmToMetres(double mm) { return mm * 0.001; }
/// rad → degrees.
constexpr double RadToDeg(double rad) { return rad * (180.0 / std::numbers::pi); }
/// degrees → rad.
constexpr double DegToRad(double deg) { return deg * (std::numbers::pi / 180.0); }
/// rpm → rad/s.
constexpr double RpmToRadPerS(double rpm) { return rpm * (2.0 * std::numbers::pi / 60.0); }
/// rad/s → rpm.
constexpr double RadPerSToRpm(double rad_s) { return rad_s * (60.0 / (2.0 * std::numbers::pi)); }

/// m → whole mm for the int32 fields of the geometry packet, rounded to nearest and clamped to
/// the int32 range (NaN gives 0).
inline std::int32_t MetresToWholeMm(double m) {
  const double mm = std::round(MetresToMm(m));
  if (std::isnan(mm)) return 0;
  constexpr double lo = std::numeric_limits<std::int32_t>::min();
  constexpr double hi = std::numeric_limits<std::int32_t>::max();
  return static_cast<std::int32_t>(mm < lo ? lo : (mm > hi ? hi : mm));
}

/// A blob area in pixels → the uint32 `area` of SSL_DetectionBall: rounded to nearest, clamped
/// to the uint32 range (NaN gives 0).
inline std::uint32_t WholePixels(double px) {
  const double r = std::round(px);
  if (!(r > 0)) return 0;  // also NaN
  constexpr double hi = std::numeric_limits<std::uint32_t>::max();
  return static_cast<std::uint32_t>(r > hi ? hi : r);
}

/// Simulated ns → s.
constexpr double NsToSeconds(std::int64_t ns) { return static_cast<double>(ns) * 1e-9; }

}  // namespace ubersim::transport
