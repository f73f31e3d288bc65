// SPDX-License-Identifier: BSD-3-Clause
#include "targets.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <span>
#include <stdexcept>
#include <string_view>

#include "slam2d/core/error.hpp"
#include "slam2d/io/config_file.hpp"
#include "slam2d/io/detail/cdr.hpp"
#include "slam2d/io/detail/ros1_messages.hpp"
#include "slam2d/io/log_reader.hpp"
#include "slam2d/io/map_io.hpp"
#include "slam2d/io/pose_graph_io.hpp"
#include "slam2d/io/relations.hpp"
#include "slam2d/io/trajectory_io.hpp"
#include "slam2d/localization/mcl.hpp"
#include "slam2d/slam/graph/graph_slam.hpp"
#include "slam2d/slam/rbpf/rbpf_slam.hpp"

namespace slam2d::fuzz {
namespace {

// The readers take paths: each input is written to a file in this process's own folder, in
// memory (/dev/shm) where there is one.
class ScratchFolder {
 public:
  ScratchFolder() {
    const std::filesystem::path base =
        std::filesystem::is_directory("/dev/shm") ? std::filesystem::path("/dev/shm") : std::filesystem::temp_directory_path();
    path_ = base / ("slam2d-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(path_);
  }
  ~ScratchFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

const std::filesystem::path& scratch() {
  static const ScratchFolder folder;
  return folder.path();
}

std::string write_input(const std::string& name, const std::uint8_t* data, std::size_t size) {
  const std::filesystem::path path = scratch() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path.string();
}

void write_text(const std::string& name, std::string_view text) {
  write_input(name, reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

// Runs `parse`; slam2d::Error is the expected refusal, anything else escapes.
template <typename Parse>
void refused_or_read(Parse&& parse) {
  try {
    parse();
  } catch (const Error&) {
  }
}

void read_whole_log(const std::string& path) {
  LogReader reader(path);
  while (reader.next()) {
  }
}

void carmen(const std::uint8_t* data, std::size_t size) {
  refused_or_read([&] { read_whole_log(write_input("log.clf", data, size)); });
}

// The bytes as a .gz file: zlib's refusals and the reader's on what it inflates.
void carmen_gz(const std::uint8_t* data, std::size_t size) {
  refused_or_read([&] { read_whole_log(write_input("log.clf.gz", data, size)); });
}

void relations(const std::uint8_t* data, std::size_t size) {
  refused_or_read([&] { read_relations(write_input("log.relations", data, size)); });
}

void trajectory(const std::uint8_t* data, std::size_t size) {
  refused_or_read([&] { read_any_trajectory(write_input("trajectory.txt", data, size)); });
}

void pose_graph_g2o(const std::uint8_t* data, std::size_t size) {
  refused_or_read([&] { read_pose_graph(write_input("graph.g2o", data, size)); });
}

void pose_graph_toro(const std::uint8_t* data, std::size_t size) {
  refused_or_read([&] { read_pose_graph(write_input("graph.graph", data, size)); });
}

// The YAML fuzzed, beside a valid 2 x 2 PGM it may name.
void map_yaml(const std::uint8_t* data, std::size_t size) {
  write_text("map.pgm", std::string_view("P5\n2 2\n255\n\x00\xfe\xcd\x80", 15));
  refused_or_read([&] { read_map(write_input("map.yaml", data, size)); });
}

void pgm(const std::uint8_t* data, std::size_t size) {
  refused_or_read([&] { read_gray_image(write_input("image.pgm", data, size)); });
}

void png(const std::uint8_t* data, std::size_t size) {
  refused_or_read([&] { read_gray_image(write_input("image.png", data, size)); });
  refused_or_read([&] { read_png_rgb(write_input("image.png", data, size)); });
}

// A preset read into the configs with the deepest field tables (sections, enums, sizes).
void config(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  refused_or_read([&] {
    const ConfigNode node = ConfigNode::parse(text, "preset.yaml");
    GraphSlamConfig graph;
    refused_or_read([&] { read_valid_config(node, graph); });
    RbpfConfig rbpf;
    refused_or_read([&] { read_valid_config(node, rbpf); });
    MclConfig mcl;
    refused_or_read([&] { read_valid_config(node, mcl); });
  });
}

void ros1_bag(const std::uint8_t* data, std::size_t size) {
  refused_or_read([&] { read_whole_log(write_input("log.bag", data, size)); });
}

void mcap(const std::uint8_t* data, std::size_t size) {
  refused_or_read([&] { read_whole_log(write_input("log.mcap", data, size)); });
}

// A rosbag2 folder: a fixed metadata.yaml naming the fuzzed sqlite3 file.
void rosbag2_db3(const std::uint8_t* data, std::size_t size) {
  std::filesystem::create_directories(scratch() / "bag");
  write_text("bag/metadata.yaml",
             "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
             "  relative_file_paths: [bag_0.db3]\n  duration: {nanoseconds: 1}\n"
             "  starting_time: {nanoseconds_since_epoch: 0}\n  message_count: 0\n  topics_with_message_count: []\n"
             "  compression_format: ''\n  compression_mode: ''\n");
  write_input("bag/bag_0.db3", data, size);
  refused_or_read([&] { read_whole_log((scratch() / "bag").string()); });
}

// The first byte picks the type (and /tf_static); the rest is the message.
void cdr(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return;
  const auto type = static_cast<detail::Ros2Type>(data[0] % 4);
  refused_or_read([&] { detail::decode_cdr(type, data + 1, size - 1, (data[0] & 4) != 0); });
}

void ros1_message(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return;
  const auto type = static_cast<ros1::MessageType>(data[0] % 4);
  refused_or_read([&] { ros1::decode_message(type, std::span<const std::uint8_t>(data + 1, size - 1), (data[0] & 4) != 0); });
}

}  // namespace

const std::vector<NamedTarget>& targets() {
  static const std::vector<NamedTarget> all{
      {"carmen", carmen},         {"carmen_gz", carmen_gz},   {"relations", relations},   {"trajectory", trajectory},
      {"pose_graph_g2o", pose_graph_g2o}, {"pose_graph_toro", pose_graph_toro}, {"map_yaml", map_yaml},
      {"pgm", pgm},               {"png", png},               {"config", config},         {"ros1_bag", ros1_bag},
      {"mcap", mcap},             {"rosbag2_db3", rosbag2_db3}, {"cdr", cdr},             {"ros1_message", ros1_message}};
  return all;
}

Target target(const std::string& name) {
  for (const NamedTarget& named : targets()) {
    if (name == named.name) return named.run;
  }
  throw std::invalid_argument("no fuzz target '" + name + "'");
}

}  // namespace slam2d::fuzz
