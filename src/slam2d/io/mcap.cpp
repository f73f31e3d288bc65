// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/mcap.hpp"

#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <utility>
#include <vector>

#include "slam2d/core/error.hpp"
#include "slam2d/io/detail/cdr.hpp"
#include "slam2d/io/detail/compression.hpp"
#include "slam2d/io/detail/mcap_records.hpp"

namespace slam2d {
namespace {

using mcap::kMagic;
constexpr std::uint64_t kRecordPrefix = 9;  // opcode (1) + content length (8)
constexpr std::uint64_t kFooterRecord = kRecordPrefix + 20;

// The opcodes the reader handles, as the bytes it compares.
constexpr std::uint8_t kFooter = static_cast<std::uint8_t>(mcap::Opcode::kFooter);
constexpr std::uint8_t kSchema = static_cast<std::uint8_t>(mcap::Opcode::kSchema);
constexpr std::uint8_t kChannel = static_cast<std::uint8_t>(mcap::Opcode::kChannel);
constexpr std::uint8_t kMessage = static_cast<std::uint8_t>(mcap::Opcode::kMessage);
constexpr std::uint8_t kChunk = static_cast<std::uint8_t>(mcap::Opcode::kChunk);
constexpr std::uint8_t kMessageIndex = static_cast<std::uint8_t>(mcap::Opcode::kMessageIndex);
constexpr std::uint8_t kChunkIndex = static_cast<std::uint8_t>(mcap::Opcode::kChunkIndex);
constexpr std::uint8_t kDataEnd = static_cast<std::uint8_t>(mcap::Opcode::kDataEnd);

/// A malformed file; what() is the reason, the source adds the path.
class Malformed : public Error {
 public:
  using Error::Error;
};

std::string at(const std::string& what, std::uint64_t offset) { return what + " at offset " + std::to_string(offset); }

/// Little-endian fields of one record's content (the spec's primitive types), bounds-checked.
class Fields {
 public:
  Fields(const std::uint8_t* data, std::uint64_t size) : data_(data), size_(size) {}
  std::uint8_t u8() { return static_cast<std::uint8_t>(little<1>()); }
  std::uint16_t u16() { return static_cast<std::uint16_t>(little<2>()); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(little<4>()); }
  std::uint64_t u64() { return little<8>(); }
  std::string string() {
    const std::uint32_t length = u32();
    const std::uint8_t* p = take(length, "a string");
    return std::string(reinterpret_cast<const char*>(p), length);
  }
  /// A byte array with a uint32 (maps, arrays, schema data) or uint64 (chunk records) length.
  Fields sub32(const char* what) { return sub(u32(), what); }
  Fields sub64(const char* what) { return sub(u64(), what); }
  const std::uint8_t* data() const { return data_ + pos_; }
  std::uint64_t remaining() const { return size_ - pos_; }
  bool done() const { return pos_ == size_; }

