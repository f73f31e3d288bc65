// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// CARMEN log files (plain or gzip), read as a stream of messages and written atomically.
//
// Read: FLASER, RLASER (old front/rear laser), ROBOTLASER1, RAWLASER1-4, ODOM, TRUEPOS, PARAM.
// Timestamps are the ipc_timestamp field. Lines starting with '#' and blank lines are comments;
// any other message type is skipped and counted. Timestamps that go backwards are kept in file
// order and counted: over all timestamped messages (lasers, odometry, true poses; PARAM lines do
// not count) and over the laser messages alone. The Intel log's "631 backwards steps" is the
// laser-only count; over all messages in file order it is 889.
//
// FLASER/RLASER carry no angles. The CARMEN convention is a 180 deg scanner centred on the
// sensor's x axis, starting at -90 deg: 180 or 360 beams split the field of view into n equal
// steps (last beam at +89 or +89.5 deg); 181 or 361 beams put beams at both ends (-90..+90).
// PARAM lines (laser_front_laser_fov, laser_front_laser_resolution, robot_frontlaser_offset,
// robot_frontlaser_side_offset, robot_frontlaser_angular_offset, robot_front_laser_max and the
// rear equivalents) and the reader options override this. RLASER is mounted facing backwards.
//
// The geometry checks itself (docs/sensor_geometry.md): at the first FLASER/RLASER line of each
// beam count the reader decides field of view, angle_min, increment and maximum range from the
// options, the PARAM lines and the convention, checking beams x resolution against the field of
// view (within one beam step). A PARAM's unit is guessed only when unambiguous: CARMEN writes
// degrees, but a value <= 2 pi that fits the beam count only when read as radians is radians.
// PARAM lines that contradict each other in every unit fall back to the convention with a
// warning when the convention agrees with one of them, and are a ParseError naming the PARAM's
// line otherwise. What was decided, and why, is in CarmenStats::old_laser_geometries.
// ROBOTLASER1 and RAWLASER declare their own angles and maximum range; ROBOTLASER1's mounting is
// robot_pose^-1 * laser_pose, RAWLASER's is the identity (a raw scan has no robot).
//
// Odometry that integrates reversing as forward driving (FR079) is repaired by default: a laser
// message's odom_pose is rebuilt from the scan-to-scan increments, the translation of an increment
// scaled by the signed share of its travel, sum tv / sum |tv| over the ODOM messages since the pose
// last moved (-1 mirrors a step driven wholly in reverse; core/odometry_repair.hpp, which also says
// when it trusts tv's sign). Only LaserMessage::odom_pose changes; ODOM lines and the laser_pose
// triple are returned as logged. docs/odometry_guard.md.

#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/odometry.hpp"
#include "slam2d/core/se2.hpp"
#include "slam2d/core/sensor_log.hpp"
#include "slam2d/io/scan_geometry.hpp"

