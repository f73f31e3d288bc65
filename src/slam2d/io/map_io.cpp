// SPDX-License-Identifier: BSD-3-Clause
// Occupancy maps in the ROS map_server format (map_server/src/image_loader.cpp and
// map_saver.cpp of ROS 1 navigation; nav2_map_server's map_io.cpp for the "raw" mode).
// Images: Netpbm PGM (P5 binary, P2 ASCII; http://netpbm.sourceforge.net/doc/pgm.html) and PNG
// through libpng.
//
// Choices made here:
// - Pixels are converted to one grey level before the thresholds: colour is the rounded mean of
//   R, G and B, and any alpha channel (or tRNS transparency) is ignored.
// - 16-bit PNG and PGM samples with maxval < 255 are scaled to 8 bits with rounding
//   (v * 255 / maxval); PGM with maxval > 255 is rejected.
// - "scale" mode: 1 + 98 (p - free) / (occupied - free), truncated, as ROS 1 map_server.
// - "raw" mode: the pixel value (255 - value when negate, as both map servers do) if it is at most
//   100, else unknown.

#include "slam2d/io/map_io.hpp"

#include <png.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <csetjmp>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>

#include "slam2d/core/error.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/detail/number_format.hpp"
#include "slam2d/io/input_limits.hpp"

namespace slam2d {

namespace {


std::vector<std::uint8_t> read_file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ParseError(path, 0, std::string("cannot open: ") + std::strerror(errno));
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw ParseError(path, 0, "read error");
  return bytes;
}

// ---------------------------------------------------------------------------------------------
// PGM

/// Reads the whitespace-separated numbers of a PGM, skipping '#' comments and counting lines.
class PgmTokens {
 public:
  PgmTokens(const std::vector<std::uint8_t>& bytes, const std::string& path) : bytes_(bytes), path_(path) {}

  /// The next unsigned decimal number; `what` names it in errors.
  long long next_number(const char* what) {
    skip_space_and_comments();
    if (pos_ >= bytes_.size()) throw ParseError(path_, line_, std::string("truncated PGM: missing ") + what);
    long long value = 0;
    std::size_t digits = 0;
    while (pos_ < bytes_.size() && std::isdigit(bytes_[pos_])) {
      value = std::min(value * 10 + (bytes_[pos_++] - '0'), 1LL << 40);
      ++digits;
    }
    if (digits == 0 || (pos_ < bytes_.size() && !is_space(bytes_[pos_]) && bytes_[pos_] != '#')) {
      throw ParseError(path_, line_, std::string("PGM: expected ") + what + " (a non-negative integer)");
    }
    return value;
  }
  /// After the header of a P5 file: exactly one whitespace byte, then the raster.
  std::size_t raster_start() {
    if (pos_ >= bytes_.size()) throw ParseError(path_, line_, "truncated PGM: no pixel data");
    return pos_ + 1;
  }
  void skip(std::size_t n) { pos_ += n; }
  std::size_t line() const { return line_; }

 private:
  static bool is_space(std::uint8_t c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }
  void skip_space_and_comments() {
    while (pos_ < bytes_.size()) {
      const std::uint8_t c = bytes_[pos_];
      if (c == '#') {
        while (pos_ < bytes_.size() && bytes_[pos_] != '\n') ++pos_;
      } else if (is_space(c)) {
        if (c == '\n') ++line_;
        ++pos_;
      } else {
        return;
      }
    }
  }

  const std::vector<std::uint8_t>& bytes_;
  const std::string& path_;
  std::size_t pos_ = 2;   // after the magic number
  std::size_t line_ = 1;  // 1-based
};

std::uint8_t scale_sample(long long value, long long maxval) {
  return static_cast<std::uint8_t>((value * 255 + maxval / 2) / maxval);
}

/// The P5 raster: width * height bytes right after the header's single whitespace byte.
void read_binary_raster(const std::vector<std::uint8_t>& bytes, PgmTokens& tokens, long long maxval,
                        const std::string& path, GrayImage& image) {
  const auto count = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  const std::size_t start = tokens.raster_start();
  const std::size_t available = bytes.size() - std::min(bytes.size(), start);
  if (available < count) {
    throw ParseError(path, 0, "truncated PGM: expected " + std::to_string(count) + " bytes of pixel data, found " +
                                  std::to_string(available));
  }
  image.pixels.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint8_t v = bytes[start + i];
    if (v > maxval) throw ParseError(path, 0, "PGM: pixel value " + std::to_string(v) + " exceeds maxval");
    image.pixels[i] = scale_sample(v, maxval);
  }
}

