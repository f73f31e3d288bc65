// SPDX-License-Identifier: BSD-3-Clause
#include "run_mcap_output.hpp"

#include <filesystem>

#include "slam2d/core/error.hpp"
#include "slam2d/io/run_mcap.hpp"

namespace slam2d::cli {

void write_run_mcap(const std::string& path, const std::string& log, const LogReaderOptions& input, bool front_only,
                    const OccupancyMap& map, const Trajectory& trajectory) {
  const std::filesystem::path out(path);
  if (out.has_parent_path()) std::filesystem::create_directories(out.parent_path());
  RunMcapWriter writer(path);
  LogReader reader(log, input);
  std::size_t k = 0;
  while (auto message = reader.next()) {
    const auto* laser = std::get_if<LaserMessage>(&*message);
    if (laser == nullptr || (front_only && laser->type == "RLASER")) continue;
    check(k < trajectory.size(), path + ": the log has more scans than the trajectory has poses");
    writer.add_scan(laser->scan, trajectory[k++].pose);
  }
  check(k == trajectory.size(), path + ": the log has fewer scans than the trajectory has poses");
  writer.commit(map, trajectory);
}

}  // namespace slam2d::cli