namespace slam2d {

struct CarmenReaderOptions {
  /// Overrides of the FLASER/RLASER geometry (io/scan_geometry.hpp); PARAM lines and the
  /// convention are used where unset. An override beats a PARAM line; a PARAM it contradicts is
  /// dropped with a warning. FLASER/RLASER carry no maximum range: readings at or above the decided
  /// one are "no return"; a robot_front_laser_max / robot_rear_laser_max PARAM gives it, else
  /// default_range_max.
  ScanGeometryOverrides geometry;
  double default_range_max = 80.0;  // m, SICK LMS in its 80 m mode (returns ~81.9 m for "no return")
  double range_min = 0.0;           // m
  /// Repair laser odometry that integrates reversing as forward driving (see above); false gives
  /// every pose as logged (`--raw-odometry`).
  bool repair_reverse_odometry = true;
};

/// Where a FLASER/RLASER geometry value came from.
enum class GeometrySource {
  kConvention,      // the CARMEN convention: 180 deg centred on the x axis; 80 m (default_range_max)
  kParam,           // a PARAM line, in CARMEN's unit (degrees, metres)
  kParamUnitGuess,  // a PARAM line whose unit was guessed: radians where CARMEN writes degrees
  kDerived,         // from the other values: increment = fov / steps, fov = steps x increment, angle_min = -fov / 2
  kOverride,        // a reader option (a command-line override)
};

/// "convention", "PARAM", "PARAM (unit guessed)", "derived", "override".
const char* to_string(GeometrySource source);

struct GeometryValue {
  double value = 0.0;  // rad for angles, m for the range
  GeometrySource source = GeometrySource::kConvention;
  std::string reason;  // for people, e.g. "PARAM laser_front_laser_fov 3.14159 (line 3) read as radians"
};

/// The geometry decided for one old-format laser (FLASER: front, RLASER: rear) and one beam
/// count, at its first laser line, and kept until a PARAM line changes that laser's geometry.
struct OldLaserGeometry {
  bool rear = false;
  std::size_t beams = 0;
  std::size_t first_line = 0;  // the laser line it was decided at
  std::size_t scans = 0;       // laser lines that used it
  GeometryValue field_of_view;    // rad
  GeometryValue angle_min;        // rad
  GeometryValue angle_increment;  // rad
  GeometryValue range_max;        // m
  std::size_t readings = 0;              // ranges read with it
  std::size_t readings_at_range_max = 0;  // of those, at or above range_max (no return)
  std::vector<std::string> warnings;     // PARAM lines dropped, ambiguous units
};

struct CarmenStats {
  std::size_t lines = 0;
  std::size_t comment_lines = 0;  // '#' and blank lines
  std::size_t laser_messages = 0;
  std::size_t odometry_messages = 0;
  std::size_t true_pose_messages = 0;
  std::size_t param_messages = 0;
  std::size_t skipped_lines = 0;                      // unknown message types
  std::map<std::string, std::size_t> skipped_types;  // type -> count
  std::size_t backwards_timestamps = 0;        // steps back in time, over all timestamped messages
  std::size_t backwards_laser_timestamps = 0;  // steps back in time, over laser messages only
  std::optional<double> first_stamp;     // s, of the first timestamped message
  std::optional<double> last_stamp;      // s, of the last timestamped message
  /// Laser odometry increments repaired for reversing (some or all of their travel), and whether the repair
  /// switched itself off because the log's poses record reversing themselves.
  std::size_t odometry_steps_reversed = 0;
  bool odometry_poses_record_reversing = false;
  /// FLASER/RLASER geometries in the order they were decided (one per laser and beam count).
  std::vector<OldLaserGeometry> old_laser_geometries;
  /// The front (FLASER) geometry used by the most scans, or null when the log has no FLASER.
  const OldLaserGeometry* front_geometry() const;
};

class CarmenReader {
 public:
  /// Opens the log. Throws Error("PATH: cannot open: ...") if it cannot be read, and Error when an
  /// option is out of range (field of view outside (0, 2 pi], non-positive increment or range).
  explicit CarmenReader(const std::string& path, CarmenReaderOptions options = {});
  ~CarmenReader();
  CarmenReader(CarmenReader&&) noexcept;
  CarmenReader& operator=(CarmenReader&&) noexcept;

  /// The next message in file order, or nullopt at the end. Throws ParseError("PATH:LINE: ...")
  /// on a malformed line: wrong field count, a non-number, NaN/inf/negative ranges,
  /// non-finite poses or timestamps; and at a PARAM line whose geometry contradicts the beam
  /// count, the other PARAM lines and the convention in every unit (thrown at the first laser line).
  std::optional<SensorMessage> next();
  /// Counts so far (complete once next() has returned nullopt).
  const CarmenStats& stats() const;
  /// Fraction of the file read so far, in [0, 1] (for progress display; gzip files use the
  /// uncompressed size from the gzip trailer); negative when the size is unknown.
  double progress() const;
  const std::string& path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Writes a CARMEN log atomically (gzip when the path ends in .gz). Nothing appears at `path`
/// until commit(). Numbers are written in their shortest exact form, so reading gives back
/// exactly what was written.
class CarmenWriter {
 public:
  explicit CarmenWriter(const std::string& path);
  ~CarmenWriter();
  CarmenWriter(CarmenWriter&&) noexcept;
  CarmenWriter& operator=(CarmenWriter&&) noexcept;

  void write_comment(const std::string& text);
  /// PARAM name value.
  void write_param(const std::string& name, const std::string& value, double stamp);
  /// FLASER/RLASER as the old format; ROBOTLASER1 and RAWLASER* in their own format.
  void write(const LaserMessage& message);
  void write(const OdometryMessage& message);
  void write(const TruePoseMessage& message);
  /// Any message; false for one CARMEN has no line for (an IMU reading), which is not written.
  bool write(const SensorMessage& message);
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam2d