/// The P2 raster: width * height decimal numbers (comments allowed).
void read_ascii_raster(const std::vector<std::uint8_t>& bytes, PgmTokens& tokens, long long maxval,
                       const std::string& path, GrayImage& image) {
  const auto count = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  if (bytes.size() < count) {  // every ASCII sample takes at least one byte
    throw ParseError(path, 0, "truncated PGM: expected " + std::to_string(count) + " pixel values");
  }
  image.pixels.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    const long long v = tokens.next_number("pixel value");
    if (v > maxval) throw ParseError(path, tokens.line(), "PGM: pixel value " + std::to_string(v) + " exceeds maxval");
    image.pixels[i] = scale_sample(v, maxval);
  }
}

GrayImage decode_pgm(const std::vector<std::uint8_t>& bytes, const std::string& path) {
  PgmTokens tokens(bytes, path);
  const long long width = tokens.next_number("width");
  const long long height = tokens.next_number("height");
  if (width <= 0 || height <= 0 || static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height) > input_limits().max_map_cells) {
    throw ParseError(path, tokens.line(), "PGM: invalid size " + std::to_string(width) + " x " + std::to_string(height));
  }
  const long long maxval = tokens.next_number("maxval");
  if (maxval > 255) {
    throw ParseError(path, tokens.line(), "PGM with maxval " + std::to_string(maxval) +
                                              " (16-bit samples) is not supported: maxval must be at most 255");
  }
  if (maxval == 0) throw ParseError(path, tokens.line(), "PGM: maxval must be positive");
  GrayImage image{static_cast<int>(width), static_cast<int>(height), {}};
  if (bytes[1] == '5') read_binary_raster(bytes, tokens, maxval, path, image);
  else read_ascii_raster(bytes, tokens, maxval, path, image);
  return image;
}

// ---------------------------------------------------------------------------------------------
// PNG (libpng; errors leave libpng through longjmp to a frame that owns no C++ objects)

struct PngSource {
  const std::vector<std::uint8_t>* bytes = nullptr;
  std::size_t pos = 0;
  char error[256] = "";
};

void png_read_bytes(png_structp png, png_bytep out, png_size_t n) {
  auto* source = static_cast<PngSource*>(png_get_io_ptr(png));
  if (source->bytes->size() - source->pos < n) png_error(png, "truncated PNG");
  std::memcpy(out, source->bytes->data() + source->pos, n);
  source->pos += n;
}

void png_fail(png_structp png, png_const_charp message) {
  auto* source = static_cast<PngSource*>(png_get_error_ptr(png));
  std::snprintf(source->error, sizeof(source->error), "%s", message);
  png_longjmp(png, 1);
}

void png_ignore_warning(png_structp, png_const_charp) {}

/// Decoded 8-bit samples, `channels` per pixel (1 grey, 2 grey + alpha, 3 RGB, 4 RGBA).
struct PngRaster {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<std::uint8_t> samples;
  std::vector<png_bytep> rows;
};

