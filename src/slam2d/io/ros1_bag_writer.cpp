// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/ros1_bag_writer.hpp"

#include <limits>
#include <map>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/detail/compression.hpp"
#include "slam2d/io/detail/message_definitions.hpp"
#include "slam2d/io/detail/ros1_messages.hpp"
#include "slam2d/io/detail/ros1_records.hpp"

namespace slam2d {
namespace {

using ros1::Op;
using ros1::Time;
using ros1::WireWriter;

constexpr std::size_t kBagHeaderRecord = 4096;  // rosbag pads the bag header record to this

/// A record header's fields ("name=value", each with its uint32 length).
class RecordHeader {
 public:
  explicit RecordHeader(Op op) { field("op", {reinterpret_cast<const std::uint8_t*>(&op), 1}); }
  RecordHeader& field(std::string_view name, ros1::Bytes value) {
    fields_.u32(static_cast<std::uint32_t>(name.size() + 1 + value.size()));
    fields_.raw({reinterpret_cast<const std::uint8_t*>(name.data()), name.size()}).u8('=').raw(value);
    return *this;
  }
  RecordHeader& text(std::string_view name, std::string_view value) {
    return field(name, {reinterpret_cast<const std::uint8_t*>(value.data()), value.size()});
  }
  RecordHeader& u32(std::string_view name, std::uint32_t value) { return field(name, WireWriter().u32(value).bytes()); }
  RecordHeader& u64(std::string_view name, std::uint64_t value) { return field(name, WireWriter().u64(value).bytes()); }
  RecordHeader& time(std::string_view name, Time value) {
    return field(name, WireWriter().u32(value.sec).u32(value.nsec).bytes());
  }
  const std::vector<std::uint8_t>& bytes() const { return fields_.bytes(); }

 private:
  WireWriter fields_;
};

/// header_len, header, data_len, data.
void append_record(WireWriter& out, const RecordHeader& header, ros1::Bytes data) {
  out.u32(static_cast<std::uint32_t>(header.bytes().size())).raw(header.bytes());
  out.u32(static_cast<std::uint32_t>(data.size())).raw(data);
}

bool before(Time a, Time b) { return a.nanoseconds() < b.nanoseconds(); }

struct ConnectionInfo {
  std::uint32_t id = 0;
  std::string topic;
  ros1::MessageType type;
  std::uint32_t seq = 0;  // header.seq of its next message
};

struct ChunkInfo {
  std::uint64_t pos = 0;
  Time start, end;
  std::map<std::uint32_t, std::uint32_t> counts;  // connection: messages
};

class Ros1BagSink final : public BagSink {
 public:
  Ros1BagSink(const std::string& path, Ros1BagWriterOptions options) : file_(path), options_(options) {
    check(options_.chunk_bytes > 0, path + ": ROS 1 chunk size must be positive");
    emit(WireWriter().raw({reinterpret_cast<const std::uint8_t*>(ros1::kMagic.data()), ros1::kMagic.size()}).bytes());
    emit(bag_header(0, 0, 0));  // rewritten by commit()
  }

  void write(const std::string& topic, double receive_time, const DecodedMessage& message) override {
    check(!committed_, file_.path() + ": write after commit");
    const ros1::MessageType type = ros1::message_type_of(message);
    auto found = connections_.find(topic);
    if (found == connections_.end()) {
      ConnectionInfo info{static_cast<std::uint32_t>(connections_.size()), topic, type, 0};
      found = connections_.emplace(topic, info).first;
      order_.push_back(topic);
      append_record(chunk_, connection_header(info), connection_data(info));  // in the chunk where first used
    }
    ConnectionInfo& connection = found->second;
    if (connection.type != type) {
      throw Error(file_.path() + ": topic " + topic + " is " + std::string(ros1::type_name(connection.type)) + ", not " +
                  std::string(ros1::type_name(type)));
    }
    const Time time = ros1::to_time(receive_time);
    const std::vector<std::uint8_t> data = ros1::encode_message(message, connection.seq++);
    index_[connection.id].push_back({time, static_cast<std::uint32_t>(chunk_.size())});
    RecordHeader header(Op::kMessageData);
    header.u32("conn", connection.id).time("time", time);
    append_record(chunk_, header, data);
    if (chunk_messages_ == 0 || before(time, chunk_start_)) chunk_start_ = time;
    if (chunk_messages_ == 0 || before(chunk_end_, time)) chunk_end_ = time;
    ++chunk_messages_;
    if (chunk_.size() >= options_.chunk_bytes) flush_chunk();
  }

