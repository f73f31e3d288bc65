// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A whole CARMEN log written from messages, with the PARAM lines that declare the geometry of its
// FLASER/RLASER scans, so that CarmenReader gives back every scan's beam angles, maximum range
// and mounting exactly as they were in memory (after, say, fewer beams or a shorter scanner).
//
// FLASER/RLASER carry no geometry; the reader takes it from PARAM lines (carmen_reader.cpp):
// angle_min = -fov / 2, angle_increment = the resolution, range_max, and the mounting offsets.
// So a scan can be declared when its first beam is at -field_of_view / 2, which holds for every
// scan the reader produced and for what the fault injector makes of them (sim/fault_injection.hpp).
// Degrees are chosen so that the reader's deg -> rad conversion gives back the same doubles.

#include <string>
#include <vector>

#include "slam2d/io/carmen.hpp"

namespace slam2d {

/// What PARAM lines declare for the old front (FLASER) or rear (RLASER) laser.
struct DeclaredLaserGeometry {
  double field_of_view = 0.0;    // rad
  double angle_increment = 0.0;  // rad
  double range_max = 0.0;        // m
  SE2 T_robot_sensor;            // the mounting (the rear laser's yaw includes its pi)

  bool operator==(const DeclaredLaserGeometry& other) const = default;
};

/// The geometry of a FLASER/RLASER message. Throws Error (naming the message's line) when its
/// first beam is not at -field_of_view / 2, which PARAM lines cannot express.
DeclaredLaserGeometry declared_laser_geometry(const LaserMessage& message);

/// Writes the PARAM lines declaring `geometry` for the front (rear = false) or rear laser, at `stamp`.
void write_old_laser_params(CarmenWriter& writer, const DeclaredLaserGeometry& geometry, bool rear, double stamp);

/// Writes a whole log atomically (gzip when the path ends in .gz): `comments` as '#' lines, then
/// `messages` in order. Before the first FLASER (RLASER), and again before any whose geometry
/// differs from the last one declared, the front (rear) geometry PARAM lines are written.
/// Throws Error on a message CarmenWriter refuses or whose geometry cannot be declared; then
/// nothing is written at `path`.
void write_carmen_log(const std::string& path, const std::vector<std::string>& comments,
                      const std::vector<SensorMessage>& messages);

}  // namespace slam2d