/// Sets the transformations to 8-bit grey or RGB (alpha kept, ignored later) and reads the image.
/// False on a libpng error (message in the source). No C++ object lives in this frame.
bool png_decode(png_structp png, png_infop info, const PngSource& source, PngRaster& raster, bool want_rgb) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_info(png, info);
  const png_uint_32 width = png_get_image_width(png, info);
  const png_uint_32 height = png_get_image_height(png, info);
  if (static_cast<std::uint64_t>(width) * height > input_limits().max_map_cells) png_error(png, "image too large");
  const int colour_type = png_get_color_type(png, info);
  if (png_get_bit_depth(png, info) == 16) png_set_scale_16(png);
  if (colour_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (colour_type == PNG_COLOR_TYPE_GRAY) png_set_expand_gray_1_2_4_to_8(png);
  if (want_rgb) png_set_gray_to_rgb(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  raster.width = static_cast<int>(width);
  raster.height = static_cast<int>(height);
  raster.channels = png_get_channels(png, info);
  if (png_get_bit_depth(png, info) != 8 || png_get_rowbytes(png, info) != width * raster.channels) {
    png_error(png, "unsupported PNG pixel format");
  }
  // Deflate compresses at most ~1032:1, so a raster much larger than that is a lie of the header.
  if (static_cast<double>(width) * height * raster.channels > 1100.0 * static_cast<double>(source.bytes->size()) + 1e6) {
    png_error(png, "image size does not fit the file size");
  }
  raster.samples.resize(static_cast<std::size_t>(width) * height * raster.channels);
  raster.rows.resize(height);
  for (png_uint_32 row = 0; row < height; ++row) {
    raster.rows[row] = raster.samples.data() + static_cast<std::size_t>(row) * width * raster.channels;
  }
  png_read_image(png, raster.rows.data());
  png_read_end(png, nullptr);
  return true;
}

PngRaster decode_png(const std::vector<std::uint8_t>& bytes, const std::string& path, bool want_rgb) {
  PngSource source;
  source.bytes = &bytes;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &source, png_fail, png_ignore_warning);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  if (info == nullptr) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    throw Error(path + ": cannot initialise libpng");
  }
  png_set_read_fn(png, &source, png_read_bytes);
  PngRaster raster;
  bool ok = false;
  try {
    ok = png_decode(png, info, source, raster, want_rgb);
  } catch (...) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw;
  }
  png_destroy_read_struct(&png, &info, nullptr);
  if (!ok) throw ParseError(path, 0, std::string("corrupt PNG: ") + source.error);
  return raster;
}

bool is_png(const std::vector<std::uint8_t>& bytes) { return bytes.size() >= 8 && png_sig_cmp(bytes.data(), 0, 8) == 0; }

GrayImage gray_from_raster(const PngRaster& raster) {
  GrayImage image{raster.width, raster.height, {}};
  const std::size_t count = static_cast<std::size_t>(raster.width) * raster.height;
  image.pixels.resize(count);
  const int c = raster.channels;
  for (std::size_t i = 0; i < count; ++i) {
    const std::uint8_t* s = raster.samples.data() + i * c;
    image.pixels[i] = c <= 2 ? s[0] : static_cast<std::uint8_t>((s[0] + s[1] + s[2] + 1) / 3);  // rounded mean
  }
  return image;
}

/// The PNG file's bytes; `path` (or what the image is) heads the error messages.
std::vector<std::uint8_t> encode_png_bytes(const std::string& path, int width, int height, bool rgb,
                                           const std::vector<std::uint8_t>& samples) {
  const std::size_t channels = rgb ? 3 : 1;
  check(width > 0 && height > 0 && samples.size() == static_cast<std::size_t>(width) * height * channels,
        path + ": cannot write an empty image or one whose size does not match its pixels");
  png_image image;
  std::memset(&image, 0, sizeof(image));
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = rgb ? PNG_FORMAT_RGB : PNG_FORMAT_GRAY;
  png_alloc_size_t size = 0;
  if (png_image_write_to_memory(&image, nullptr, &size, 0, samples.data(), 0, nullptr) == 0) {
    const std::string message = image.message;
    png_image_free(&image);
    throw Error(path + ": cannot encode PNG: " + message);
  }
  std::vector<std::uint8_t> encoded(size);
  const int ok = png_image_write_to_memory(&image, encoded.data(), &size, 0, samples.data(), 0, nullptr);
  const std::string message = image.message;
  png_image_free(&image);
  if (ok == 0) throw Error(path + ": cannot encode PNG: " + message);
  encoded.resize(size);
  return encoded;
}

void encode_png(const std::string& path, int width, int height, bool rgb, const std::vector<std::uint8_t>& samples) {
  write_file_atomically(path, std::span<const std::uint8_t>(encode_png_bytes(path, width, height, rgb, samples)));
}

// ---------------------------------------------------------------------------------------------
// YAML metadata

/// A plain number, or YAML's spellings of infinity and NaN (.inf, -.inf, .nan, ...).
std::optional<double> parse_yaml_number(const std::string& text) {
  std::string lower = text;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower == ".nan") return std::nan("");
  if (lower == ".inf" || lower == "+.inf") return HUGE_VAL;
  if (lower == "-.inf") return -HUGE_VAL;
  return parse_double(text);
}

struct YamlKey {
  YAML::Node value;
  std::size_t line = 0;  // 1-based line of the key
};

