// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/detail/ros1_records.hpp"

#include <memory>

#include "slam2d/io/detail/compression.hpp"

namespace slam2d::ros1 {

void throw_overrun(std::size_t wanted, std::size_t position, std::size_t size) {
  throw Error("needs " + std::to_string(wanted) + " bytes at byte " + std::to_string(position) + " of " +
              std::to_string(size) + " (truncated, or a length runs past its record)");
}

Time read_time(WireReader& reader) {
  Time time;
  time.sec = reader.u32();
  time.nsec = reader.u32();
  return time;
}

HeaderFields::HeaderFields(Bytes bytes) {
  WireReader reader(bytes);
  while (reader.remaining() > 0) {
    const Bytes field = reader.bytes(reader.u32());
    const std::string_view text(reinterpret_cast<const char*>(field.data()), field.size());
    const std::size_t equals = text.find('=');
    check(equals != std::string_view::npos, "a header field without '='");
    fields_.emplace_back(text.substr(0, equals), field.subspan(equals + 1));
  }
}

std::optional<Bytes> HeaderFields::find(std::string_view name) const {
  for (const auto& [key, value] : fields_) {
    if (key == name) return value;
  }
  return std::nullopt;
}

Bytes HeaderFields::get(std::string_view name) const {
  const std::optional<Bytes> value = find(name);
  if (!value) throw Error("a record header without its field '" + std::string(name) + "'");
  return *value;
}

namespace {
WireReader fixed_field(const HeaderFields& fields, std::string_view name, std::size_t size) {
  const Bytes value = fields.get(name);
  if (value.size() != size) {
    throw Error("header field '" + std::string(name) + "' has " + std::to_string(value.size()) + " bytes, not " +
                std::to_string(size));
  }
  return WireReader(value);
}
}  // namespace

Op HeaderFields::op() const { return static_cast<Op>(fixed_field(*this, "op", 1).bytes(1)[0]); }
std::uint32_t HeaderFields::u32(std::string_view name) const { return fixed_field(*this, name, 4).u32(); }
std::uint64_t HeaderFields::u64(std::string_view name) const { return fixed_field(*this, name, 8).u64(); }
Time HeaderFields::time(std::string_view name) const {
  WireReader reader = fixed_field(*this, name, 8);
  return read_time(reader);
}
std::string HeaderFields::text(std::string_view name) const {
  const Bytes value = get(name);
  return {reinterpret_cast<const char*>(value.data()), value.size()};
}

RecordLayout record_layout(std::uint64_t pos, std::uint64_t size, std::uint32_t header_len, std::uint32_t data_len) {
  RecordLayout layout;
  layout.header_pos = pos + 4;
  layout.header_len = header_len;
  layout.data_pos = layout.header_pos + header_len + 4;
  layout.data_len = data_len;
  if (layout.end() > size) {
    throw Error("record at byte " + std::to_string(pos) + " (header " + std::to_string(header_len) + " bytes, data " +
                std::to_string(data_len) + ") runs past the end at byte " + std::to_string(size) + " (truncated?)");
  }
  return layout;
}

std::vector<std::uint8_t> decompress_chunk(std::string_view compression, Bytes data, std::uint64_t size) {
  if (compression == "none") {  // copied, so that every chunk is owned the same way
    if (data.size() != size) {
      throw Error("uncompressed chunk of " + std::to_string(data.size()) + " bytes, its header says " +
                  std::to_string(size));
    }
    return {data.begin(), data.end()};
  }
  if (compression != "bz2" && compression != "lz4") {
    throw Error("unknown chunk compression '" + std::string(compression) + "' (slam2d reads none, bz2 and lz4)");
  }
  try {  // detail::decompress refuses a declared size past the input limits (a bomb) first
    return detail::decompress(compression == "bz2" ? detail::Codec::kBz2 : detail::Codec::kLz4Frame, data, size);
  } catch (const Error& e) {
    throw Error(std::string("corrupt chunk: ") + e.what());
  }
}

}  // namespace slam2d::ros1
