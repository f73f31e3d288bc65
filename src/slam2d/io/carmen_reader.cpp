// Reader for CARMEN 0.7 logger files (carmen/src/logger, "message formats defined: ...").
//
// Every message ends in "ipc_timestamp ipc_hostname logger_timestamp"; old logs may stop after
// ipc_timestamp (or after the hostname), so 1 to 3 trailing fields are accepted. The ipc timestamp
// is the message's stamp. Numbers are parsed strictly (std::from_chars, whole token, finite;
// ranges also non-negative). The reader holds one line at a time.
//
// CARMEN parameters used for the old FLASER/RLASER messages (carmen.ini names; front / rear):
//   laser_front_laser_fov          / laser_rear_laser_fov           field of view, degrees
//   laser_front_laser_resolution   / laser_rear_laser_resolution    angle between beams, degrees
//   robot_frontlaser_offset        / robot_rearlaser_offset         x of the sensor on the robot, m
//   robot_frontlaser_side_offset   / robot_rearlaser_side_offset    y of the sensor on the robot, m
//   robot_frontlaser_angular_offset/ robot_rearlaser_angular_offset sensor yaw on the robot, rad
//   robot_front_laser_max          / robot_rear_laser_max           maximum range, m
// Offsets are taken in the robot frame (x forward, y left), so a rear scanner behind the centre
// has a negative robot_rearlaser_offset. The rear scanner faces backwards: its yaw is
// robot_rearlaser_angular_offset + pi.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string_view>
#include <utility>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/number_format.hpp"
#include "slam2d/io/text_input.hpp"

namespace slam2d {

namespace {

// ---------------------------------------------------------------------------------------------
// Tokens and numbers.

// Why `token` (parsed as `value`) is not a finite number; empty when it is one.
std::string number_problem(std::string_view token, const std::optional<double>& value) {
  if (!value) return "is not a number: '" + std::string(token) + "'";
  if (std::isnan(*value)) return "is NaN";
  if (std::isinf(*value)) return "is infinite or out of range: '" + std::string(token) + "'";
  return {};
}

// ---------------------------------------------------------------------------------------------
// One line's fields, with error messages that name the message type and the field.

class Fields {
 public:
  Fields(const LineReader& reader, const std::vector<std::string_view>& tokens)
      : reader_(reader), tokens_(tokens) {}

  std::size_t size() const { return tokens_.size(); }
  std::string_view type() const { return tokens_[0]; }
  std::string_view token(std::size_t i) const { return tokens_[i]; }

  [[noreturn]] void fail(const std::string& message) const {
    reader_.fail(std::string(type()) + ": " + message);
  }

  /// A finite number.
  double number(std::size_t i, std::string_view name) const {
    const std::optional<double> value = parse_double(tokens_[i]);
    const std::string problem = number_problem(tokens_[i], value);
    if (!problem.empty()) fail(std::string(name) + " " + problem);
    return *value;
  }

  /// A count (a non-negative integer).
  std::size_t count(std::size_t i, std::string_view name) const {
    const std::string_view t = tokens_[i];
    std::size_t value = 0;
    const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
    if (ec != std::errc() || ptr != t.data() + t.size()) {
      fail(std::string(name) + " is not a count: '" + std::string(t) + "'");
    }
    return value;
  }

  /// `n` values starting at token `first`: finite, and non-negative unless `allow_negative`.
  std::vector<double> values(std::size_t first, std::size_t n, std::string_view name,
                             bool allow_negative) const {
    std::vector<double> out(n);
    for (std::size_t k = 0; k < n; ++k) {
      const std::string_view t = tokens_[first + k];
      const std::optional<double> value = parse_double(t);
      const std::string problem = number_problem(t, value);
      if (!problem.empty()) fail(value_name(name, k, n) + " " + problem);
      out[k] = *value;
      if (!allow_negative && out[k] < 0.0) fail(value_name(name, k, n) + " is negative: " + std::string(t));
    }
    return out;
  }

  SE2 pose(std::size_t i, std::string_view prefix) const {
    const std::string p(prefix);
    return SE2(number(i, p + "x"), number(i + 1, p + "y"), number(i + 2, p + "theta"));
  }