 private:
  template <int N>
  std::uint64_t little() {
    const std::uint8_t* p = take(N, "a field");
    std::uint64_t value = 0;
    for (int i = N - 1; i >= 0; --i) value = (value << 8) | p[i];
    return value;
  }
  Fields sub(std::uint64_t length, const char* what) {
    const std::uint8_t* p = take(length, what);
    return Fields(p, length);
  }
  const std::uint8_t* take(std::uint64_t n, const char* what) {
    if (n > size_ - pos_) {
      throw Malformed(std::string(what) + " of " + std::to_string(n) + " bytes runs past the end of its record");
    }
    const std::uint8_t* p = data_ + pos_;
    pos_ += n;
    return p;
  }
  const std::uint8_t* data_;
  std::uint64_t size_;
  std::uint64_t pos_ = 0;
};

/// One record inside a byte range (a chunk's records): its opcode and content.
struct RecordView {
  std::uint8_t opcode = 0;
  Fields content{nullptr, 0};
  std::uint64_t end = 0;  // offset just past it
};

RecordView record_in(const std::vector<std::uint8_t>& bytes, std::uint64_t offset) {
  if (offset > bytes.size() || bytes.size() - offset < kRecordPrefix) throw Malformed(at("record", offset) + " runs past the end of its chunk");
  Fields prefix(bytes.data() + offset, kRecordPrefix);
  RecordView view;
  view.opcode = prefix.u8();
  const std::uint64_t length = prefix.u64();
  if (length > bytes.size() - offset - kRecordPrefix) {
    throw Malformed(at("record", offset) + " of " + std::to_string(length) + " bytes runs past the end of its chunk");
  }
  view.content = Fields(bytes.data() + offset + kRecordPrefix, length);
  view.end = offset + kRecordPrefix + length;
  return view;
}

void check_compression(const std::string& compression) {
  if (!compression.empty() && compression != "zstd" && compression != "lz4") {
    throw Malformed("unknown compression '" + compression + "' (slam2d reads '', 'zstd', 'lz4')");
  }
}

/// The records of a chunk; `compression` is one check_compression accepts.
std::vector<std::uint8_t> decompress(const std::string& compression, const std::uint8_t* data, std::uint64_t size,
                                     std::uint64_t uncompressed) {
  if (compression.empty()) {
    if (size != uncompressed) {
      throw Malformed("uncompressed chunk of " + std::to_string(size) + " bytes says " + std::to_string(uncompressed));
    }
    return std::vector<std::uint8_t>(data, data + size);
  }
  try {
    return detail::decompress(compression == "lz4" ? detail::Codec::kLz4Frame : detail::Codec::kZstd, {data, size},
                              uncompressed);
  } catch (const Error& e) {
    throw Malformed(e.what());
  }
}

class McapSource final : public BagSource {
 public:
  explicit McapSource(std::string path) : path_(std::move(path)) {
    try {
      open();
    } catch (const Malformed& e) {
      throw Error(path_ + ": " + e.what());
    }
  }

  const std::string& path() const override { return path_; }
  const std::vector<BagTopic>& topics() const override { return topics_; }
  double progress() const override {
    return messages_.empty() ? 1.0 : static_cast<double>(next_) / static_cast<double>(messages_.size());
  }

  std::optional<DecodedRecord> next(const std::vector<std::string>& wanted) override {
    if (!selected_ || wanted != wanted_) select(wanted);
    try {
      while (next_ < messages_.size()) {
        const MessageRef& ref = messages_[next_++];
        const Channel& channel = channels_.at(ref.channel);
        if (!topic_types_[channel.topic]) continue;
        const detail::Ros2Type type = *topic_types_[channel.topic];
        if (ref.chunk == kTopLevel) {
          const std::vector<std::uint8_t> content = read_record(ref.offset, kMessage, "message");
          return decode(Fields(content.data(), content.size()), ref, type);
        }
        load_chunk(ref.chunk);
        RecordView view = record_in(chunk_data_, ref.offset);
        if (view.opcode != kMessage) {
          throw Malformed(at("chunk", chunks_[ref.chunk].offset) + ": the message index points at record " +
                          std::to_string(ref.offset) + ", which is not a message");
        }
        return decode(view.content, ref, type);
      }
    } catch (const Malformed& e) {
      throw Error(path_ + ": " + e.what());
    }
    return std::nullopt;
  }

 private:
  static constexpr std::uint32_t kTopLevel = std::numeric_limits<std::uint32_t>::max();

  struct Channel {
    std::uint16_t schema_id = 0;
    std::string topic_name;
    std::string encoding;
    std::size_t topic = 0;  // index in topics_
  };
  struct ChunkRef {
    std::uint64_t offset = 0;  // of the Chunk record in the file
    std::uint64_t length = 0;  // the whole record
  };
  struct MessageRef {
    std::uint64_t log_time = 0;
    std::uint64_t offset = 0;   // of the Message record: in the file (top level) or in its chunk
    std::uint32_t chunk = 0;    // index in chunks_, or kTopLevel
    std::uint32_t order = 0;    // position in file order
    std::uint16_t channel = 0;
  };

  // --- reading the file -------------------------------------------------------------------------