  void commit() override {
    check(!committed_, file_.path() + ": commit called twice");
    flush_chunk();
    const std::uint64_t index_pos = offset_;
    for (const std::string& topic : order_) {
      const ConnectionInfo& info = connections_.at(topic);
      WireWriter record;
      append_record(record, connection_header(info), connection_data(info));
      emit(record.bytes());
    }
    for (const ChunkInfo& chunk : chunks_) {
      RecordHeader header(Op::kChunkInfo);
      header.u32("ver", 1).u64("chunk_pos", chunk.pos).time("start_time", chunk.start).time("end_time", chunk.end);
      header.u32("count", static_cast<std::uint32_t>(chunk.counts.size()));
      WireWriter data;
      for (const auto& [connection, count] : chunk.counts) data.u32(connection).u32(count);
      WireWriter record;
      append_record(record, header, data.bytes());
      emit(record.bytes());
    }
    // The bag header, now that the index is known, over the placeholder.
    file_.stream().seekp(static_cast<std::streamoff>(ros1::kMagic.size()));
    const std::vector<std::uint8_t> header =
        bag_header(index_pos, static_cast<std::uint32_t>(connections_.size()), static_cast<std::uint32_t>(chunks_.size()));
    file_.stream().write(reinterpret_cast<const char*>(header.data()), static_cast<std::streamsize>(header.size()));
    file_.commit();
    committed_ = true;
  }

 private:
  static std::vector<std::uint8_t> bag_header(std::uint64_t index_pos, std::uint32_t connections, std::uint32_t chunks) {
    RecordHeader header(Op::kBagHeader);
    header.u64("index_pos", index_pos).u32("conn_count", connections).u32("chunk_count", chunks);
    const std::size_t used = 4 + header.bytes().size() + 4;
    WireWriter record;
    append_record(record, header, std::vector<std::uint8_t>(kBagHeaderRecord - used, ' '));
    return record.take();
  }

  static RecordHeader connection_header(const ConnectionInfo& info) {
    RecordHeader header(Op::kConnection);
    header.u32("conn", info.id).text("topic", info.topic);
    return header;
  }

  static std::vector<std::uint8_t> connection_data(const ConnectionInfo& info) {
    WireWriter data;  // the connection header: "name=value" fields like a record header's
    const auto add = [&](std::string_view name, std::string_view value) {
      data.u32(static_cast<std::uint32_t>(name.size() + 1 + value.size()));
      data.raw({reinterpret_cast<const std::uint8_t*>(name.data()), name.size()}).u8('=');
      data.raw({reinterpret_cast<const std::uint8_t*>(value.data()), value.size()});
    };
    const std::string_view type = ros1::type_name(info.type);
    add("topic", info.topic);
    add("type", type);
    add("md5sum", ros1::md5sum(info.type));
    add("message_definition", detail::message_definition(type, detail::RosVersion::kRos1));
    add("callerid", "/slam2d");
    if (info.topic == "/tf_static") add("latching", "1");
    return data.take();
  }

  void flush_chunk() {
    if (chunk_messages_ == 0) return;
    const detail::Codec codec = options_.compression == Ros1Compression::kBz2   ? detail::Codec::kBz2
                                : options_.compression == Ros1Compression::kLz4 ? detail::Codec::kLz4Frame
                                                                                 : detail::Codec::kNone;
    const char* name = codec == detail::Codec::kBz2 ? "bz2" : codec == detail::Codec::kLz4Frame ? "lz4" : "none";
    check(chunk_.size() <= std::numeric_limits<std::uint32_t>::max(), file_.path() + ": a chunk over 4 GiB");
    ChunkInfo info{offset_, chunk_start_, chunk_end_, {}};
    RecordHeader header(Op::kChunk);
    header.text("compression", name).u32("size", static_cast<std::uint32_t>(chunk_.size()));
    WireWriter record;
    append_record(record, header, detail::compress(codec, chunk_.bytes()));
    for (const auto& [connection, entries] : index_) {
      RecordHeader index(Op::kIndexData);
      index.u32("ver", 1).u32("conn", connection).u32("count", static_cast<std::uint32_t>(entries.size()));
      WireWriter data;
      for (const auto& [time, at] : entries) data.u32(time.sec).u32(time.nsec).u32(at);
      append_record(record, index, data.bytes());
      info.counts[connection] = static_cast<std::uint32_t>(entries.size());
    }
    emit(record.bytes());
    chunks_.push_back(std::move(info));
    chunk_ = WireWriter();
    index_.clear();
    chunk_messages_ = 0;
  }

  void emit(const std::vector<std::uint8_t>& bytes) {
    file_.stream().write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    offset_ += bytes.size();
  }

  AtomicFile file_;
  Ros1BagWriterOptions options_;
  std::uint64_t offset_ = 0;
  std::map<std::string, ConnectionInfo> connections_;
  std::vector<std::string> order_;  // topics in the order first written
  WireWriter chunk_;                // the open chunk's records, uncompressed
  std::map<std::uint32_t, std::vector<std::pair<Time, std::uint32_t>>> index_;  // connection: (time, offset)
  std::size_t chunk_messages_ = 0;
  Time chunk_start_, chunk_end_;
  std::vector<ChunkInfo> chunks_;
  bool committed_ = false;
};

}  // namespace

std::unique_ptr<BagSink> open_ros1_bag_writer(const std::string& path, Ros1BagWriterOptions options) {
  return std::make_unique<Ros1BagSink>(path, options);
}

}  // namespace slam2d
