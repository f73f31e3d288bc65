// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// rosbag2 folders (ROS 2): metadata.yaml beside the storage file, MCAP ("mcap") or SQLite
// ("sqlite3", a .db3 with the Humble tables topics(id, name, type, serialization_format,
// offered_qos_profiles) and messages(id, topic_id, timestamp, data)).

#include <memory>
#include <string>

#include "slam2d/io/bag_source.hpp"

namespace slam2d {

/// True for a folder holding a metadata.yaml, or for the path of a metadata.yaml itself.
bool is_rosbag2(const std::string& path);

/// Opens a rosbag2 folder (or its metadata.yaml): storage_identifier and relative_file_paths
/// from metadata.yaml, then open_mcap on each .mcap or an SQLite reader on each .db3 (messages
/// ORDER BY timestamp, id; DecodedRecord::index is the messages row id). A bag split into several
/// storage files reads as one: topics merged, messages in receive-time order across the files.
/// Throws Error("PATH: ...") for a missing or malformed metadata.yaml, an unknown storage
/// identifier, compressed storage (compression_mode FILE or MESSAGE), a storage file that does not
/// exist, a topic whose type differs between files and a .db3 without those tables.
std::unique_ptr<BagSource> open_rosbag2(const std::string& path);

/// The SQLite reader alone, on a .db3 file.
std::unique_ptr<BagSource> open_rosbag2_sqlite(const std::string& db3_path);

}  // namespace slam2d
