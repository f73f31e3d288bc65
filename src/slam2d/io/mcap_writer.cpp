// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/mcap_writer.hpp"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "slam2d/core/error.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/detail/cdr.hpp"
#include "slam2d/io/detail/compression.hpp"
#include "slam2d/io/detail/mcap_records.hpp"
#include "slam2d/io/detail/message_definitions.hpp"
#include "slam2d/io/detail/ros_time.hpp"

namespace slam2d {
namespace {

using mcap::Opcode;

/// Little-endian record content, as the spec's primitive types.
class Content {
 public:
  Content& u8(std::uint8_t v) { return little(v, 1); }
  Content& u16(std::uint16_t v) { return little(v, 2); }
  Content& u32(std::uint32_t v) { return little(v, 4); }
  Content& u64(std::uint64_t v) { return little(v, 8); }
  Content& string(const std::string& text) {
    u32(static_cast<std::uint32_t>(text.size()));
    bytes.insert(bytes.end(), text.begin(), text.end());
    return *this;
  }
  Content& bytes32(std::span<const std::uint8_t> data) {  // uint32 length + bytes
    u32(static_cast<std::uint32_t>(data.size()));
    return raw(data);
  }
  Content& raw(std::span<const std::uint8_t> data) {
    bytes.insert(bytes.end(), data.begin(), data.end());
    return *this;
  }
  std::vector<std::uint8_t> bytes;

 private:
  Content& little(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }
};

/// One record: opcode, uint64 length, content.
std::vector<std::uint8_t> record(Opcode opcode, const Content& content) {
  Content out;
  out.u8(static_cast<std::uint8_t>(opcode)).u64(content.bytes.size()).raw(content.bytes);
  return std::move(out.bytes);
}

std::uint32_t crc(std::uint32_t running, std::span<const std::uint8_t> data) {
  return static_cast<std::uint32_t>(crc32(running, data.data(), static_cast<uInt>(data.size())));
}

const char* compression_name(McapCompression compression) {
  switch (compression) {
    case McapCompression::kNone: return "";
    case McapCompression::kZstd: return "zstd";
    case McapCompression::kLz4: return "lz4";
  }
  return "";
}

detail::Codec codec_of(McapCompression compression) {
  switch (compression) {
    case McapCompression::kNone: return detail::Codec::kNone;
    case McapCompression::kZstd: return detail::Codec::kZstd;
    case McapCompression::kLz4: return detail::Codec::kLz4Frame;
  }
  return detail::Codec::kNone;
}

struct MessageTimes {
  std::uint64_t start = std::numeric_limits<std::uint64_t>::max();
  std::uint64_t end = 0;
  void add(std::uint64_t t) {
    start = std::min(start, t);
    end = std::max(end, t);
  }
  bool empty() const { return start > end; }
};

}  // namespace

struct McapWriter::Impl {
  Impl(const std::string& path, McapWriterOptions options) : file(path), options(std::move(options)) {}

  void emit(std::span<const std::uint8_t> bytes) {
    file.stream().write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    offset += bytes.size();
    if (in_data_section) data_crc = crc(data_crc, bytes);
  }

  void flush_chunk() {
    if (chunk_records.empty()) return;
    const std::vector<std::uint8_t> compressed = detail::compress(codec_of(options.compression), chunk_records);
    Content chunk;
    chunk.u64(chunk_times.start).u64(chunk_times.end).u64(chunk_records.size()).u32(crc(0, chunk_records));
    chunk.string(compression_name(options.compression)).u64(compressed.size()).raw(compressed);
    const std::uint64_t chunk_start = offset;
    emit(record(Opcode::kChunk, chunk));
    const std::uint64_t chunk_length = offset - chunk_start;
    Content index_offsets;
    const std::uint64_t indexes_start = offset;
    for (const auto& [channel, entries] : chunk_index) {
      Content message_index;
      Content list;
      for (const auto& [time, at] : entries) list.u64(time).u64(at);
      message_index.u16(channel).bytes32(list.bytes);
      index_offsets.u16(channel).u64(offset);
      emit(record(Opcode::kMessageIndex, message_index));
    }
    Content chunk_index_record;
    chunk_index_record.u64(chunk_times.start).u64(chunk_times.end).u64(chunk_start).u64(chunk_length);
    chunk_index_record.bytes32(index_offsets.bytes).u64(offset - indexes_start);
    chunk_index_record.string(compression_name(options.compression)).u64(compressed.size()).u64(chunk_records.size());
    chunk_indexes.push_back(record(Opcode::kChunkIndex, chunk_index_record));
    ++chunk_count;
    chunk_records.clear();
    chunk_index.clear();
    chunk_times = {};
  }

