// SPDX-License-Identifier: BSD-3-Clause
#include "real_data/real_logs.hpp"

#include <cmath>
#include <utility>
#include <variant>

#include "slam2d/core/error.hpp"
#include "slam2d/core/odometry_chain.hpp"
#include "slam2d/registration/odometry_time_offset.hpp"
#include "slam2d/sim/fault_injection.hpp"

namespace slam2d::test {

std::vector<SensorMessage> read_log(const std::filesystem::path& log, const CarmenReaderOptions& options) {
  std::vector<SensorMessage> messages;
  CarmenReader reader(log.string(), options);
  while (auto message = reader.next()) messages.push_back(std::move(*message));
  return messages;
}

std::vector<SensorMessage> read_log_with_fault(const std::filesystem::path& log, const std::string& fault,
                                               std::uint64_t seed) {
  return read_log_with_faults(log, {fault}, seed);
}

ScansOutOfStep read_scans_out_of_step(const std::filesystem::path& log, double by) {
  std::vector<SensorMessage> messages = read_log_with_fault(log, "odom-shift:by=" + std::to_string(by));
  const OdometryTimeOffset offset = estimate_odometry_time_offset(messages);
  if (!offset.estimated) throw Error(log.string() + ": the odometry's time offset was not estimated: " + offset.reason);
  shift_scan_odometry(messages, -offset.offset);
  return {laser_messages(std::move(messages)), offset.offset};
}

std::vector<SensorMessage> read_log_with_faults(const std::filesystem::path& log, const std::vector<std::string>& faults,
                                                std::uint64_t seed) {
  std::vector<SensorMessage> messages = read_log(log);
  std::vector<Fault> parsed;
  for (const std::string& fault : faults) parsed.push_back(parse_fault(fault));
  apply_faults(parsed, messages, seed);
  return messages;
}

std::vector<LaserMessage> laser_messages(std::vector<SensorMessage> messages) {
  std::vector<LaserMessage> scans;
  for (SensorMessage& message : messages) {
    if (auto* laser = std::get_if<LaserMessage>(&message)) scans.push_back(std::move(*laser));
  }
  return scans;
}

CorrectedScans read_corrected_flaser(const std::filesystem::path& log) {
  CorrectedScans result;
  CarmenReader reader(log.string());
  while (auto message = reader.next()) {
    auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || laser->type != "FLASER") continue;
    laser->scan.stamp = static_cast<double>(result.reference.size());
    result.reference.push_back(laser->scan.stamp, laser->odom_pose);
    result.scans.push_back(std::move(*laser));
  }
  return result;
}

std::vector<Relation> relations_at_most(std::vector<Relation> relations, double seconds) {
  std::erase_if(relations, [seconds](const Relation& r) { return !(std::abs(r.stamp_to - r.stamp_from) <= seconds); });
  return relations;
}

}  // namespace slam2d::test