/// Reads the YAML's keys and fails with ParseError(yaml path, line of the key, message).
class MetadataParser {
 public:
  MetadataParser(std::string path, YAML::Node root) : path_(std::move(path)), root_(std::move(root)) {}

  YamlKey require(const std::string& key) const {
    std::optional<YamlKey> found = find(key);
    if (!found) throw ParseError(path_, 0, "missing key '" + key + "'");
    return *found;
  }
  std::optional<YamlKey> find(const std::string& key) const {
    for (auto it = root_.begin(); it != root_.end(); ++it) {
      if (it->first.IsScalar() && it->first.Scalar() == key) {
        return YamlKey{it->second, static_cast<std::size_t>(it->first.Mark().line + 1)};
      }
    }
    return std::nullopt;
  }
  std::string scalar(const YamlKey& key, const std::string& name) const {
    if (!key.value.IsScalar()) fail(key, name + " must be a single value");
    return key.value.Scalar();
  }
  double finite_number(const YamlKey& key, const std::string& name) const {
    const std::string text = scalar(key, name);
    const std::optional<double> value = parse_yaml_number(text);
    if (!value) fail(key, name + " is not a number: '" + text + "'");
    if (!std::isfinite(*value)) fail(key, name + " must be finite, got " + text);
    return *value;
  }
  [[noreturn]] void fail(const YamlKey& key, const std::string& message) const {
    throw ParseError(path_, key.line, message);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  YAML::Node root_;
};

YAML::Node load_yaml(const std::string& yaml_path) {
  const std::vector<std::uint8_t> bytes = read_file_bytes(yaml_path);
  YAML::Node root;
  try {
    root = YAML::Load(std::string(bytes.begin(), bytes.end()));
  } catch (const YAML::Exception& e) {
    std::string message = e.msg;  // may quote the offending (binary) byte
    for (char& c : message) c = std::isprint(static_cast<unsigned char>(c)) ? c : '?';
    throw ParseError(yaml_path, e.mark.line >= 0 ? e.mark.line + 1 : 0, "not valid YAML: " + message);
  }
  if (!root.IsMap()) {
    const std::size_t line = root.IsDefined() && !root.IsNull() ? root.Mark().line + 1 : 0;
    throw ParseError(yaml_path, line, "not a map YAML file: expected keys image, resolution, origin, ...");
  }
  return root;
}

void parse_origin(const MetadataParser& parser, MapMetadata& meta) {
  const YamlKey key = parser.require("origin");
  if (!key.value.IsSequence() || key.value.size() != 3) {
    const std::string got = key.value.IsSequence() ? std::to_string(key.value.size()) + " values" : "no list";
    parser.fail(key, "origin must be a list of 3 numbers [x, y, yaw], got " + got);
  }
  for (std::size_t i = 0; i < 3; ++i) {
    const YamlKey element{key.value[i], key.line};
    meta.origin[static_cast<Eigen::Index>(i)] = parser.finite_number(element, "origin");
  }
}

void parse_thresholds(const MetadataParser& parser, MapMetadata& meta) {
  const YamlKey occupied = parser.require("occupied_thresh");
  const YamlKey free = parser.require("free_thresh");
  meta.occupied_thresh = parser.finite_number(occupied, "occupied_thresh");
  meta.free_thresh = parser.finite_number(free, "free_thresh");
  if (meta.occupied_thresh < 0.0 || meta.occupied_thresh > 1.0) {
    parser.fail(occupied, "occupied_thresh must lie in [0, 1], got " + format_number(meta.occupied_thresh));
  }
  if (meta.free_thresh < 0.0 || meta.free_thresh > 1.0) {
    parser.fail(free, "free_thresh must lie in [0, 1], got " + format_number(meta.free_thresh));
  }
  if (meta.free_thresh >= meta.occupied_thresh) {
    parser.fail(free, "free_thresh (" + format_number(meta.free_thresh) + ") must be below occupied_thresh (" +
                          format_number(meta.occupied_thresh) + ")");
  }
}

void parse_options(const MetadataParser& parser, MapMetadata& meta) {
  if (const std::optional<YamlKey> negate = parser.find("negate")) {
    const std::string text = parser.scalar(*negate, "negate");
    if (text == "0" || text == "false" || text == "False" || text == "FALSE") meta.negate = false;
    else if (text == "1" || text == "true" || text == "True" || text == "TRUE") meta.negate = true;
    else parser.fail(*negate, "negate must be 0 or 1, got '" + text + "'");
  }
  if (const std::optional<YamlKey> mode = parser.find("mode")) {
    meta.mode = parser.scalar(*mode, "mode");
    if (meta.mode != "trinary" && meta.mode != "scale" && meta.mode != "raw") {
      parser.fail(*mode, "mode must be trinary, scale or raw, got '" + meta.mode + "'");
    }
  }
}

std::filesystem::path resolve_image(const std::string& yaml_path, const std::string& image) {
  const std::filesystem::path path(image);
  if (path.is_absolute()) return path;
  return std::filesystem::path(yaml_path).parent_path() / path;
}

/// The metadata and the resolved image path; the image must exist.
MapMetadata parse_metadata(const std::string& yaml_path, std::filesystem::path& image_path) {
  const MetadataParser parser(yaml_path, load_yaml(yaml_path));
  MapMetadata meta;
  const YamlKey image = parser.require("image");
  meta.image = parser.scalar(image, "image");
  if (meta.image.empty()) parser.fail(image, "image must name the map's image file");
  const YamlKey resolution = parser.require("resolution");
  meta.resolution = parser.finite_number(resolution, "resolution");
  if (meta.resolution <= 0.0) parser.fail(resolution, "resolution must be positive, got " + parser.scalar(resolution, ""));
  parse_origin(parser, meta);
  parse_thresholds(parser, meta);
  parse_options(parser, meta);
  image_path = resolve_image(yaml_path, meta.image);
  std::error_code error;
  if (!std::filesystem::is_regular_file(image_path, error)) {
    parser.fail(image, "image '" + meta.image + "' not found (looked for " + image_path.string() + ")");
  }
  return meta;
}

// ---------------------------------------------------------------------------------------------
// Pixels <-> cells

/// The cell value of every grey level, as map_server (see the header and the notes above).
std::array<std::int8_t, 256> pixel_to_cell_table(const MapMetadata& meta) {
  std::array<std::int8_t, 256> table{};
  for (int pixel = 0; pixel < 256; ++pixel) {
    const int v = meta.negate ? 255 - pixel : pixel;
    std::int8_t cell = OccupancyMap::kUnknown;
    const double p = (255.0 - v) / 255.0;
    if (meta.mode == "raw") {
      cell = v <= 100 ? static_cast<std::int8_t>(v) : OccupancyMap::kUnknown;
    } else if (p > meta.occupied_thresh) {
      cell = OccupancyMap::kOccupied;
    } else if (p < meta.free_thresh) {
      cell = OccupancyMap::kFree;
    } else if (meta.mode == "scale") {
      cell = static_cast<std::int8_t>(1.0 + 98.0 * (p - meta.free_thresh) / (meta.occupied_thresh - meta.free_thresh));
    }
    table[static_cast<std::size_t>(pixel)] = cell;
  }
  return table;
}

/// map_saver's trinary image: 0 occupied, 254 free, 205 unknown (or in between).
GrayImage map_to_image(const OccupancyMap& map, const MapMetadata& meta) {
  GrayImage image{map.width, map.height, std::vector<std::uint8_t>(map.cells.size())};
  for (int iy = 0; iy < map.height; ++iy) {
    const std::size_t row = static_cast<std::size_t>(map.height - 1 - iy) * map.width;
    for (int ix = 0; ix < map.width; ++ix) {
      const int v = map.at(ix, iy);
      std::uint8_t pixel = 205;
      if (v >= 0 && v / 100.0 > meta.occupied_thresh) pixel = 0;
      else if (v >= 0 && v / 100.0 < meta.free_thresh) pixel = 254;
      image.pixels[row + ix] = pixel;
    }
  }
  return image;
}

std::string yaml_string(const std::string& text) {
  const bool plain = !text.empty() && text.front() != '-' &&
                     text.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_./-") ==
                         std::string::npos;
  if (plain) return text;
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') quoted += '\\';
    quoted += c;
  }
  return quoted + "\"";
}