  AtomicFile file;
  McapWriterOptions options;
  std::uint64_t offset = 0;
  bool in_data_section = false;
  std::uint32_t data_crc = 0;
  std::vector<std::vector<std::uint8_t>> schemas;   // records, for the summary
  std::vector<std::vector<std::uint8_t>> channels;  // records, for the summary
  std::vector<std::uint8_t> chunk_records;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index;  // channel: (log time, offset)
  MessageTimes chunk_times;
  std::vector<std::vector<std::uint8_t>> chunk_indexes;
  std::uint32_t chunk_count = 0;
  std::map<std::uint16_t, std::uint64_t> channel_counts;
  std::uint64_t message_count = 0;
  MessageTimes times;
  std::map<std::uint16_t, std::uint32_t> sequences;
  bool committed = false;
};

McapWriter::McapWriter(const std::string& path, McapWriterOptions options)
    : impl_(std::make_unique<Impl>(path, std::move(options))) {
  check(impl_->options.chunk_bytes > 0, path + ": MCAP chunk size must be positive");
  impl_->in_data_section = true;  // the data section's CRC covers the leading magic too (as the mcap libraries write it)
  impl_->emit(mcap::kMagic);
  Content header;
  header.string(impl_->options.profile).string("slam2d");
  impl_->emit(record(Opcode::kHeader, header));
}

McapWriter::~McapWriter() = default;

const std::string& McapWriter::path() const { return impl_->file.path(); }

std::uint16_t McapWriter::add_schema(const std::string& name, const std::string& encoding, const std::string& data) {
  check(impl_->schemas.size() < std::numeric_limits<std::uint16_t>::max(), path() + ": too many MCAP schemas");
  const auto id = static_cast<std::uint16_t>(impl_->schemas.size() + 1);
  Content schema;
  schema.u16(id).string(name).string(encoding);
  schema.bytes32({reinterpret_cast<const std::uint8_t*>(data.data()), data.size()});
  impl_->schemas.push_back(record(Opcode::kSchema, schema));
  impl_->emit(impl_->schemas.back());
  return id;
}

std::uint16_t McapWriter::add_channel(const std::string& topic, std::uint16_t schema, const std::string& message_encoding,
                                      const std::vector<std::pair<std::string, std::string>>& metadata) {
  check(schema >= 1 && schema <= impl_->schemas.size(), path() + ": channel " + topic + " on an unknown schema");
  check(impl_->channels.size() < std::numeric_limits<std::uint16_t>::max() - 1, path() + ": too many MCAP channels");
  const auto id = static_cast<std::uint16_t>(impl_->channels.size() + 1);
  Content map;
  for (const auto& [key, value] : metadata) map.string(key).string(value);
  Content channel;
  channel.u16(id).u16(schema).string(topic).string(message_encoding).bytes32(map.bytes);
  impl_->channels.push_back(record(Opcode::kChannel, channel));
  impl_->emit(impl_->channels.back());
  return id;
}

void McapWriter::write(std::uint16_t channel, std::uint64_t log_time_ns, std::span<const std::uint8_t> data) {
  Impl& s = *impl_;
  check(!s.committed, path() + ": MCAP write after commit");
  check(channel >= 1 && channel <= s.channels.size(), path() + ": message on an unknown MCAP channel");
  Content message;
  message.u16(channel).u32(s.sequences[channel]++).u64(log_time_ns).u64(log_time_ns).raw(data);
  s.chunk_index[channel].emplace_back(log_time_ns, s.chunk_records.size());
  const std::vector<std::uint8_t> bytes = record(Opcode::kMessage, message);
  s.chunk_records.insert(s.chunk_records.end(), bytes.begin(), bytes.end());
  s.chunk_times.add(log_time_ns);
  s.times.add(log_time_ns);
  ++s.channel_counts[channel];
  ++s.message_count;
  if (s.chunk_records.size() >= s.options.chunk_bytes) s.flush_chunk();
}

void McapWriter::commit() {
  Impl& s = *impl_;
  check(!s.committed, path() + ": MCAP commit called twice");
  s.flush_chunk();
  s.in_data_section = false;
  Content data_end;
  data_end.u32(s.data_crc);
  s.emit(record(Opcode::kDataEnd, data_end));

  // The summary: one group per record kind, each listed in a Summary Offset.
  const std::uint64_t summary_start = s.offset;
  std::uint32_t summary_crc = 0;
  const auto emit_summary = [&](std::span<const std::uint8_t> bytes) {
    summary_crc = crc(summary_crc, bytes);
    s.emit(bytes);
  };
  std::vector<std::vector<std::uint8_t>> offsets;
  const auto group = [&](Opcode opcode, const std::vector<std::vector<std::uint8_t>>& records) {
    if (records.empty()) return;
    const std::uint64_t start = s.offset;
    for (const auto& r : records) emit_summary(r);
    Content offset;
    offset.u8(static_cast<std::uint8_t>(opcode)).u64(start).u64(s.offset - start);
    offsets.push_back(record(Opcode::kSummaryOffset, offset));
  };
  group(Opcode::kSchema, s.schemas);
  group(Opcode::kChannel, s.channels);
  Content statistics;
  statistics.u64(s.message_count).u16(static_cast<std::uint16_t>(s.schemas.size()))
      .u32(static_cast<std::uint32_t>(s.channels.size())).u32(0).u32(0).u32(s.chunk_count);
  statistics.u64(s.times.empty() ? 0 : s.times.start).u64(s.times.empty() ? 0 : s.times.end);
  Content counts;
  for (const auto& [channel, count] : s.channel_counts) counts.u16(channel).u64(count);
  statistics.bytes32(counts.bytes);
  group(Opcode::kStatistics, {record(Opcode::kStatistics, statistics)});
  group(Opcode::kChunkIndex, s.chunk_indexes);
  const std::uint64_t offsets_start = s.offset;
  for (const auto& r : offsets) emit_summary(r);

  // The summary CRC runs through the footer's summary_offset_start, the field before it.
  Content footer;
  footer.u8(static_cast<std::uint8_t>(Opcode::kFooter)).u64(8 + 8 + 4).u64(summary_start).u64(offsets_start);
  footer.u32(crc(summary_crc, footer.bytes));
  s.emit(footer.bytes);
  s.emit(mcap::kMagic);
  s.file.commit();
  s.committed = true;
}

std::uint64_t seconds_to_nanoseconds(double stamp) {
  const detail::SplitStamp t = detail::split_stamp(stamp, 0.0, 1.8e10, "a ROS time in ns (0 to 1.8e10 s)");
  return static_cast<std::uint64_t>(t.sec) * 1'000'000'000u + t.nsec;
}

namespace {

/// The BagSink: one schema per type and one channel per topic, made on first use.
class McapBagSink final : public BagSink {
 public:
  McapBagSink(const std::string& path, McapWriterOptions options) : writer_(path, std::move(options)) {}

