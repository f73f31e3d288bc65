// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/ros1_bag.hpp"

#include <algorithm>
#include <fstream>
#include <future>
#include <map>
#include <set>
#include <thread>
#include <tuple>
#include <utility>

#include "slam2d/io/detail/ros1_messages.hpp"
#include "slam2d/io/detail/ros1_records.hpp"

namespace slam2d {

namespace {

using ros1::Bytes;
using ros1::HeaderFields;
using ros1::Op;
using ros1::RecordLayout;
using ros1::WireReader;

/// Random access to the bag file; every read is checked against the file size.
class BagFile {
 public:
  explicit BagFile(const std::string& path) : stream_(path, std::ios::binary) {
    check(stream_.is_open(), "cannot open the file");
    stream_.seekg(0, std::ios::end);
    size_ = static_cast<std::uint64_t>(stream_.tellg());
  }
  std::uint64_t size() const { return size_; }

  std::vector<std::uint8_t> read(std::uint64_t pos, std::uint64_t n) {
    if (pos > size_ || n > size_ - pos) {
      throw Error("needs " + std::to_string(n) + " bytes at byte " + std::to_string(pos) + " of a " +
                  std::to_string(size_) + "-byte file (truncated?)");
    }
    std::vector<std::uint8_t> bytes(n);
    stream_.seekg(static_cast<std::streamoff>(pos));
    stream_.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(n));
    check(static_cast<std::uint64_t>(stream_.gcount()) == n, "read error");
    return bytes;
  }

  /// The layout of the record at `pos`, and its header bytes.
  std::pair<RecordLayout, std::vector<std::uint8_t>> record(std::uint64_t pos) {
    const std::uint32_t header_len = WireReader(read(pos, 4)).u32();
    const std::vector<std::uint8_t> after_header = read(pos + 4 + header_len, 4);
    const RecordLayout layout = ros1::record_layout(pos, size_, header_len, WireReader(after_header).u32());
    return {layout, read(layout.header_pos, layout.header_len)};
  }

 private:
  std::ifstream stream_;
  std::uint64_t size_ = 0;
};

struct Connection {
  std::uint32_t id = 0;
  std::string topic;
  std::string type;
  std::string md5sum;
};

struct Chunk {
  std::uint64_t pos = 0;  // of the chunk record
  std::string compression;
  std::uint64_t size = 0;  // uncompressed
  RecordLayout layout;
};

/// One message, from a chunk's index data.
struct IndexEntry {
  std::uint64_t time_ns = 0;
  ros1::Time time;
  std::uint32_t chunk = 0;       // in chunks_, which are in file order
  std::uint32_t offset = 0;      // of its message data record in the uncompressed chunk
  std::uint32_t connection = 0;  // in connections_
};

class Ros1Bag final : public BagSource {
 public:
  explicit Ros1Bag(std::string path) : path_(std::move(path)), file_(path_) {
    read_index();
    list_topics();
  }

  const std::string& path() const override { return path_; }
  const std::vector<BagTopic>& topics() const override { return topics_; }
  std::vector<std::string> warnings() const override { return warnings_; }
  double progress() const override {
    return queue_.empty() ? (started_ ? 1.0 : 0.0) : static_cast<double>(next_) / static_cast<double>(queue_.size());
  }

  std::optional<DecodedRecord> next(const std::vector<std::string>& wanted) override {
    try {
      if (!started_ || wanted != wanted_) plan(wanted);
      if (next_ == queue_.size()) return std::nullopt;
      const std::size_t file_index = queue_[next_];
      DecodedRecord record = read_message(file_index);
      last_yielded_ = file_index;
      if (++next_ == last_use_[entries_[file_index].chunk]) chunk_data_.erase(entries_[file_index].chunk);
      return record;
    } catch (const Error& e) {
      throw Error(path_ + ": " + e.what());
    }
  }

