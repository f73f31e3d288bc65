// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The user's word on a laser's geometry, for every log format: the field of view, the angle of the
// first beam, the angle between beams and the maximum range, each unset or given. CARMEN's
// FLASER/RLASER declare no angles, so there the overrides join the PARAM lines and the convention
// (io/carmen.hpp, docs/sensor_geometry.md); a bag's LaserScan declares its own, and an override
// replaces what it declares (a converter that wrote 180 beams of a 179 deg sensor as 180 deg).
//
// One meaning everywhere: n beams span `beam_steps(n)` steps, n - 1 for an odd n (beams at both
// ends: 181 beams of 1 deg are -90 .. +90 deg) and n otherwise (180 beams of 1 deg are -90 .. +89
// deg), so the field of view is steps x increment and, unless given, the first beam is at
// -field of view / 2.

#include <cstddef>
#include <optional>
#include <string>

#include "slam2d/core/laser_scan.hpp"

namespace slam2d {

struct ScanGeometryOverrides {
  std::optional<double> field_of_view;    // rad, in (0, 2 pi]
  std::optional<double> angle_increment;  // rad, > 0; beats the field of view
  std::optional<double> angle_min;        // rad; default -field_of_view / 2
  std::optional<double> range_max;        // m, > 0: readings at or above are "no return"

  bool any() const { return field_of_view || angle_increment || angle_min || range_max; }
};

/// Steps between the first and the last beam's edge for `beams` beams (see above).
std::size_t beam_steps(std::size_t beams);

/// Error("WHO: ...") unless every override is finite and in its range (above).
void check_overrides(const ScanGeometryOverrides& overrides, const std::string& who);

/// `scan` (which declares its own angles) with the overrides applied: an increment or a field of
/// view replaces the declared spacing, and then the first beam is at -field of view / 2 unless
/// angle_min is given; range_max replaces the declared maximum range.
void apply_overrides(LaserScan& scan, const ScanGeometryOverrides& overrides);

}  // namespace slam2d
