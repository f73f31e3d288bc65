// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The block compressions of the bag formats, in one place for their readers and writers: bz2 (ROS 1
// chunks), lz4 as one LZ4 frame (ROS 1's roslz4 and MCAP's "lz4") and zstd (MCAP), through
// Debian's libbz2, liblz4 and libzstd.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace slam2d::detail {

enum class Codec { kNone, kBz2, kLz4Frame, kZstd };

/// `data` compressed (kNone: copied).
std::vector<std::uint8_t> compress(Codec codec, std::span<const std::uint8_t> data);

/// `data` decompressed to exactly `size` bytes; Error("CODEC: reason") for corrupt data or data that
/// gives another size. The caller bounds `size` before calling (the bytes are allocated up front).
std::vector<std::uint8_t> decompress(Codec codec, std::span<const std::uint8_t> data, std::size_t size);

}  // namespace slam2d::detail