 private:
  // Bag header -> index position -> connections and chunk infos -> each chunk's index data.
  void read_index() {
    const std::vector<std::uint8_t> magic = file_.read(0, ros1::kMagic.size());
    check(std::equal(magic.begin(), magic.end(), ros1::kMagic.begin()), "not a ROS 1 bag v2.0 (no '#ROSBAG V2.0' magic)");
    const auto [header_layout, header_bytes] = file_.record(ros1::kMagic.size());
    const HeaderFields bag_header(header_bytes);
    check(bag_header.op() == Op::kBagHeader, "the first record is not a bag header");
    const std::uint64_t index_pos = bag_header.u64("index_pos");
    const std::uint32_t connection_count = bag_header.u32("conn_count");
    const std::uint32_t chunk_count = bag_header.u32("chunk_count");
    if (index_pos == 0 || index_pos < header_layout.end() || index_pos >= file_.size()) {
      // A recording that was killed: no index (or one cut off). Read it as `rosbag reindex` would.
      warnings_.push_back(path_ + ": warning: no index (a recording that was not closed): read in one pass over its chunks");
      scan_chunks(header_layout.end());
      return;
    }

    std::vector<std::uint64_t> chunk_positions;
    for (std::uint64_t pos = index_pos; pos < file_.size();) {
      const auto [layout, bytes] = file_.record(pos);
      const HeaderFields fields(bytes);
      if (fields.op() == Op::kConnection) {
        read_connection(fields, layout);
      } else if (fields.op() == Op::kChunkInfo) {
        check(fields.u32("ver") == 1, "chunk info version " + std::to_string(fields.u32("ver")) + " (not 1)");
        chunk_positions.push_back(fields.u64("chunk_pos"));
      }
      pos = layout.end();
    }
    check(connections_.size() == connection_count && chunk_positions.size() == chunk_count,
          "the index holds " + std::to_string(connections_.size()) + " connections and " +
              std::to_string(chunk_positions.size()) + " chunk infos, the bag header says " +
              std::to_string(connection_count) + " and " + std::to_string(chunk_count));
    std::ranges::sort(chunk_positions);
    for (const std::uint64_t pos : chunk_positions) read_chunk_index(pos, index_pos);
    // File order: by chunk, then by offset in the chunk; a message's position is its index.
    std::ranges::sort(entries_, {}, [](const IndexEntry& e) { return std::pair(e.chunk, e.offset); });
  }

  void read_connection(const HeaderFields& fields, const RecordLayout& layout) {
    add_connection(fields, file_.read(layout.data_pos, layout.data_len));
  }

  // A connection record: its header's conn and topic, and its data, the connection header.
  void add_connection(const HeaderFields& fields, Bytes data) {
    const std::uint32_t id = fields.u32("conn");
    check(!connection_index_.contains(id), "connection " + std::to_string(id) + " defined twice");
    const HeaderFields connection_header(data);
    Connection& connection = connections_.emplace_back();
    connection.id = id;
    connection.topic = fields.text("topic");
    connection.type = connection_header.text("type");
    if (connection_header.find("md5sum")) connection.md5sum = connection_header.text("md5sum");
    connection_index_[id] = static_cast<std::uint32_t>(connections_.size() - 1);
  }

  // A bag without an index: every chunk from `pos` on, decompressed, its connection and message
  // data records listed in file order. A tail cut short (the last chunk of a killed recording)
  // ends the pass with a warning; a corrupt complete chunk is an error.
  void scan_chunks(std::uint64_t pos) {
    std::string cut;  // where the bag was cut, if it was
    while (pos < file_.size()) {
      RecordLayout layout;
      std::vector<std::uint8_t> header_bytes;
      try {
        std::tie(layout, header_bytes) = file_.record(pos);
      } catch (const Error&) {
        cut = "the last " + std::to_string(file_.size() - pos) + " bytes (from byte " + std::to_string(pos) +
              ") are a record cut short";
        break;
      }
      const HeaderFields fields(header_bytes);
      if (fields.op() == Op::kChunk && layout.data_len == 0) {  // rosbag fills the length in when it closes a chunk
        cut = "the chunk at byte " + std::to_string(pos) + " was never closed (its data length is 0)";
        break;
      }
      if (fields.op() == Op::kChunk) {
        const std::string where = "chunk at byte " + std::to_string(pos) + ": ";
        try {
          Chunk& chunk = chunks_.emplace_back();
          chunk.pos = pos;
          chunk.compression = fields.text("compression");
          chunk.size = fields.u32("size");
          chunk.layout = layout;
          list_chunk_records(static_cast<std::uint32_t>(chunks_.size() - 1),
                             ros1::decompress_chunk(chunk.compression, file_.read(layout.data_pos, layout.data_len), chunk.size));
        } catch (const Error& e) {
          throw Error(where + e.what());
        }
      } else if (fields.op() == Op::kConnection && !connection_index_.contains(fields.u32("conn"))) {
        read_connection(fields, layout);
      }
      pos = layout.end();
    }
    if (cut.empty()) return;
    check(!entries_.empty(), "no index, and " + cut + " before any message: nothing to read");
    warnings_.push_back(path_ + ": warning: " + cut + ": the " + std::to_string(entries_.size()) +
                        " messages before it are read");
  }

