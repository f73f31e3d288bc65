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
// ROBOTLASER1 and RAWLASER declare their own angles and maximum range; ROBOTLASER1's mounting is
// robot_pose^-1 * laser_pose, RAWLASER's is the identity (a raw scan has no robot).

#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <variant>

#include "slam2d/core/laser_scan.hpp"
#include "slam2d/core/odometry.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct LaserMessage {
  std::string type;   // "FLASER", "RLASER", "ROBOTLASER1", "RAWLASER1" .. "RAWLASER4"
  LaserScan scan;     // stamp = ipc timestamp, angles, ranges, T_robot_sensor
  double field_of_view = 0.0;  // rad, as declared by the log or the convention above
  SE2 laser_pose;     // the "x y theta" triple (estimated pose; raw logs repeat odometry)
  SE2 odom_pose;      // the robot's odometry pose at the scan (T_odom_robot); absent in RAWLASER
  bool has_poses = true;  // false for RAWLASER, which carries no pose
  std::size_t line = 0;   // 1-based line in the file
};

struct TruePoseMessage {
  double stamp = 0.0;  // s
  SE2 true_pose;
  SE2 odom_pose;
  std::size_t line = 0;
};

struct OdometryMessage {
  OdometryReading reading;
  std::size_t line = 0;
};

using CarmenMessage = std::variant<LaserMessage, OdometryMessage, TruePoseMessage>;

struct CarmenReaderOptions {
  /// Overrides for FLASER/RLASER geometry (rad); PARAM lines are used when these are unset.
  std::optional<double> field_of_view;
  std::optional<double> angle_increment;
  std::optional<double> angle_min;
  /// m. FLASER/RLASER carry no maximum range: readings at or above are "no return".
  /// A robot_front_laser_max / robot_rear_laser_max PARAM overrides the default.
  std::optional<double> range_max;
  double default_range_max = 80.0;  // m, SICK LMS in its 80 m mode (returns ~81.9 m for "no return")
  double range_min = 0.0;           // m
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
};

class CarmenReader {
 public:
  /// Opens the log. Throws Error("PATH: cannot open: ...") if it cannot be read.
  explicit CarmenReader(const std::string& path, CarmenReaderOptions options = {});
  ~CarmenReader();
  CarmenReader(CarmenReader&&) noexcept;
  CarmenReader& operator=(CarmenReader&&) noexcept;

  /// The next message in file order, or nullopt at the end. Throws ParseError("PATH:LINE: ...")
  /// on a malformed line: wrong field count, a non-number, NaN/inf/negative ranges,
  /// non-finite poses or timestamps.
  std::optional<CarmenMessage> next();
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
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam2d
