// SPDX-License-Identifier: BSD-3-Clause
// Trajectory files: slam2d text ("timestamp x y theta") and TUM RGB-D ("timestamp tx ty tz qx qy qz qw",
// Sturm et al. 2012, "A benchmark for the evaluation of RGB-D SLAM systems").
#include "slam2d/io/trajectory_io.hpp"

#include <array>
#include <cmath>
#include <string_view>
#include <vector>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/detail/number_format.hpp"
#include "slam2d/io/detail/text_input.hpp"

namespace slam2d {

namespace {

constexpr std::array<std::string_view, 4> kTextFields = {"timestamp", "x", "y", "theta"};
constexpr std::array<std::string_view, 8> kTumFields = {"timestamp", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
constexpr double kMaxQuaternionNormError = 5e-3;  // accepted | |q| - 1 | (files print few digits)

struct Quaternion {
  double x, y, z, w;
};

// Yaw of a rotation quaternion. A pure rotation about z uses 2 atan2(qz, qw), which the TUM writer
// makes exact; otherwise the z-y-x Euler yaw atan2(2 (w z + x y), w^2 + x^2 - y^2 - z^2).
double quaternion_yaw(const Quaternion& q) {
  if (q.x == 0.0 && q.y == 0.0) return normalize_angle(2.0 * std::atan2(q.z, q.w));
  return normalize_angle(std::atan2(2.0 * (q.w * q.z + q.x * q.y), q.w * q.w + q.x * q.x - q.y * q.y - q.z * q.z));
}

// (qz, qw) of a rotation by `theta` about z. Of the doubles within one ulp of (sin, cos)(theta / 2),
// picks a pair that quaternion_yaw() maps back to exactly `theta`, so write -> read is exact.
std::pair<double, double> yaw_quaternion(double theta) {
  const double qz = std::sin(0.5 * theta);
  const double qw = std::cos(0.5 * theta);
  if (quaternion_yaw({0.0, 0.0, qz, qw}) == theta) return {qz, qw};
  const std::array<double, 3> z_candidates = {qz, std::nextafter(qz, -2.0), std::nextafter(qz, 2.0)};
  const std::array<double, 3> w_candidates = {qw, std::nextafter(qw, -2.0), std::nextafter(qw, 2.0)};
  for (double z : z_candidates) {
    for (double w : w_candidates) {
      if (quaternion_yaw({0.0, 0.0, z, w}) == theta) return {z, w};
    }
  }
  return {qz, qw};  // only subnormal angles get here; the yaw read back is then off by < 1e-300 rad
}

// Reads the data lines of a trajectory file with `N` numbers per line.
template <std::size_t N, typename MakePose>
Trajectory read_stamped_lines(const std::string& path, const std::array<std::string_view, N>& names,
                              MakePose make_pose) {
  LineReader reader(path);
  Trajectory trajectory;
  std::string line;
  std::array<double, N> values{};
  while (reader.next(line)) {
    if (is_blank_or_comment(line)) continue;
    const std::vector<std::string_view> fields = split_fields(line);
    if (fields.size() != N) {
      reader.fail("expected " + std::to_string(N) + " numbers, got " + std::to_string(fields.size()));
    }
    for (std::size_t i = 0; i < N; ++i) values[i] = parse_finite_field(reader, fields[i], names[i]);
    trajectory.push_back(values[0], make_pose(reader, values));
  }
  return trajectory;
}

// Writes one line per pose: `header`, then the numbers from `values_of(pose)` separated by spaces.
template <typename ValuesOf>
void write_stamped_lines(const std::string& path, const Trajectory& trajectory, std::string_view header,
                         ValuesOf values_of) {
  AtomicFile file(path, has_gzip_extension(path));
  file.stream() << header << '\n';
  std::string text;
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const StampedPose& p = trajectory[i];
    if (!std::isfinite(p.stamp) || !p.pose.vector().allFinite()) {
      throw Error(path + ": pose " + std::to_string(i) + " has a non-finite value");
    }
    text.clear();
    for (double value : values_of(p)) {
      if (!text.empty()) text += ' ';
      append_number(text, value);
    }
    text += '\n';
    file.stream() << text;
  }
  file.commit();
}

}  // namespace

Trajectory read_trajectory(const std::string& path) {
  return read_stamped_lines(path, kTextFields, [](const LineReader&, const std::array<double, 4>& v) {
    return SE2(v[1], v[2], v[3]);
  });
}

void write_trajectory(const std::string& path, const Trajectory& trajectory) {
  write_stamped_lines(path, trajectory, "# timestamp x y theta", [](const StampedPose& p) {
    return std::array<double, 4>{p.stamp, p.pose.x(), p.pose.y(), p.pose.theta()};
  });
}

Trajectory read_trajectory_tum(const std::string& path) {
  return read_stamped_lines(path, kTumFields, [](const LineReader& reader, const std::array<double, 8>& v) {
    const Quaternion q{v[4], v[5], v[6], v[7]};
    const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
    if (std::abs(norm - 1.0) > kMaxQuaternionNormError) {
      reader.fail("quaternion is not a unit quaternion: norm " + format_number(norm));
    }
    return SE2(v[1], v[2], quaternion_yaw(q));  // tz and any tilt are dropped in 2D
  });
}

void write_trajectory_tum(const std::string& path, const Trajectory& trajectory) {
  write_stamped_lines(path, trajectory, "# timestamp tx ty tz qx qy qz qw", [](const StampedPose& p) {
    const auto [qz, qw] = yaw_quaternion(p.pose.theta());
    return std::array<double, 8>{p.stamp, p.pose.x(), p.pose.y(), 0.0, 0.0, 0.0, qz, qw};
  });
}

TrajectoryFormat trajectory_format_from_name(const std::string& name) {
  if (name == "text") return TrajectoryFormat::kText;
  if (name == "tum") return TrajectoryFormat::kTum;
  throw Error("unknown trajectory format '" + name + "' (known: text, tum)");
}

TrajectoryFormat detect_trajectory_format(const std::string& path) {
  LineReader reader(path);
  std::string line;
  while (reader.next(line)) {
    if (is_blank_or_comment(line)) continue;
    const std::size_t fields = split_fields(line).size();
    if (fields == kTextFields.size()) return TrajectoryFormat::kText;
    if (fields == kTumFields.size()) return TrajectoryFormat::kTum;
    reader.fail("expected 4 numbers (timestamp x y theta) or 8 (TUM: timestamp tx ty tz qx qy qz qw), got " +
                std::to_string(fields));
  }
  return TrajectoryFormat::kText;  // no data line: an empty trajectory either way
}

Trajectory read_any_trajectory(const std::string& path) {
  return detect_trajectory_format(path) == TrajectoryFormat::kTum ? read_trajectory_tum(path) : read_trajectory(path);
}

void write_trajectory(const std::string& path, const Trajectory& trajectory, TrajectoryFormat format) {
  if (format == TrajectoryFormat::kTum) {
    write_trajectory_tum(path, trajectory);
  } else {
    write_trajectory(path, trajectory);
  }
}

}  // namespace slam2d
