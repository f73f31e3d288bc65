// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/detail/compression.hpp"

#include <algorithm>
#include <bzlib.h>
#include <lz4frame.h>
#include <zstd.h>

#include <climits>
#include <memory>
#include <string>

#include "slam2d/core/error.hpp"
#include "slam2d/io/input_limits.hpp"

namespace slam2d::detail {
namespace {

constexpr int kZstdLevel = 3;  // zstd's default: mcap and rosbag2 write it

char* chars(const std::uint8_t* bytes) { return reinterpret_cast<char*>(const_cast<std::uint8_t*>(bytes)); }

void check_int(std::size_t size, const char* codec) {
  if (size > static_cast<std::size_t>(UINT_MAX)) throw Error(std::string(codec) + ": a block of " + std::to_string(size) + " bytes is too large");
}

std::vector<std::uint8_t> bz2_compress(std::span<const std::uint8_t> data) {
  check_int(data.size(), "bz2");
  unsigned int size = static_cast<unsigned int>(data.size() + data.size() / 100 + 600);  // bzlib's bound
  std::vector<std::uint8_t> out(size);
  const int status = BZ2_bzBuffToBuffCompress(chars(out.data()), &size, chars(data.data()),
                                              static_cast<unsigned int>(data.size()), 9, 0, 0);
  if (status != BZ_OK) throw Error("bz2: compression failed (" + std::to_string(status) + ")");
  out.resize(size);
  return out;
}

std::vector<std::uint8_t> bz2_decompress(std::span<const std::uint8_t> data, std::size_t size) {
  check_int(size, "bz2");
  check_int(data.size(), "bz2");
  std::vector<std::uint8_t> out(size);
  unsigned int out_size = static_cast<unsigned int>(size);
  const int status = BZ2_bzBuffToBuffDecompress(chars(out.data()), &out_size, chars(data.data()),
                                                static_cast<unsigned int>(data.size()), 0, 0);
  if (status == BZ_OUTBUFF_FULL) throw Error("bz2: the data gives more than " + std::to_string(size) + " bytes");
  if (status != BZ_OK) throw Error("bz2: corrupt data (" + std::to_string(status) + ")");
  if (out_size != size) throw Error("bz2: the data gives " + std::to_string(out_size) + " bytes, not " + std::to_string(size));
  return out;
}

std::vector<std::uint8_t> lz4_compress(std::span<const std::uint8_t> data) {
  std::vector<std::uint8_t> out(LZ4F_compressFrameBound(data.size(), nullptr));
  const std::size_t size = LZ4F_compressFrame(out.data(), out.size(), data.data(), data.size(), nullptr);
  if (LZ4F_isError(size)) throw Error(std::string("lz4: ") + LZ4F_getErrorName(size));
  out.resize(size);
  return out;
}

std::vector<std::uint8_t> lz4_decompress(std::span<const std::uint8_t> data, std::size_t size) {
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) throw Error("lz4: cannot create a context");
  const std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> context(raw, LZ4F_freeDecompressionContext);
  std::vector<std::uint8_t> out(size);
  std::size_t in_pos = 0;
  std::size_t out_pos = 0;
  std::size_t hint = 1;
  while (in_pos < data.size()) {  // one frame, or several one after the other
    std::size_t in_size = data.size() - in_pos;
    std::size_t out_size = size - out_pos;
    hint = LZ4F_decompress(context.get(), out.data() + out_pos, &out_size, data.data() + in_pos, &in_size, nullptr);
    if (LZ4F_isError(hint)) throw Error(std::string("lz4: corrupt data (") + LZ4F_getErrorName(hint) + ")");
    in_pos += in_size;
    out_pos += out_size;
    if (in_size == 0 && out_size == 0) break;  // no progress: the output is full
  }
  if (in_pos < data.size()) throw Error("lz4: the data gives more than " + std::to_string(size) + " bytes");
  if (hint != 0) throw Error("lz4: the data ends inside its frame (truncated)");
  if (out_pos != size) throw Error("lz4: the data gives " + std::to_string(out_pos) + " bytes, not " + std::to_string(size));
  return out;
}

std::vector<std::uint8_t> zstd_compress(std::span<const std::uint8_t> data) {
  std::vector<std::uint8_t> out(ZSTD_compressBound(data.size()));
  const std::size_t size = ZSTD_compress(out.data(), out.size(), data.data(), data.size(), kZstdLevel);
  if (ZSTD_isError(size)) throw Error(std::string("zstd: ") + ZSTD_getErrorName(size));
  out.resize(size);
  return out;
}

std::vector<std::uint8_t> zstd_decompress(std::span<const std::uint8_t> data, std::size_t size) {
  std::vector<std::uint8_t> out(size);
  const std::size_t got = ZSTD_decompress(out.data(), out.size(), data.data(), data.size());
  if (ZSTD_isError(got)) throw Error(std::string("zstd: ") + ZSTD_getErrorName(got));
  if (got != size) throw Error("zstd: the data gives " + std::to_string(got) + " bytes, not " + std::to_string(size));
  return out;
}

}  // namespace

std::vector<std::uint8_t> compress(Codec codec, std::span<const std::uint8_t> data) {
  switch (codec) {
    case Codec::kNone: return {data.begin(), data.end()};
    case Codec::kBz2: return bz2_compress(data);
    case Codec::kLz4Frame: return lz4_compress(data);
    case Codec::kZstd: return zstd_compress(data);
  }
  throw Error("unknown codec");
}

std::vector<std::uint8_t> decompress(Codec codec, std::span<const std::uint8_t> data, std::size_t size) {
  // A chunk declares its inflated size, and that much is allocated: a hostile declaration (or a
  // real bomb) is refused before.
  const InputLimits& limits = input_limits();
  if (codec != Codec::kNone &&
      (size > limits.max_decompressed_bytes || size / std::max<std::size_t>(data.size(), 1) >= limits.max_compression_ratio)) {
    throw Error("a compressed block of " + std::to_string(data.size()) + " bytes declares " + std::to_string(size) +
                " bytes inflated: over max_decompressed_bytes (" + std::to_string(limits.max_decompressed_bytes) +
                ") or max_compression_ratio (" + std::to_string(limits.max_compression_ratio) + "); a decompression bomb? " +
                limit_hint("max_decompressed_bytes"));
  }
  switch (codec) {
    case Codec::kNone:
      if (data.size() != size) throw Error("uncompressed data of " + std::to_string(data.size()) + " bytes, not " + std::to_string(size));
      return {data.begin(), data.end()};
    case Codec::kBz2: return bz2_decompress(data, size);
    case Codec::kLz4Frame: return lz4_decompress(data, size);
    case Codec::kZstd: return zstd_decompress(data, size);
  }
  throw Error("unknown codec");
}

}  // namespace slam2d::detail
