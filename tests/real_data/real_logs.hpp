// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Public CARMEN logs read whole for the real-data tests: their messages, with a fault injected as
// `slam2d perturb` does, their laser messages, and the relations of a short span.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "slam2d/core/relation.hpp"
#include "slam2d/core/sensor_log.hpp"
#include "slam2d/core/trajectory.hpp"
#include "slam2d/io/carmen.hpp"

namespace slam2d::test {

/// Every message of the CARMEN log, in file order (CarmenReader with `options`).
std::vector<SensorMessage> read_log(const std::filesystem::path& log, const CarmenReaderOptions& options = {});

/// The same with `fault` (a spec for parse_fault) applied with `seed`, as `slam2d perturb --fault
/// FAULT --seed SEED` does it to the messages it reads.
std::vector<SensorMessage> read_log_with_fault(const std::filesystem::path& log, const std::string& fault,
                                               std::uint64_t seed = 1);
/// Several faults in order, as several --fault options do.
std::vector<SensorMessage> read_log_with_faults(const std::filesystem::path& log, const std::vector<std::string>& faults,
                                                std::uint64_t seed = 1);

/// The log's scans with its odometry moved `by` s ahead of the laser (`odom-shift:by=BY`), that
/// offset estimated from the data and compensated, as `slam2d map` does with
/// --odometry-time-offset auto.
struct ScansOutOfStep {
  std::vector<LaserMessage> scans;
  double estimate = 0.0;  // s, the offset estimated
};
ScansOutOfStep read_scans_out_of_step(const std::filesystem::path& log, double by);

/// The laser messages, in order, moved out of `messages`.
std::vector<LaserMessage> laser_messages(std::vector<SensorMessage> messages);

/// A SLAM-corrected log's FLASER scans (their odometry is the corrected trajectory itself), each
/// stamped by its index as the robustness benchmark does (Freiburg campus's stamps do not
/// increase), and that trajectory as the reference.
struct CorrectedScans {
  std::vector<LaserMessage> scans;
  Trajectory reference;
};
CorrectedScans read_corrected_flaser(const std::filesystem::path& log);

/// The relations whose two stamps are at most `seconds` apart (|stamp_to - stamp_from| <= seconds), in order.
std::vector<Relation> relations_at_most(std::vector<Relation> relations, double seconds);

}  // namespace slam2d::test