  void list_chunk_records(std::uint32_t chunk, const std::vector<std::uint8_t>& records) {
    for (std::uint64_t pos = 0; pos < records.size();) {
      WireReader lengths(Bytes(records).subspan(pos));
      const std::uint32_t header_len = lengths.u32();
      lengths.skip(header_len);
      const RecordLayout layout = ros1::record_layout(pos, records.size(), header_len, lengths.u32());
      const HeaderFields fields(Bytes(records).subspan(layout.header_pos, layout.header_len));
      if (fields.op() == Op::kConnection) {
        if (!connection_index_.contains(fields.u32("conn"))) add_connection(fields, Bytes(records).subspan(layout.data_pos, layout.data_len));
      } else if (fields.op() == Op::kMessageData) {
        const auto found = connection_index_.find(fields.u32("conn"));
        check(found != connection_index_.end(), "message on unknown connection " + std::to_string(fields.u32("conn")));
        IndexEntry& entry = entries_.emplace_back();
        entry.time = fields.time("time");
        entry.time_ns = entry.time.nanoseconds();
        entry.chunk = chunk;
        entry.offset = static_cast<std::uint32_t>(pos);
        entry.connection = found->second;
      }
      pos = layout.end();
    }
  }

  // A chunk record, then one index data record per connection in it.
  void read_chunk_index(std::uint64_t chunk_pos, std::uint64_t index_pos) {
    const std::string where = "chunk at byte " + std::to_string(chunk_pos) + ": ";
    try {
      const auto [layout, bytes] = file_.record(chunk_pos);
      const HeaderFields fields(bytes);
      check(fields.op() == Op::kChunk, "not a chunk record");
      Chunk& chunk = chunks_.emplace_back();
      chunk.pos = chunk_pos;
      chunk.compression = fields.text("compression");
      chunk.size = fields.u32("size");
      chunk.layout = layout;
      const auto chunk_number = static_cast<std::uint32_t>(chunks_.size() - 1);
      for (std::uint64_t pos = layout.end(); pos < index_pos;) {
        const auto [index_layout, index_bytes] = file_.record(pos);
        const HeaderFields index(index_bytes);
        if (index.op() != Op::kIndexData) break;
        read_index_data(index, index_layout, chunk_number);
        pos = index_layout.end();
      }
    } catch (const Error& e) {
      throw Error(where + e.what());
    }
  }

  // Index data v1: uint32 count entries of (time, uint32 offset).
  void read_index_data(const HeaderFields& fields, const RecordLayout& layout, std::uint32_t chunk) {
    check(fields.u32("ver") == 1, "index data version " + std::to_string(fields.u32("ver")) + " (not 1)");
    const std::uint32_t id = fields.u32("conn");
    const auto found = connection_index_.find(id);
    check(found != connection_index_.end(), "index data for unknown connection " + std::to_string(id));
    const std::uint64_t count = fields.u32("count");
    check(count * 12 == layout.data_len, "index data of " + std::to_string(layout.data_len) + " bytes for " +
                                             std::to_string(count) + " messages");
    const std::vector<std::uint8_t> data = file_.read(layout.data_pos, layout.data_len);
    WireReader reader(data);
    for (std::uint64_t i = 0; i < count; ++i) {
      IndexEntry& entry = entries_.emplace_back();
      entry.time = ros1::read_time(reader);
      entry.time_ns = entry.time.nanoseconds();
      entry.chunk = chunk;
      entry.offset = reader.u32();
      entry.connection = found->second;
      check(entry.offset < chunks_[chunk].size, "message offset " + std::to_string(entry.offset) +
                                                    " past the chunk's " + std::to_string(chunks_[chunk].size) +
                                                    " bytes");
    }
  }