  void read_exact(std::uint64_t offset, void* out, std::uint64_t n) {
    if (offset > size_ || n > size_ - offset) throw Malformed(at("read of " + std::to_string(n) + " bytes", offset).append(" runs past the end of the file"));
    file_.clear();
    file_.seekg(static_cast<std::streamoff>(offset));
    file_.read(static_cast<char*>(out), static_cast<std::streamsize>(n));
    if (!file_) throw Malformed(at("read error", offset));
  }

  /// A record's opcode and content length at `offset`, checked against the file size.
  std::pair<std::uint8_t, std::uint64_t> record_prefix(std::uint64_t offset) {
    if (offset > size_ || size_ - offset < kRecordPrefix) {
      throw Malformed(at("record", offset) + " runs past the end of the file (truncated?)");
    }
    std::uint8_t bytes[kRecordPrefix];
    read_exact(offset, bytes, kRecordPrefix);
    Fields prefix(bytes, kRecordPrefix);
    const std::uint8_t opcode = prefix.u8();
    const std::uint64_t length = prefix.u64();
    if (length > size_ - offset - kRecordPrefix) {
      throw Malformed(at("record", offset) + " (opcode " + std::to_string(opcode) + ") of " + std::to_string(length) +
                      " bytes runs past the end of the file (truncated?)");
    }
    return {opcode, length};
  }

  /// The content of the record at `offset`, which must have `opcode`.
  std::vector<std::uint8_t> read_record(std::uint64_t offset, std::uint8_t opcode, const char* what) {
    const auto [found, length] = record_prefix(offset);
    if (found != opcode) throw Malformed(at(what, offset) + ": found opcode " + std::to_string(found));
    std::vector<std::uint8_t> content(length);
    read_exact(offset + kRecordPrefix, content.data(), length);
    return content;
  }

  void open() {
    file_.open(path_, std::ios::binary);
    if (!file_) throw Malformed("cannot open");
    file_.seekg(0, std::ios::end);
    size_ = static_cast<std::uint64_t>(file_.tellg());
    unsigned char magic[8] = {};
    if (size_ < kMagic.size()) throw Malformed("not an MCAP file (too short for the magic)");
    read_exact(0, magic, kMagic.size());
    if (std::memcmp(magic, kMagic.data(), kMagic.size()) != 0) throw Malformed("not an MCAP file (bad magic)");

    if (!read_summary()) scan_data_section();
    std::stable_sort(messages_.begin(), messages_.end(),
                     [](const MessageRef& a, const MessageRef& b) { return a.log_time < b.log_time; });
    make_topics();
  }

