// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/rosbag2_writer.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <map>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/detail/cdr.hpp"
#include "slam2d/io/rosbag2.hpp"

namespace slam2d {
namespace {

namespace fs = std::filesystem;

// Humble's offered_qos_profiles string: reliable; /tf_static transient local (latched).
std::string qos_profile(bool latched) {
  return fmt::format(
      "- history: 3\n  depth: 0\n  reliability: 1\n  durability: {}\n  deadline:\n    sec: 2147483647\n    nsec: 4294967295\n"
      "  lifespan:\n    sec: 2147483647\n    nsec: 4294967295\n  liveliness: 1\n  liveliness_lease_duration:\n"
      "    sec: 2147483647\n    nsec: 4294967295\n  avoid_ros_namespace_conventions: false",
      latched ? 1 : 2);
}

// A YAML double-quoted scalar.
std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    out += c;
  }
  return out + "\"";
}

struct TopicInfo {
  std::string type;
  std::size_t count = 0;
};

class Rosbag2Sink final : public BagSink {
 public:
  Rosbag2Sink(const std::string& folder, McapWriterOptions options)
      : folder_(fs::path(folder).lexically_normal()),
        staging_(fs::path(folder_.string() + ".tmp-slam2d")),
        storage_name_(folder_.filename().string() + "_0.mcap") {
    std::error_code error;
    if (fs::exists(folder_, error) && !is_rosbag2(folder_.string())) {
      throw Error(folder + ": exists and is not a rosbag2 folder; not overwritten");
    }
    fs::remove_all(staging_, error);
    fs::create_directories(staging_, error);
    if (error) throw Error(staging_.string() + ": cannot create: " + error.message());
    writer_ = open_mcap_writer((staging_ / storage_name_).string(), std::move(options));
  }

  ~Rosbag2Sink() override {
    writer_.reset();  // removes its temporary file
    std::error_code error;
    if (!committed_) fs::remove_all(staging_, error);
  }

  void write(const std::string& topic, double receive_time, const DecodedMessage& message) override {
    writer_->write(topic, receive_time, message);
    if (topics_.find(topic) == topics_.end()) order_.push_back(topic);
    TopicInfo& info = topics_[topic];
    info.type = detail::ros2_type_name(message);
    ++info.count;
    const std::uint64_t ns = seconds_to_nanoseconds(receive_time);
    first_ = std::min(first_, ns);
    last_ = std::max(last_, ns);
  }

  void commit() override {
    writer_->commit();
    write_file_atomically((staging_ / "metadata.yaml").string(), metadata());
    std::error_code error;
    const fs::path old(folder_.string() + ".old-slam2d");
    fs::remove_all(old, error);
    if (fs::exists(folder_, error)) fs::rename(folder_, old, error);
    if (error) throw Error(folder_.string() + ": cannot replace: " + error.message());
    rename_durably(staging_.string(), folder_.string());  // the staging folder's entries synced, then the parent's
    committed_ = true;
    fs::remove_all(old, error);
  }

 private:
  std::string metadata() const {
    std::size_t total = 0;
    for (const auto& [name, info] : topics_) total += info.count;
    const std::uint64_t start = total == 0 ? 0 : first_;
    const std::uint64_t duration = total == 0 ? 0 : last_ - first_;
    std::string yaml = "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: mcap\n";
    yaml += fmt::format("  duration:\n    nanoseconds: {}\n  starting_time:\n    nanoseconds_since_epoch: {}\n", duration, start);
    yaml += fmt::format("  message_count: {}\n  topics_with_message_count:\n", total);
    for (const std::string& name : order_) {
      const TopicInfo& info = topics_.at(name);
      yaml += fmt::format("    - topic_metadata:\n        name: {}\n        type: {}\n        serialization_format: cdr\n"
                          "        offered_qos_profiles: {}\n      message_count: {}\n",
                          quoted(name), info.type, quoted(qos_profile(name == "/tf_static")), info.count);
    }
    yaml += "  compression_format: \"\"\n  compression_mode: \"\"\n";
    yaml += fmt::format("  relative_file_paths:\n    - {}\n", storage_name_);
    yaml += fmt::format("  files:\n    - path: {}\n      starting_time:\n        nanoseconds_since_epoch: {}\n"
                        "      duration:\n        nanoseconds: {}\n      message_count: {}\n",
                        storage_name_, start, duration, total);
    return yaml;
  }

  fs::path folder_;
  fs::path staging_;
  std::string storage_name_;
  std::unique_ptr<BagSink> writer_;
  std::map<std::string, TopicInfo> topics_;
  std::vector<std::string> order_;  // topics in the order first written
  std::uint64_t first_ = std::numeric_limits<std::uint64_t>::max();
  std::uint64_t last_ = 0;
  bool committed_ = false;
};

}  // namespace

std::unique_ptr<BagSink> open_rosbag2_writer(const std::string& folder, McapWriterOptions options) {
  return std::make_unique<Rosbag2Sink>(folder, std::move(options));
}

}  // namespace slam2d