  // Per topic name, over its connections: type, count, first and last receive time.
  void list_topics() {
    std::map<std::string, std::size_t> topic_index;
    for (const Connection& connection : connections_) {
      if (topic_index.emplace(connection.topic, topics_.size()).second) {
        topics_.push_back({.name = connection.topic, .type = connection.type});
      }
    }
    std::vector<std::pair<ros1::Time, ros1::Time>> span(topics_.size());  // first, last
    for (const IndexEntry& entry : entries_) {
      const std::size_t t = topic_index.at(connections_[entry.connection].topic);
      auto& [first, last] = span[t];
      if (topics_[t].count++ == 0 || entry.time_ns < first.nanoseconds()) first = entry.time;
      if (entry.time_ns > last.nanoseconds()) last = entry.time;
    }
    for (std::size_t t = 0; t < topics_.size(); ++t) {
      topics_[t].first_stamp = span[t].first.seconds();
      topics_[t].last_stamp = span[t].second.seconds();
    }
  }

  // The messages of `wanted` in the recording (file) order, after the last one yielded
  // when the wanted topics change on the way; which chunk is needed until when.
  void plan(const std::vector<std::string>& wanted) {
    const std::set<std::string> names(wanted.begin(), wanted.end());
    std::vector<std::optional<ros1::MessageType>> types(connections_.size());
    for (std::size_t c = 0; c < connections_.size(); ++c) {
      const Connection& connection = connections_[c];
      if (!names.contains(connection.topic)) continue;
      types[c] = ros1::message_type(connection.type);
      check(types[c].has_value(), "topic " + connection.topic + " has type " + connection.type +
                                      ", which slam2d does not decode (it reads sensor_msgs/LaserScan, "
                                      "nav_msgs/Odometry, tf2_msgs/TFMessage and sensor_msgs/Imu)");
      check(connection.md5sum.empty() || connection.md5sum == "*" || connection.md5sum == ros1::md5sum(*types[c]),
            "topic " + connection.topic + " has a " + connection.type + " of another definition (md5sum " +
                connection.md5sum + ", slam2d reads " + std::string(ros1::md5sum(*types[c])) + ")");
    }
    types_ = std::move(types);
    queue_.clear();
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      if (types_[entries_[i].connection] && (!last_yielded_ || comes_after(i, *last_yielded_))) queue_.push_back(i);
    }
    last_use_.assign(chunks_.size(), 0);
    chunk_order_.clear();
    for (std::size_t q = 0; q < queue_.size(); ++q) {
      const std::uint32_t chunk = entries_[queue_[q]].chunk;
      if (last_use_[chunk] == 0) chunk_order_.push_back(chunk);
      last_use_[chunk] = q + 1;
    }
    pending_.clear();
    next_to_start_ = 0;
    chunk_data_.clear();
    next_ = 0;
    wanted_ = wanted;
    started_ = true;
  }

  bool comes_after(std::size_t a, std::size_t b) const {
    return a > b;  // file order
  }

  // A chunk's records, decompressed. Chunks are decompressed on worker threads, in the order the
  // queue first needs them, up to one per core ahead of the reader (bz2 dominates reading time).
  const std::vector<std::uint8_t>& chunk_data(std::uint32_t chunk_number) {
    const auto found = chunk_data_.find(chunk_number);
    if (found != chunk_data_.end()) return found->second;
    while (!pending_.contains(chunk_number)) {
      check(next_to_start_ < chunk_order_.size(), "chunk at byte " + std::to_string(chunks_[chunk_number].pos) +
                                                      " failed to decompress before");
      start_decompression();
    }
    auto future = std::move(pending_.at(chunk_number));
    pending_.erase(chunk_number);
    while (pending_.size() < chunks_ahead_ && next_to_start_ < chunk_order_.size()) start_decompression();
    try {
      return chunk_data_[chunk_number] = future.get();
    } catch (const Error& e) {
      throw Error("chunk at byte " + std::to_string(chunks_[chunk_number].pos) + ": " + e.what());
    }
  }