  /// Reads the summary through the footer; false when the file has none (or no chunk indexes).
  bool read_summary() {
    if (size_ < 2 * kMagic.size() + kFooterRecord) return false;
    unsigned char magic[8];
    read_exact(size_ - kMagic.size(), magic, kMagic.size());
    if (std::memcmp(magic, kMagic.data(), kMagic.size()) != 0) return false;  // truncated: the linear pass reports it
    const std::uint64_t footer_offset = size_ - kMagic.size() - kFooterRecord;
    const std::vector<std::uint8_t> footer = read_record(footer_offset, kFooter, "footer");
    Fields fields(footer.data(), footer.size());
    const std::uint64_t summary_start = fields.u64();
    if (summary_start == 0) return false;
    if (summary_start < kMagic.size() || summary_start > footer_offset) {
      throw Malformed(at("footer", footer_offset) + ": summary start " + std::to_string(summary_start) + " is outside the file");
    }
    // The DataEnd record ends the data section, just before the summary.
    constexpr std::uint64_t kDataEndRecord = kRecordPrefix + 4;
    if (summary_start >= kMagic.size() + kDataEndRecord && record_prefix(summary_start - kDataEndRecord).first == kDataEnd) {
      check_data_section_crc(summary_start - kDataEndRecord);
    }
    struct ChunkIndex {
      ChunkRef chunk;
      std::vector<std::uint64_t> message_indexes;  // file offsets of its MessageIndex records
    };
    std::vector<ChunkIndex> indexes;
    for (std::uint64_t offset = summary_start; offset < footer_offset;) {
      const auto [opcode, length] = record_prefix(offset);
      if (opcode == kSchema || opcode == kChannel || opcode == kChunkIndex) {
        std::vector<std::uint8_t> content(length);
        read_exact(offset + kRecordPrefix, content.data(), length);
        Fields record(content.data(), content.size());
        try {
          if (opcode == kChunkIndex) {
            ChunkIndex index;
            record.u64();  // message_start_time
            record.u64();  // message_end_time
            index.chunk.offset = record.u64();
            index.chunk.length = record.u64();
            Fields offsets = record.sub32("message index offsets");
            while (!offsets.done()) {
              offsets.u16();
              index.message_indexes.push_back(offsets.u64());
            }
            indexes.push_back(std::move(index));
          } else {
            add_definition(opcode, record);
          }
        } catch (const Malformed& e) {
          throw Malformed(at("summary record", offset) + ": " + e.what());
        }
      }
      offset += kRecordPrefix + length;
    }
    if (indexes.empty()) return false;
    std::sort(indexes.begin(), indexes.end(),
              [](const ChunkIndex& a, const ChunkIndex& b) { return a.chunk.offset < b.chunk.offset; });
    for (ChunkIndex& index : indexes) {
      if (index.chunk.offset > size_ || index.chunk.length > size_ - index.chunk.offset) {
        throw Malformed(at("chunk index for the chunk", index.chunk.offset) + ": the chunk runs past the end of the file");
      }
      const auto chunk = static_cast<std::uint32_t>(chunks_.size());
      chunks_.push_back(index.chunk);
      if (index.message_indexes.empty()) {  // no message indexes: list the messages from the chunk itself
        load_chunk(chunk);
        list_chunk_messages(chunk);
        continue;
      }
      const std::size_t first = messages_.size();
      for (const std::uint64_t offset : index.message_indexes) read_message_index(offset, chunk);
      std::sort(messages_.begin() + static_cast<std::ptrdiff_t>(first), messages_.end(),
                [](const MessageRef& a, const MessageRef& b) { return a.offset < b.offset; });
      for (std::size_t i = first; i < messages_.size(); ++i) messages_[i].order = static_cast<std::uint32_t>(i);  // file order
    }
    return true;
  }

  void read_message_index(std::uint64_t offset, std::uint32_t chunk) {
    const std::vector<std::uint8_t> content = read_record(offset, kMessageIndex, "message index");
    try {
      Fields record(content.data(), content.size());
      const std::uint16_t channel = record.u16();
      require_channel(channel);
      Fields entries = record.sub32("message index entries");
      while (!entries.done()) {
        MessageRef ref;
        ref.log_time = entries.u64();
        ref.offset = entries.u64();
        ref.chunk = chunk;
        ref.channel = channel;
        add_message(ref);
      }
    } catch (const Malformed& e) {
      throw Malformed(at("message index", offset) + ": " + e.what());
    }
  }

  /// The DataEnd record at `offset`: a non-zero data_section_crc must be the CRC-32 of every byte
  /// before the record, the leading magic included, as the mcap libraries write it (one more read of
  /// the data section, in blocks).
  void check_data_section_crc(std::uint64_t offset) {
    const std::vector<std::uint8_t> content = read_record(offset, kDataEnd, "data end");
    Fields fields(content.data(), content.size());
    const std::uint32_t expected = fields.u32();
    if (expected == 0) return;
    std::vector<std::uint8_t> block(std::uint64_t{1} << 20);
    uLong actual = crc32(0L, Z_NULL, 0);
    for (std::uint64_t at = 0; at < offset;) {
      const std::uint64_t n = std::min<std::uint64_t>(block.size(), offset - at);
      read_exact(at, block.data(), n);
      actual = crc32(actual, block.data(), static_cast<uInt>(n));
      at += n;
    }
    if (actual != expected) {
      throw Malformed(at("data end", offset) + ": data section CRC mismatch (the file says " + std::to_string(expected) +
                      ", its bytes give " + std::to_string(actual) + ")");
    }
  }