bool ends_with_png(const std::string& name) {
  if (name.size() < 4) return false;
  std::string tail = name.substr(name.size() - 4);
  for (char& c : tail) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return tail == ".png";
}

}  // namespace

MapMetadata read_map_metadata(const std::string& yaml_path) {
  std::filesystem::path image_path;
  return parse_metadata(yaml_path, image_path);
}

OccupancyMap read_map(const std::string& yaml_path) {
  std::filesystem::path image_path;
  const MapMetadata meta = parse_metadata(yaml_path, image_path);
  const GrayImage image = read_gray_image(image_path.string());
  const std::array<std::int8_t, 256> table = pixel_to_cell_table(meta);
  OccupancyMap map;
  map.resolution = meta.resolution;
  map.origin = SE2(meta.origin.x(), meta.origin.y(), meta.origin.z());
  map.width = image.width;
  map.height = image.height;
  map.cells.resize(image.pixels.size());
  for (int row = 0; row < image.height; ++row) {  // image row 0 is the top: map row height - 1
    const std::size_t from = static_cast<std::size_t>(row) * image.width;
    for (int col = 0; col < image.width; ++col) map.at(col, image.height - 1 - row) = table[image.pixels[from + col]];
  }
  return map;
}

void write_map(const std::string& yaml_path, const OccupancyMap& map, const std::string& image_name) {
  check(map.width > 0 && map.height > 0 &&
            map.cells.size() == static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height),
        yaml_path + ": cannot write an empty map or one whose size does not match its cells");
  check(std::isfinite(map.resolution) && map.resolution > 0.0 && map.origin.vector().allFinite(),
        yaml_path + ": cannot write a map with a non-positive resolution or a non-finite origin");
  MapMetadata meta;
  meta.image = image_name.empty() ? std::filesystem::path(yaml_path).stem().string() + ".pgm" : image_name;
  const std::string image_path = resolve_image(yaml_path, meta.image).string();
  const GrayImage image = map_to_image(map, meta);
  if (ends_with_png(meta.image)) write_png(image_path, image);
  else write_pgm(image_path, image);

  std::string yaml = "image: " + yaml_string(meta.image) + "\n";
  yaml += "resolution: " + format_number(map.resolution) + "\n";
  yaml += "origin: [" + format_number(map.origin.x()) + ", " + format_number(map.origin.y()) + ", " +
          format_number(map.origin.theta()) + "]\n";
  yaml += "negate: 0\n";
  yaml += "occupied_thresh: " + format_number(meta.occupied_thresh) + "\n";
  yaml += "free_thresh: " + format_number(meta.free_thresh) + "\n";
  yaml += "mode: trinary\n";
  write_file_atomically(yaml_path, yaml);
}