  /// The trailing "ipc_timestamp [ipc_hostname [logger_timestamp]]" from token `i`; returns the stamp.
  double stamp_tail(std::size_t i) const {
    const double stamp = number(i, "ipc_timestamp");
    if (i + 2 < tokens_.size()) number(i + 2, "logger_timestamp");
    return stamp;
  }

 private:
  static std::string value_name(std::string_view name, std::size_t k, std::size_t n) {
    return std::string(name) + " " + std::to_string(k + 1) + " of " + std::to_string(n);
  }

  const LineReader& reader_;
  const std::vector<std::string_view>& tokens_;
};

constexpr std::size_t kMinTail = 1;  // ipc_timestamp
constexpr std::size_t kMaxTail = 3;  // ipc_timestamp ipc_hostname logger_timestamp

bool tail_fits(std::size_t available, std::size_t fixed) {
  return available >= fixed + kMinTail && available <= fixed + kMaxTail;
}

// ---------------------------------------------------------------------------------------------
// Geometry of the old FLASER/RLASER messages, from PARAM lines.

struct OldLaserParams {
  std::optional<double> field_of_view;    // rad
  std::optional<double> angle_increment;  // rad
  std::optional<double> range_max;        // m
  double offset_x = 0.0;                  // m
  double offset_y = 0.0;                  // m
  double offset_theta = 0.0;              // rad
};

enum class ParamKind { kFieldOfViewDeg, kResolutionDeg, kRangeMax, kOffsetX, kOffsetY, kOffsetTheta };

struct ParamBinding {
  std::string_view name;
  bool rear;
  ParamKind kind;
};

constexpr ParamBinding kParamBindings[] = {
    {"laser_front_laser_fov", false, ParamKind::kFieldOfViewDeg},
    {"laser_front_laser_resolution", false, ParamKind::kResolutionDeg},
    {"robot_front_laser_max", false, ParamKind::kRangeMax},
    {"robot_frontlaser_offset", false, ParamKind::kOffsetX},
    {"robot_frontlaser_side_offset", false, ParamKind::kOffsetY},
    {"robot_frontlaser_angular_offset", false, ParamKind::kOffsetTheta},
    {"laser_rear_laser_fov", true, ParamKind::kFieldOfViewDeg},
    {"laser_rear_laser_resolution", true, ParamKind::kResolutionDeg},
    {"robot_rear_laser_max", true, ParamKind::kRangeMax},
    {"robot_rearlaser_offset", true, ParamKind::kOffsetX},
    {"robot_rearlaser_side_offset", true, ParamKind::kOffsetY},
    {"robot_rearlaser_angular_offset", true, ParamKind::kOffsetTheta},
};

void apply_param(OldLaserParams& params, ParamKind kind, double value, const Fields& fields) {
  const bool must_be_positive =
      kind == ParamKind::kFieldOfViewDeg || kind == ParamKind::kResolutionDeg || kind == ParamKind::kRangeMax;
  if (must_be_positive && !(value > 0.0)) {
    fields.fail(std::string(fields.token(1)) + " must be positive, got " + std::string(fields.token(2)));
  }
  switch (kind) {
    case ParamKind::kFieldOfViewDeg: params.field_of_view = deg_to_rad(value); break;
    case ParamKind::kResolutionDeg: params.angle_increment = deg_to_rad(value); break;
    case ParamKind::kRangeMax: params.range_max = value; break;
    case ParamKind::kOffsetX: params.offset_x = value; break;
    case ParamKind::kOffsetY: params.offset_y = value; break;
    case ParamKind::kOffsetTheta: params.offset_theta = value; break;
  }
}

// The uncompressed size of the file in bytes: the gzip trailer's ISIZE (size mod 2^32 of the
// last member) for gzip files, else the file size; negative when it cannot be found.
double uncompressed_size(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char magic[2] = {0, 0};
  if (!in.read(reinterpret_cast<char*>(magic), 2)) return -1.0;
  if (magic[0] != 0x1f || magic[1] != 0x8b) {
    std::error_code error;
    const auto size = std::filesystem::file_size(path, error);
    return error ? -1.0 : static_cast<double>(size);
  }
  unsigned char isize[4] = {0, 0, 0, 0};
  if (!in.seekg(-4, std::ios::end) || !in.read(reinterpret_cast<char*>(isize), 4)) return -1.0;
  return static_cast<double>(isize[0] | (isize[1] << 8) | (isize[2] << 16) | (std::uint32_t{isize[3]} << 24));
}

}  // namespace

// -----------------------------------------------------------------------------------------------

struct CarmenReader::Impl {
  Impl(const std::string& path, CarmenReaderOptions opts)
      : reader(path), options(opts), total_bytes(uncompressed_size(path)) {}

