// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Writing a rosbag2 folder: one MCAP storage file (NAME_0.mcap, io/mcap_writer.hpp) and its
// metadata.yaml (format version 5, the newest that ROS 2 Humble reads; Iron and later read it too).
// The folder is built beside the target and renamed into place on commit(): a failed run leaves no
// folder, and a rosbag2 folder already at the path is replaced only once the new one is complete.

#include <memory>
#include <string>

#include "slam2d/io/bag_sink.hpp"
#include "slam2d/io/mcap_writer.hpp"

namespace slam2d {

/// Throws Error when `folder` exists and is not a rosbag2 folder (it is never overwritten).
std::unique_ptr<BagSink> open_rosbag2_writer(const std::string& folder, McapWriterOptions options = {});

}  // namespace slam2d
