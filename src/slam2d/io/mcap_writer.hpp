// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Writing MCAP files (https://mcap.dev/spec) as rosbag2 and Foxglove do: a Header, the Schema and
// Channel records, the messages in Chunks (uncompressed, zstd or lz4), each chunk followed by its
// Message Index records, DataEnd with the data section's CRC, then a summary (schemas, channels,
// Statistics, Chunk Indexes), Summary Offsets and the Footer. Written atomically: nothing appears
// at the path unless commit() succeeds.
//
// McapWriter is the container alone (any schema and message encoding); open_mcap_writer is the
// BagSink of the messages slam2d reads, as ROS 2 writes them (profile "ros2", "ros2msg" schemas,
// CDR messages), so that slam2d's own reader, `ros2 bag` and Foxglove read the file.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "slam2d/io/bag_sink.hpp"

namespace slam2d {

enum class McapCompression { kNone, kZstd, kLz4 };

struct McapWriterOptions {
  McapCompression compression = McapCompression::kZstd;
  std::size_t chunk_bytes = 768 * 1024;  // uncompressed records per chunk (rosbag2's default)
  std::string profile = "ros2";
};

class McapWriter {
 public:
  explicit McapWriter(const std::string& path, McapWriterOptions options = {});
  ~McapWriter();  // without commit(): nothing at the path
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// A schema: its name ("nav_msgs/msg/Path"), encoding ("ros2msg") and text. Ids from 1.
  std::uint16_t add_schema(const std::string& name, const std::string& encoding, const std::string& data);
  /// A channel on `topic` with `schema` (an id add_schema gave), messages in `message_encoding`.
  std::uint16_t add_channel(const std::string& topic, std::uint16_t schema, const std::string& message_encoding,
                            const std::vector<std::pair<std::string, std::string>>& metadata = {});
  /// One message on `channel` at `log_time_ns` (also its publish time).
  void write(std::uint16_t channel, std::uint64_t log_time_ns, std::span<const std::uint8_t> data);
  /// Finishes the data section, writes the summary and renames the file into place.
  void commit();
  const std::string& path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The BagSink of a ROS 2 MCAP bag at `path` (see above).
std::unique_ptr<BagSink> open_mcap_writer(const std::string& path, McapWriterOptions options = {});

/// A ROS time in ns from s; Error for a stamp that is negative, not finite or past 2^64 ns.
std::uint64_t seconds_to_nanoseconds(double stamp);

}  // namespace slam2d