  /// One pass over the data section, for a file without a summary or chunk indexes.
  void scan_data_section() {
    for (std::uint64_t offset = kMagic.size();;) {
      const auto [opcode, length] = record_prefix(offset);
      if (opcode == kDataEnd) check_data_section_crc(offset);
      if (opcode == kDataEnd || opcode == kFooter) return;
      if (opcode == kSchema || opcode == kChannel) {
        std::vector<std::uint8_t> content(length);
        read_exact(offset + kRecordPrefix, content.data(), length);
        Fields record(content.data(), content.size());
        add_definition(opcode, record, offset);
      } else if (opcode == kMessage) {
        std::uint8_t head[14];
        if (length < sizeof head) throw Malformed(at("message", offset) + " is too short");
        read_exact(offset + kRecordPrefix, head, sizeof head);
        Fields fields(head, sizeof head);
        MessageRef ref;
        ref.channel = fields.u16();
        fields.u32();  // sequence
        ref.log_time = fields.u64();
        ref.offset = offset;
        ref.chunk = kTopLevel;
        require_channel(ref.channel, offset);
        add_message(ref);
      } else if (opcode == kChunk) {
        const auto chunk = static_cast<std::uint32_t>(chunks_.size());
        chunks_.push_back(ChunkRef{offset, kRecordPrefix + length});
        load_chunk(chunk);
        list_chunk_messages(chunk);
      }
      offset += kRecordPrefix + length;
    }
  }

  /// The Schema, Channel and Message records of the loaded chunk.
  void list_chunk_messages(std::uint32_t chunk) {
    for (std::uint64_t offset = 0; offset < chunk_data_.size();) {
      try {
        RecordView view = record_in(chunk_data_, offset);
        if (view.opcode == kSchema || view.opcode == kChannel) {
          add_definition(view.opcode, view.content);
        } else if (view.opcode == kMessage) {
          MessageRef ref;
          ref.channel = view.content.u16();
          view.content.u32();  // sequence
          ref.log_time = view.content.u64();
          ref.offset = offset;
          ref.chunk = chunk;
          require_channel(ref.channel);
          add_message(ref);
        }
        offset = view.end;
      } catch (const Malformed& e) {
        throw Malformed(at("chunk", chunks_[chunk].offset) + ": " + at("record", offset) + ": " + e.what());
      }
    }
  }

  /// Decompresses chunk `index` into chunk_data_ (kept until another chunk is needed).
  void load_chunk(std::uint32_t index) {
    if (loaded_chunk_ == index) return;
    loaded_chunk_ = kTopLevel;
    const ChunkRef& chunk = chunks_[index];
    try {
      const auto [opcode, length] = record_prefix(chunk.offset);
      if (opcode != kChunk) throw Malformed("found opcode " + std::to_string(opcode) + ", not a chunk");
      if (kRecordPrefix + length != chunk.length) throw Malformed("its length differs from its chunk index's");
      const std::vector<std::uint8_t> content = read_record(chunk.offset, kChunk, "chunk");
      Fields fields(content.data(), content.size());
      fields.u64();  // message_start_time
      fields.u64();  // message_end_time
      const std::uint64_t uncompressed_size = fields.u64();
      const std::uint32_t crc = fields.u32();
      const std::string compression = fields.string();
      check_compression(compression);
      Fields records = fields.sub64("the records");
      chunk_data_ = decompress(compression, records.data(), records.remaining(), uncompressed_size);
      if (crc != 0) {
        uLong actual = crc32(0L, Z_NULL, 0);
        // zlib's crc32 takes uInt lengths: feed it in pieces.
        for (std::uint64_t at_byte = 0; at_byte < chunk_data_.size();) {
          const auto n = static_cast<uInt>(std::min<std::uint64_t>(chunk_data_.size() - at_byte, 1u << 30));
          actual = crc32(actual, chunk_data_.data() + at_byte, n);
          at_byte += n;
        }
        if (actual != crc) throw Malformed("CRC mismatch");
      }
    } catch (const Malformed& e) {
      throw Malformed(at("chunk", chunk.offset) + ": " + e.what());
    }
    loaded_chunk_ = index;
  }

  // --- definitions and messages -----------------------------------------------------------------