  void write(const std::string& topic, double receive_time, const DecodedMessage& message) override {
    const std::string type = detail::ros2_type_name(message);
    auto channel = channels_.find(topic);
    if (channel == channels_.end()) {
      auto schema = schemas_.find(type);
      if (schema == schemas_.end()) {
        schema = schemas_.emplace(type, writer_.add_schema(type, "ros2msg", detail::message_definition(type, detail::RosVersion::kRos2))).first;
      }
      channel = channels_.emplace(topic, std::make_pair(writer_.add_channel(topic, schema->second, "cdr"), type)).first;
    }
    if (channel->second.second != type) {
      throw Error(writer_.path() + ": topic " + topic + " is " + channel->second.second + ", not " + type);
    }
    writer_.write(channel->second.first, seconds_to_nanoseconds(receive_time), detail::encode_cdr(message));
  }

  void commit() override { writer_.commit(); }

 private:
  McapWriter writer_;
  std::map<std::string, std::uint16_t> schemas_;                          // type: schema id
  std::map<std::string, std::pair<std::uint16_t, std::string>> channels_;  // topic: channel id, type
};

}  // namespace

std::unique_ptr<BagSink> open_mcap_writer(const std::string& path, McapWriterOptions options) {
  return std::make_unique<McapBagSink>(path, std::move(options));
}

}  // namespace slam2d
