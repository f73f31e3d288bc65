// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Angle helpers. All angles are radians.

#include <cmath>
#include <numbers>

namespace slam2d {

/// Wraps an angle to [-pi, pi).
inline double normalize_angle(double angle) {
  if (angle >= -std::numbers::pi && angle < std::numbers::pi) return angle;
  double wrapped = std::fmod(angle + std::numbers::pi, 2.0 * std::numbers::pi);
  if (wrapped < 0.0) wrapped += 2.0 * std::numbers::pi;
  return wrapped - std::numbers::pi;
}

/// The signed smallest rotation from `from` to `to`, in [-pi, pi).
inline double angle_difference(double to, double from) { return normalize_angle(to - from); }

constexpr double deg_to_rad(double degrees) { return degrees * std::numbers::pi / 180.0; }
constexpr double rad_to_deg(double radians) { return radians * 180.0 / std::numbers::pi; }

}  // namespace slam2d
