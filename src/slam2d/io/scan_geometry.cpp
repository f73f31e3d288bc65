// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/scan_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "slam2d/core/error.hpp"

namespace slam2d {

std::size_t beam_steps(std::size_t beams) {
  return beams % 2 == 1 && beams > 1 ? beams - 1 : std::max<std::size_t>(beams, 1);
}

void check_overrides(const ScanGeometryOverrides& overrides, const std::string& who) {
  const auto finite = [](const std::optional<double>& v) { return !v || std::isfinite(*v); };
  check(finite(overrides.field_of_view) && finite(overrides.angle_increment) && finite(overrides.angle_min) &&
            finite(overrides.range_max),
        who + ": geometry overrides must be finite");
  constexpr double kFullTurn = 2.0 * std::numbers::pi + 1e-9;
  check(!overrides.field_of_view || (*overrides.field_of_view > 0.0 && *overrides.field_of_view <= kFullTurn),
        who + ": field_of_view must be in (0, 2 pi] rad");
  check(!overrides.angle_increment || *overrides.angle_increment > 0.0, who + ": angle_increment must be positive");
  check(!overrides.range_max || *overrides.range_max > 0.0, who + ": range_max must be positive");
}

void apply_overrides(LaserScan& scan, const ScanGeometryOverrides& overrides) {
  const double steps = static_cast<double>(beam_steps(scan.size()));
  if (overrides.angle_increment) {
    scan.angle_increment = *overrides.angle_increment;
  } else if (overrides.field_of_view) {
    scan.angle_increment = *overrides.field_of_view / steps;
  }
  if (overrides.angle_min) {
    scan.angle_min = *overrides.angle_min;
  } else if (overrides.angle_increment || overrides.field_of_view) {
    scan.angle_min = -0.5 * steps * scan.angle_increment;
  }
  if (overrides.range_max) scan.range_max = *overrides.range_max;
}

}  // namespace slam2d