  void start_decompression() {
    const std::uint32_t chunk_number = chunk_order_[next_to_start_++];
    const Chunk& chunk = chunks_[chunk_number];
    std::vector<std::uint8_t> compressed;
    try {
      compressed = file_.read(chunk.layout.data_pos, chunk.layout.data_len);
    } catch (const Error& e) {
      throw Error("chunk at byte " + std::to_string(chunk.pos) + ": " + e.what());
    }
    pending_[chunk_number] = std::async(std::launch::async, [compressed = std::move(compressed), &chunk] {
      return ros1::decompress_chunk(chunk.compression, compressed, chunk.size);
    });
  }

  DecodedRecord read_message(std::size_t file_index) {
    const IndexEntry& entry = entries_[file_index];
    const Connection& connection = connections_[entry.connection];
    const std::vector<std::uint8_t>& chunk = chunk_data(entry.chunk);
    try {
      WireReader reader(Bytes(chunk).subspan(entry.offset));
      const HeaderFields fields(reader.bytes(reader.u32()));
      check(fields.op() == Op::kMessageData, "no message data record at the index's offset");
      check(fields.u32("conn") == connection.id, "the message's connection differs from its index's");
      const Bytes data = reader.bytes(reader.u32());
      return {.topic = connection.topic,
              .receive_time = entry.time.seconds(),
              .index = file_index,
              .message = ros1::decode_message(*types_[entry.connection], data, connection.topic == "/tf_static")};
    } catch (const Error& e) {
      throw Error(connection.topic + " message (record " + std::to_string(file_index) + ", time " +
                  std::to_string(entry.time.sec) + "." + std::to_string(entry.time.nsec) + ", chunk at byte " +
                  std::to_string(chunks_[entry.chunk].pos) + " offset " + std::to_string(entry.offset) +
                  "): " + e.what());
    }
  }

  std::string path_;
  BagFile file_;
  std::vector<Connection> connections_;
  std::map<std::uint32_t, std::uint32_t> connection_index_;  // connection id -> connections_
  std::vector<Chunk> chunks_;
  std::vector<IndexEntry> entries_;  // every message, in file order
  std::vector<BagTopic> topics_;
  std::vector<std::string> warnings_;  // an unindexed bag, a tail cut short

  // The current read.
  bool started_ = false;
  std::vector<std::string> wanted_;
  std::vector<std::optional<ros1::MessageType>> types_;  // per connection, when wanted
  std::vector<std::size_t> queue_;                        // entries_ indices, in file order
  std::size_t next_ = 0;
  std::optional<std::size_t> last_yielded_;
  std::vector<std::size_t> last_use_;  // per chunk: 1 + the queue position of its last message
  std::map<std::uint32_t, std::vector<std::uint8_t>> chunk_data_;  // decompressed, while needed
  std::vector<std::uint32_t> chunk_order_;                          // chunks in the order of first use
  std::size_t next_to_start_ = 0;                                   // in chunk_order_
  std::map<std::uint32_t, std::future<std::vector<std::uint8_t>>> pending_;  // being decompressed
  const std::size_t chunks_ahead_ = std::max(1u, std::thread::hardware_concurrency());
};

}  // namespace

bool is_ros1_bag(const std::string& path) {
  std::ifstream stream(path, std::ios::binary);
  std::string magic(ros1::kMagic.size(), '\0');
  return stream.read(magic.data(), static_cast<std::streamsize>(magic.size())) && magic == ros1::kMagic;
}

std::unique_ptr<BagSource> open_ros1_bag(const std::string& path) {
  try {
    return std::make_unique<Ros1Bag>(path);
  } catch (const Error& e) {
    throw Error(path + ": " + e.what());
  }
}

}  // namespace slam2d
