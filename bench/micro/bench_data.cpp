#include "bench_data.hpp"

#include <cstdlib>
#include <filesystem>
#include <map>
#include <variant>

#include "slam2d/io/carmen.hpp"

namespace slam2d::bench {

const std::vector<LoggedScan>& logged_scans(const std::string& log, std::size_t count) {
  static std::map<std::string, std::vector<LoggedScan>> cache;
  auto [it, inserted] = cache.try_emplace(log);
  if (!inserted) return it->second;
  const char* data = std::getenv("SLAM2D_DATA");
  const std::filesystem::path path = std::filesystem::path(data ? data : "../shared/data") / log / (log + ".clf.gz");
  if (!std::filesystem::exists(path)) return it->second;
  CarmenReader reader(path.string());
  while (it->second.size() < count) {
    auto message = reader.next();
    if (!message) break;
    if (const auto* laser = std::get_if<LaserMessage>(&*message); laser && laser->type != "RLASER") {
      it->second.push_back({laser->scan, laser->odom_pose, laser->laser_pose});
    }
  }
  return it->second;
}

PointCloud2 sensor_cloud(const LaserScan& scan) { return to_point_cloud(scan, ScanFrame::kSensor).cloud; }

}  // namespace slam2d::bench