  void add_definition(std::uint8_t opcode, Fields& record, std::uint64_t offset = 0) {
    try {
      const std::uint16_t id = record.u16();
      if (opcode == kSchema) {
        schema_names_[id] = record.string();
        return;
      }
      Channel channel;
      channel.schema_id = record.u16();
      channel.topic_name = record.string();
      channel.encoding = record.string();
      channels_.emplace(id, std::move(channel));  // a repeated definition (in each chunk) is the same
    } catch (const Malformed& e) {
      throw Malformed(at(opcode == kSchema ? "schema" : "channel", offset) + ": " + e.what());
    }
  }

  void require_channel(std::uint16_t channel, std::uint64_t offset = 0) const {
    if (channels_.count(channel) == 0) {
      throw Malformed(at("message", offset) + " is on channel " + std::to_string(channel) + ", which is not defined before it");
    }
  }

  void add_message(MessageRef ref) {
    ref.order = static_cast<std::uint32_t>(messages_.size());
    messages_.push_back(ref);
  }

  /// One BagTopic per topic name (channels of the same topic merged), counts from the messages.
  void make_topics() {
    for (auto& [id, channel] : channels_) {
      const auto schema = schema_names_.find(channel.schema_id);
      const std::string type = schema == schema_names_.end() ? std::string() : schema->second;
      const auto same = std::find_if(topics_.begin(), topics_.end(),
                                     [&name = channel.topic_name](const BagTopic& topic) { return topic.name == name; });
      channel.topic = static_cast<std::size_t>(same - topics_.begin());
      if (same == topics_.end()) topics_.push_back(BagTopic{channel.topic_name, type, 0, 0.0, 0.0});
    }
    for (const MessageRef& ref : messages_) {
      BagTopic& topic = topics_[channels_.at(ref.channel).topic];
      const double time = detail::nanoseconds_to_seconds(ref.log_time);
      if (topic.count++ == 0) topic.first_stamp = time;
      topic.last_stamp = time;
    }
  }

  /// The wanted topics' types (checked: decodable, CDR); others are skipped by next().
  void select(const std::vector<std::string>& wanted) {
    wanted_ = wanted;
    selected_ = true;
    topic_types_.assign(topics_.size(), std::nullopt);
    for (const auto& [id, channel] : channels_) {
      const BagTopic& topic = topics_[channel.topic];
      if (std::find(wanted.begin(), wanted.end(), topic.name) == wanted.end()) continue;
      topic_types_[channel.topic] = detail::wanted_type(path_, topic.name, topic.type, channel.encoding);
    }
  }

  DecodedRecord decode(Fields message, const MessageRef& ref, detail::Ros2Type type) {
    try {
      const std::uint16_t channel = message.u16();
      message.u32();  // sequence
      const std::uint64_t log_time = message.u64();
      message.u64();  // publish_time
      if (channel != ref.channel || log_time != ref.log_time) {
        throw Malformed("does not match its index entry (channel " + std::to_string(channel) + ", log time " +
                        std::to_string(log_time) + ")");
      }
    } catch (const Malformed& e) {
      throw Malformed("message " + std::to_string(ref.order) + ": " + e.what());
    }
    return detail::decode_record(path_, topics_[channels_.at(ref.channel).topic].name, type, ref.log_time, ref.order,
                                 message.data(), message.remaining());
  }

  std::string path_;
  std::ifstream file_;
  std::uint64_t size_ = 0;
  std::map<std::uint16_t, std::string> schema_names_;
  std::map<std::uint16_t, Channel> channels_;
  std::vector<BagTopic> topics_;
  std::vector<ChunkRef> chunks_;
  std::vector<MessageRef> messages_;  // in log_time order once open() is done
  std::size_t next_ = 0;
  std::uint32_t loaded_chunk_ = kTopLevel;
  std::vector<std::uint8_t> chunk_data_;
  std::vector<std::string> wanted_;
  std::vector<std::optional<detail::Ros2Type>> topic_types_;  // per topic; set for the wanted ones
  bool selected_ = false;
};

}  // namespace

bool is_mcap(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  char magic[kMagic.size()] = {};
  return file.read(magic, kMagic.size()) && std::memcmp(magic, kMagic.data(), kMagic.size()) == 0;
}

std::unique_ptr<BagSource> open_mcap(const std::string& path) { return std::make_unique<McapSource>(path); }

}  // namespace slam2d