GrayImage read_gray_image(const std::string& path) {
  const std::vector<std::uint8_t> bytes = read_file_bytes(path);
  if (is_png(bytes)) return gray_from_raster(decode_png(bytes, path, false));
  if (bytes.size() >= 2 && bytes[0] == 'P' && (bytes[1] == '5' || bytes[1] == '2')) return decode_pgm(bytes, path);
  throw ParseError(path, 0, "not a PGM (P2/P5) or PNG image");
}

RgbImage read_png_rgb(const std::string& path) {
  const std::vector<std::uint8_t> bytes = read_file_bytes(path);
  if (!is_png(bytes)) throw ParseError(path, 0, "not a PNG image");
  const PngRaster raster = decode_png(bytes, path, true);
  RgbImage image(raster.width, raster.height);
  const std::size_t count = static_cast<std::size_t>(raster.width) * raster.height;
  for (std::size_t i = 0; i < count; ++i) {
    for (std::size_t k = 0; k < 3; ++k) image.rgb[3 * i + k] = raster.samples[i * raster.channels + k];
  }
  return image;
}

void write_pgm(const std::string& path, const GrayImage& image) {
  check(image.width > 0 && image.height > 0 &&
            image.pixels.size() == static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height),
        path + ": cannot write an empty image or one whose size does not match its pixels");
  std::string content = "P5\n" + std::to_string(image.width) + " " + std::to_string(image.height) + "\n255\n";
  content.append(image.pixels.begin(), image.pixels.end());
  write_file_atomically(path, content);
}

void write_png(const std::string& path, const GrayImage& image) {
  encode_png(path, image.width, image.height, false, image.pixels);
}

void write_png(const std::string& path, const RgbImage& image) { encode_png(path, image.width, image.height, true, image.rgb); }

std::vector<std::uint8_t> encode_png(const RgbImage& image) {
  return encode_png_bytes("image", image.width, image.height, true, image.rgb);
}

}  // namespace slam2d
