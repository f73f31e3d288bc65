// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/carmen_log.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <variant>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/detail/number_format.hpp"

namespace slam2d {

namespace {

// rad: a first beam this far from -fov / 2 is rounding, not another geometry.
constexpr double kAngleTolerance = 1e-9;

// Degrees whose conversion by the reader (deg_to_rad) gives back `radians` exactly, when a
// neighbour of rad_to_deg(radians) within a few ulps does; else rad_to_deg(radians).
double degrees_reading_back(double radians) {
  const double degrees = rad_to_deg(radians);
  double up = degrees;
  double down = degrees;
  for (int step = 0; step < 8; ++step) {
    if (deg_to_rad(up) == radians) return up;
    if (deg_to_rad(down) == radians) return down;
    up = std::nextafter(up, std::numeric_limits<double>::infinity());
    down = std::nextafter(down, -std::numeric_limits<double>::infinity());
  }
  return degrees;
}

}  // namespace

DeclaredLaserGeometry declared_laser_geometry(const LaserMessage& message) {
  const LaserScan& scan = message.scan;
  if (!(std::abs(scan.angle_min + 0.5 * message.field_of_view) <= kAngleTolerance)) {
    throw Error(message.type + " (line " + std::to_string(message.line) + "): first beam at " +
                format_number(rad_to_deg(scan.angle_min)) + " deg with a field of view of " +
                format_number(rad_to_deg(message.field_of_view)) +
                " deg; PARAM lines can only declare a first beam at -fov/2");
  }
  return {.field_of_view = message.field_of_view,
          .angle_increment = scan.angle_increment,
          .range_max = scan.range_max,
          .T_robot_sensor = scan.T_robot_sensor};
}

void write_old_laser_params(CarmenWriter& writer, const DeclaredLaserGeometry& geometry, bool rear, double stamp) {
  const std::string laser = rear ? "laser_rear_laser_" : "laser_front_laser_";
  const std::string robot = rear ? "robot_rear_laser_max" : "robot_front_laser_max";
  const std::string mount = rear ? "robot_rearlaser_" : "robot_frontlaser_";
  // The reader adds pi to the rear laser's angular offset (it faces backwards).
  const double yaw = geometry.T_robot_sensor.theta() - (rear ? std::numbers::pi : 0.0);
  writer.write_param(laser + "fov", format_number(degrees_reading_back(geometry.field_of_view)), stamp);
  writer.write_param(laser + "resolution", format_number(degrees_reading_back(geometry.angle_increment)), stamp);
  writer.write_param(robot, format_number(geometry.range_max), stamp);
  writer.write_param(mount + "offset", format_number(geometry.T_robot_sensor.x()), stamp);
  writer.write_param(mount + "side_offset", format_number(geometry.T_robot_sensor.y()), stamp);
  writer.write_param(mount + "angular_offset", format_number(normalize_angle(yaw)), stamp);
}

void write_carmen_log(const std::string& path, const std::vector<std::string>& comments,
                      const std::vector<SensorMessage>& messages) {
  CarmenWriter writer(path);
  for (const std::string& comment : comments) writer.write_comment(comment);
  std::optional<DeclaredLaserGeometry> declared[2];  // front, rear
  for (const SensorMessage& message : messages) {
    if (const auto* laser = std::get_if<LaserMessage>(&message)) {
      const bool rear = laser->type == "RLASER";
      if (rear || laser->type == "FLASER") {
        const DeclaredLaserGeometry geometry = declared_laser_geometry(*laser);
        if (declared[rear] != geometry) write_old_laser_params(writer, geometry, rear, laser->scan.stamp);
        declared[rear] = geometry;
      }
    }
    writer.write(message);
  }
  writer.commit();
}

}  // namespace slam2d
