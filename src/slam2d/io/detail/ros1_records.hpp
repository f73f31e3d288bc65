// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// ROS 1 bag v2.0 records (http://wiki.ros.org/Bags/Format/2.0): a record is
//   int32 header_len, header (fields: int32 field_len, "name=value"), int32 data_len, data.
// The header's `op` field says which record it is. Chunks hold message data (and connection)
// records, stored uncompressed, or compressed with bz2 or lz4 (one LZ4 frame, as roslz4 writes).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "slam2d/io/detail/ros1_wire.hpp"

namespace slam2d::ros1 {

inline constexpr std::string_view kMagic = "#ROSBAG V2.0\n";

enum class Op : std::uint8_t {
  kMessageData = 0x02,
  kBagHeader = 0x03,
  kIndexData = 0x04,
  kChunk = 0x05,
  kChunkInfo = 0x06,
  kConnection = 0x07,
};

/// A ROS 1 time: uint32 seconds, uint32 nanoseconds.
struct Time {
  std::uint32_t sec = 0;
  std::uint32_t nsec = 0;
  std::uint64_t nanoseconds() const { return std::uint64_t{sec} * 1'000'000'000u + nsec; }
  double seconds() const { return static_cast<double>(sec) + static_cast<double>(nsec) * 1e-9; }
};
Time read_time(WireReader& reader);

/// The fields of a record header (or of a connection record's data, which has the same shape).
/// The values point into the parsed bytes.
class HeaderFields {
 public:
  explicit HeaderFields(Bytes bytes);
  std::optional<Bytes> find(std::string_view name) const;
  Bytes get(std::string_view name) const;  // throws Error("no field NAME") when absent
  Op op() const;
  std::uint32_t u32(std::string_view name) const;
  std::uint64_t u64(std::string_view name) const;
  Time time(std::string_view name) const;
  std::string text(std::string_view name) const;

 private:
  std::vector<std::pair<std::string_view, Bytes>> fields_;
};

/// Where a record's header and data lie, as offsets in the buffer or file it was read from.
struct RecordLayout {
  std::uint64_t header_pos = 0;
  std::uint32_t header_len = 0;
  std::uint64_t data_pos = 0;
  std::uint32_t data_len = 0;
  std::uint64_t end() const { return data_pos + data_len; }
};

/// The record at `pos` of a buffer `size` bytes long, given a way to read its two length fields;
/// throws Error when either runs past `size`.
RecordLayout record_layout(std::uint64_t pos, std::uint64_t size, std::uint32_t header_len,
                           std::uint32_t data_len);

/// A chunk's records, uncompressed: `compression` is "none", "bz2" or "lz4"; `size` the
/// uncompressed size from the chunk header. Throws Error for another compression, a size out of
/// bounds, corrupt data or data whose size differs from `size`.
std::vector<std::uint8_t> decompress_chunk(std::string_view compression, Bytes data, std::uint64_t size);

}  // namespace slam2d::ros1
