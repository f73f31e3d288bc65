// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// MCAP files (https://mcap.dev/spec), as ROS 2's rosbag2 writes them: profile "ros2", CDR messages.
//
// The reader takes the channels, schemas and chunk indexes from the summary section when the file
// has one, and the message indexes to list each chunk's messages without decompressing it; a file
// without a summary (or without chunk indexes: messages straight in the data section) is read in
// one linear pass instead. Chunks may be uncompressed, "zstd" or "lz4" (an LZ4 frame); a non-zero
// chunk CRC is checked, and a non-zero data section CRC (DataEnd) on every open. Messages come out in log_time order (ties in file order), one chunk
// decompressed at a time.

#include <memory>
#include <string>

#include "slam2d/io/bag_source.hpp"

namespace slam2d {

/// True when the file starts with the MCAP magic "\x89MCAP0\r\n".
bool is_mcap(const std::string& path);

/// Opens an MCAP file and indexes its messages. Throws Error("PATH: ...") when it cannot be read
/// or is malformed: bad magic, a record running past the end of the file or of its chunk, an
/// unknown compression, a CRC mismatch, an unsane uncompressed size, a message on an unknown
/// channel. The BagSource's next() throws the same way for what it finds later, and for a CDR
/// message that does not fit its type.
std::unique_ptr<BagSource> open_mcap(const std::string& path);

}  // namespace slam2d
