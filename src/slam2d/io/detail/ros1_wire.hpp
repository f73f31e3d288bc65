// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Little-endian reads over a byte span, each one checked against the bytes left: the one reader
// for ROS 1 record headers, index data and serialized messages; and the writer of the same.

#include <bit>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "slam2d/core/error.hpp"

namespace slam2d::ros1 {

using Bytes = std::span<const std::uint8_t>;

/// Throws Error("needs N bytes at byte P of M"): a length that runs past its record.
[[noreturn]] void throw_overrun(std::size_t wanted, std::size_t position, std::size_t size);

class WireReader {
 public:
  explicit WireReader(Bytes bytes) : bytes_(bytes) {}

  std::size_t position() const { return position_; }
  std::size_t remaining() const { return bytes_.size() - position_; }

  Bytes bytes(std::size_t n) {
    need(n);
    const Bytes out = bytes_.subspan(position_, n);
    position_ += n;
    return out;
  }
  void skip(std::size_t n) { bytes(n); }
  std::uint32_t u32() {
    const Bytes b = bytes(4);
    return static_cast<std::uint32_t>(b[0]) | static_cast<std::uint32_t>(b[1]) << 8 |
           static_cast<std::uint32_t>(b[2]) << 16 | static_cast<std::uint32_t>(b[3]) << 24;
  }
  std::uint64_t u64() {
    const std::uint64_t low = u32();
    return low | static_cast<std::uint64_t>(u32()) << 32;
  }
  float f32() { return std::bit_cast<float>(u32()); }
  double f64() { return std::bit_cast<double>(u64()); }
  /// ROS 1 string: uint32 length, then the bytes.
  std::string string() {
    const Bytes b = bytes(u32());
    return {reinterpret_cast<const char*>(b.data()), b.size()};
  }
  /// ROS 1 array length: uint32 count, checked against the bytes left for elements of at least
  /// `min_element_size` bytes, so that nothing is allocated for a count the data cannot hold.
  std::size_t count(std::size_t min_element_size) {
    const std::size_t n = u32();
    if (min_element_size > 0 && n > remaining() / min_element_size) throw_overrun(n * min_element_size, position_, bytes_.size());
    return n;
  }

 private:
  void need(std::size_t n) const {
    if (n > remaining()) throw_overrun(n, position_, bytes_.size());
  }

  Bytes bytes_;
  std::size_t position_ = 0;
};

class WireWriter {
 public:
  WireWriter& u8(std::uint8_t v) {
    bytes_.push_back(v);
    return *this;
  }
  WireWriter& u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) bytes_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }
  WireWriter& u64(std::uint64_t v) { return u32(static_cast<std::uint32_t>(v)).u32(static_cast<std::uint32_t>(v >> 32)); }
  WireWriter& f32(float v) { return u32(std::bit_cast<std::uint32_t>(v)); }
  WireWriter& f64(double v) { return u64(std::bit_cast<std::uint64_t>(v)); }
  WireWriter& raw(Bytes data) {
    bytes_.insert(bytes_.end(), data.begin(), data.end());
    return *this;
  }
  /// ROS 1 string (or uint8[]): uint32 length, then the bytes.
  WireWriter& string(std::string_view text) {
    u32(static_cast<std::uint32_t>(text.size()));
    return raw({reinterpret_cast<const std::uint8_t*>(text.data()), text.size()});
  }
  std::size_t size() const { return bytes_.size(); }
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }
  std::vector<std::uint8_t> take() { return std::move(bytes_); }

 private:
  std::vector<std::uint8_t> bytes_;
};

}  // namespace slam2d::ros1
