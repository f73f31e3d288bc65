// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Writing ROS 1 bags (format v2.0, http://wiki.ros.org/Bags/Format/2.0) as rosbag does: the bag
// header record padded to 4096 bytes, chunks (uncompressed, bz2 or lz4) holding the connection
// records on first use and the message data records, each chunk followed by one index data record
// per connection, then the index: every connection record and one chunk info record per chunk.
// Messages keep the order given (a bag's order is its recording order). Connection records carry
// the type's md5sum and full message definition (io/detail/message_definitions.hpp), so rosbag,
// Foxglove and slam2d's reader decode them; /tf_static is latched. Written atomically.

#include <cstddef>
#include <memory>
#include <string>

#include "slam2d/io/bag_sink.hpp"

namespace slam2d {

enum class Ros1Compression { kNone, kBz2, kLz4 };

struct Ros1BagWriterOptions {
  Ros1Compression compression = Ros1Compression::kBz2;  // rosbag record --bz2, the fixtures' choice
  std::size_t chunk_bytes = 768 * 1024;                   // uncompressed records per chunk (rosbag's default)
};

std::unique_ptr<BagSink> open_ros1_bag_writer(const std::string& path, Ros1BagWriterOptions options = {});

}  // namespace slam2d