  std::optional<CarmenMessage> parse_line(const Fields& fields);
  void parse_param(const Fields& fields);
  LaserMessage parse_old_laser(const Fields& fields, bool rear) const;
  void set_old_laser_geometry(LaserMessage& message, std::size_t n, bool rear) const;
  LaserMessage parse_new_laser(const Fields& fields, bool robot_laser) const;
  std::pair<std::size_t, std::size_t> new_laser_counts(const Fields& fields, std::size_t fixed_tail) const;
  OdometryMessage parse_odometry(const Fields& fields) const;
  TruePoseMessage parse_true_pose(const Fields& fields) const;
  void note_stamp(double stamp, bool is_laser);

  LineReader reader;
  CarmenReaderOptions options;
  CarmenStats stats;
  OldLaserParams front;
  OldLaserParams rear;
  std::string line;
  std::vector<std::string_view> tokens;
  std::optional<double> previous_stamp;
  std::optional<double> previous_laser_stamp;
  double total_bytes;      // uncompressed size, negative if unknown
  double bytes_read = 0.0;  // uncompressed bytes of the lines read so far
};

std::optional<CarmenMessage> CarmenReader::Impl::parse_line(const Fields& fields) {
  const std::string_view type = fields.type();
  if (type == "FLASER" || type == "RLASER") return parse_old_laser(fields, type == "RLASER");
  if (type == "ROBOTLASER1") return parse_new_laser(fields, true);
  if (type.size() == 9 && type.starts_with("RAWLASER") && type[8] >= '1' && type[8] <= '4') {
    return parse_new_laser(fields, false);
  }
  if (type == "ODOM") return parse_odometry(fields);
  if (type == "TRUEPOS") return parse_true_pose(fields);
  if (type == "PARAM") {
    parse_param(fields);
    return std::nullopt;
  }
  ++stats.skipped_lines;
  ++stats.skipped_types[std::string(type)];
  return std::nullopt;
}

// PARAM name value [ipc_timestamp ipc_hostname logger_timestamp]. Some old logs write only
// "name value hostname logger_timestamp", so the stamp fields are not interpreted; a PARAM is
// configuration, not a timestamped message.
void CarmenReader::Impl::parse_param(const Fields& fields) {
  if (fields.size() < 3 || fields.size() > 6) {
    fields.fail("expected name value [ipc_timestamp ipc_hostname logger_timestamp], got " +
                std::to_string(fields.size() - 1) + " tokens");
  }
  ++stats.param_messages;
  for (const ParamBinding& binding : kParamBindings) {
    if (binding.name != fields.token(1)) continue;
    const double value = fields.number(2, std::string(binding.name) + " value");
    apply_param(binding.rear ? rear : front, binding.kind, value, fields);
  }
}

// FLASER|RLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta ipc_timestamp [host [logger_ts]]
LaserMessage CarmenReader::Impl::parse_old_laser(const Fields& fields, bool is_rear) const {
  if (fields.size() < 2) fields.fail("missing num_readings");
  const std::size_t n = fields.count(1, "num_readings");
  const std::size_t available = fields.size() - 2;
  if (available < n || !tail_fits(available - n, 6)) {
    fields.fail("expected " + std::to_string(n) + " ranges + 9 fields, got " + std::to_string(available) +
                " tokens");
  }
  LaserMessage message;
  message.type = std::string(fields.type());
  message.line = reader.line_number();
  message.scan.ranges = fields.values(2, n, "range", false);
  message.laser_pose = fields.pose(2 + n, "");
  message.odom_pose = fields.pose(5 + n, "odom_");
  message.scan.stamp = fields.stamp_tail(8 + n);
  set_old_laser_geometry(message, n, is_rear);
  return message;
}

// The CARMEN convention (see carmen.hpp), then PARAM values, then the reader options.
void CarmenReader::Impl::set_old_laser_geometry(LaserMessage& message, std::size_t n, bool is_rear) const {
  const OldLaserParams& params = is_rear ? rear : front;
  const double fov = options.field_of_view.value_or(params.field_of_view.value_or(std::numbers::pi));
  const bool odd = n % 2 == 1 && n > 1;
  const double steps = odd ? static_cast<double>(n - 1) : static_cast<double>(std::max<std::size_t>(n, 1));
  LaserScan& scan = message.scan;
  message.field_of_view = fov;
  scan.angle_increment = options.angle_increment.value_or(params.angle_increment.value_or(fov / steps));
  scan.angle_min = options.angle_min.value_or(-0.5 * fov);
  scan.range_min = options.range_min;
  scan.range_max = options.range_max.value_or(params.range_max.value_or(options.default_range_max));
  const double yaw = params.offset_theta + (is_rear ? std::numbers::pi : 0.0);
  scan.T_robot_sensor = SE2(params.offset_x, params.offset_y, yaw);
}

// ROBOTLASER1|RAWLASERk laser_type start_angle field_of_view angular_resolution maximum_range
//   accuracy remission_mode n r_1 .. r_n m i_1 .. i_m
//   [ROBOTLASER1 only: laser_x laser_y laser_theta robot_x robot_y robot_theta laser_tv laser_rv
//    forward_safety_dist side_safety_dist turn_axis] ipc_timestamp [host [logger_ts]]
LaserMessage CarmenReader::Impl::parse_new_laser(const Fields& fields, bool robot_laser) const {
  constexpr std::size_t kFirstRange = 9;
  const std::size_t fixed_tail = robot_laser ? 11 : 0;
  const auto [n, m] = new_laser_counts(fields, fixed_tail);
  LaserMessage message;
  message.type = std::string(fields.type());
  message.line = reader.line_number();
  LaserScan& scan = message.scan;
  fields.number(1, "laser_type");
  scan.angle_min = fields.number(2, "start_angle");
  message.field_of_view = fields.number(3, "field_of_view");
  scan.angle_increment = fields.number(4, "angular_resolution");
  scan.range_max = fields.number(5, "maximum_range");
  if (!(scan.range_max > 0.0)) fields.fail("maximum_range must be positive, got " + std::string(fields.token(5)));
  fields.number(6, "accuracy");
  fields.number(7, "remission_mode");
  scan.range_min = options.range_min;
  scan.ranges = fields.values(kFirstRange, n, "range", false);
  scan.intensities = fields.values(kFirstRange + n + 1, m, "remission", true);
  std::size_t i = kFirstRange + n + 1 + m;
  if (robot_laser) {
    message.laser_pose = fields.pose(i, "laser_");
    message.odom_pose = fields.pose(i + 3, "robot_");
    constexpr const char* kRest[] = {"laser_tv", "laser_rv", "forward_safety_dist", "side_safety_dist", "turn_axis"};
    for (std::size_t k = 0; k < 5; ++k) fields.number(i + 6 + k, kRest[k]);
    scan.T_robot_sensor = message.odom_pose.between(message.laser_pose);
    i += fixed_tail;
  } else {
    message.has_poses = false;
  }
  scan.stamp = fields.stamp_tail(i);
  return message;
}

// The counts (num_readings, num_remissions) of a ROBOTLASER1/RAWLASER line, checked against its length.
std::pair<std::size_t, std::size_t> CarmenReader::Impl::new_laser_counts(const Fields& fields,
                                                                          std::size_t fixed_tail) const {
  if (fields.size() < 10) {
    fields.fail("expected 7 fields and num_readings, got " + std::to_string(fields.size() - 1) + " tokens");
  }
  const std::size_t n = fields.count(8, "num_readings");
  const std::size_t available = fields.size() - 9;  // tokens after num_readings
  const bool has_m = available > n;
  const std::size_t m = has_m ? fields.count(9 + n, "num_remissions") : 0;
  if (!has_m || available - n - 1 < m || !tail_fits(available - n - 1 - m, fixed_tail)) {
    fields.fail("expected " + std::to_string(n) + " ranges + num_remissions + " +
                (has_m ? std::to_string(m) : std::string("?")) + " remissions + " +
                std::to_string(fixed_tail + kMaxTail) + " fields, got " + std::to_string(available) +
                " tokens after num_readings");
  }
  if (m != 0 && m != n) fields.fail(std::to_string(m) + " remissions for " + std::to_string(n) + " ranges");
  return {n, m};
}

// ODOM x y theta tv rv accel ipc_timestamp [host [logger_ts]]
OdometryMessage CarmenReader::Impl::parse_odometry(const Fields& fields) const {
  if (!tail_fits(fields.size() - 1, 6)) {
    fields.fail("expected 9 fields (x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp), got " +
                std::to_string(fields.size() - 1) + " tokens");
  }
  OdometryMessage message;
  message.line = reader.line_number();
  message.reading.pose = fields.pose(1, "");
  message.reading.tv = fields.number(4, "tv");
  message.reading.rv = fields.number(5, "rv");
  fields.number(6, "accel");
  message.reading.stamp = fields.stamp_tail(7);
  return message;
}

// TRUEPOS true_x true_y true_theta odom_x odom_y odom_theta ipc_timestamp [host [logger_ts]]
TruePoseMessage CarmenReader::Impl::parse_true_pose(const Fields& fields) const {
  if (!tail_fits(fields.size() - 1, 6)) {
    fields.fail("expected 9 fields (true_x true_y true_theta odom_x odom_y odom_theta ipc_timestamp "
                "ipc_hostname logger_timestamp), got " + std::to_string(fields.size() - 1) + " tokens");
  }
  TruePoseMessage message;
  message.line = reader.line_number();
  message.true_pose = fields.pose(1, "true_");
  message.odom_pose = fields.pose(4, "odom_");
  message.stamp = fields.stamp_tail(7);
  return message;
}

void CarmenReader::Impl::note_stamp(double stamp, bool is_laser) {
  if (previous_stamp && stamp < *previous_stamp) ++stats.backwards_timestamps;
  previous_stamp = stamp;
  if (is_laser) {
    if (previous_laser_stamp && stamp < *previous_laser_stamp) ++stats.backwards_laser_timestamps;
    previous_laser_stamp = stamp;
  }
  if (!stats.first_stamp) stats.first_stamp = stamp;
  stats.last_stamp = stamp;
}

// -----------------------------------------------------------------------------------------------

CarmenReader::CarmenReader(const std::string& path, CarmenReaderOptions options)
    : impl_(std::make_unique<Impl>(path, options)) {}

CarmenReader::~CarmenReader() = default;
CarmenReader::CarmenReader(CarmenReader&&) noexcept = default;
CarmenReader& CarmenReader::operator=(CarmenReader&&) noexcept = default;

std::optional<CarmenMessage> CarmenReader::next() {
  if (!impl_) throw Error("CarmenReader: used after move");
  Impl& s = *impl_;
  while (s.reader.next(s.line)) {
    ++s.stats.lines;
    s.bytes_read += static_cast<double>(s.line.size() + 1);
    split_fields(s.line, s.tokens);
    if (s.tokens.empty() || s.tokens[0].front() == '#') {
      ++s.stats.comment_lines;
      continue;
    }
    std::optional<CarmenMessage> message = s.parse_line(Fields(s.reader, s.tokens));
    if (!message) continue;
    if (auto* laser = std::get_if<LaserMessage>(&*message)) {
      ++s.stats.laser_messages;
      s.note_stamp(laser->scan.stamp, true);
    } else if (auto* odometry = std::get_if<OdometryMessage>(&*message)) {
      ++s.stats.odometry_messages;
      s.note_stamp(odometry->reading.stamp, false);
    } else {
      ++s.stats.true_pose_messages;
      s.note_stamp(std::get<TruePoseMessage>(*message).stamp, false);
    }
    return message;
  }
  return std::nullopt;
}

const CarmenStats& CarmenReader::stats() const {
  if (!impl_) throw Error("CarmenReader: used after move");
  return impl_->stats;
}

double CarmenReader::progress() const {
  if (!impl_) throw Error("CarmenReader: used after move");
  if (impl_->total_bytes < 0.0) return -1.0;
  if (impl_->total_bytes == 0.0) return 1.0;
  return std::min(1.0, impl_->bytes_read / impl_->total_bytes);
}

const std::string& CarmenReader::path() const {
  if (!impl_) throw Error("CarmenReader: used after move");
  return impl_->reader.path();
}

}  // namespace slam2d
