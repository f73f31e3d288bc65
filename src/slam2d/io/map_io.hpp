// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Occupancy maps in the ROS map_server format: a YAML file naming a PGM or PNG image.
//
// YAML keys: image (relative to the YAML file), resolution (m/cell), origin [x, y, yaw] (pose of
// the lower-left pixel), negate (0/1), occupied_thresh, free_thresh, optional mode
// (trinary | scale | raw, default trinary). As map_server: p = (255 - v) / 255 (v / 255 when
// negate); p > occupied_thresh is occupied (100), p < free_thresh free (0), else unknown (-1);
// "scale" maps the middle band linearly to 1..99, "raw" stores the pixel value itself (0..100,
// others unknown).
//
// write_map follows map_saver (trinary, default thresholds): a cell with occupancy v/100 above
// occupied_thresh is written 0, below free_thresh 254, anything else (and unknown) 205. So
// write -> read gives back a trinary map (cells -1, 0, 100) exactly.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "slam2d/core/occupancy_map.hpp"

namespace slam2d {

struct MapMetadata {
  std::string image;             // as written in the YAML (relative to the YAML's folder)
  double resolution = 0.05;      // m per pixel
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // x, y (m), yaw (rad)
  bool negate = false;
  double occupied_thresh = 0.65;
  double free_thresh = 0.196;
  std::string mode = "trinary";  // trinary | scale | raw
};

/// An 8-bit grey image, row-major, row 0 at the top.
struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;
  bool operator==(const GrayImage& other) const = default;
};

/// Reads the YAML and its image. Throws ParseError naming the YAML (and the line of the bad key)
/// for missing or invalid metadata, and naming the image file for a missing or corrupt image.
OccupancyMap read_map(const std::string& yaml_path);
MapMetadata read_map_metadata(const std::string& yaml_path);
/// Writes YAML + image (PGM, or PNG when `image_name` ends in .png) atomically. `image_name`
/// defaults to the YAML's stem + ".pgm", in the YAML's folder.
void write_map(const std::string& yaml_path, const OccupancyMap& map, const std::string& image_name = "");

/// Binary (P5) or ASCII (P2) PGM, or PNG (grey, grey+alpha, RGB, RGBA; colour is averaged).
GrayImage read_gray_image(const std::string& path);
void write_pgm(const std::string& path, const GrayImage& image);
void write_png(const std::string& path, const GrayImage& image);
void write_png(const std::string& path, const RgbImage& image);
RgbImage read_png_rgb(const std::string& path);
/// The bytes of a PNG file holding the image (for embedding, e.g. as a data URI).
std::vector<std::uint8_t> encode_png(const RgbImage& image);

}  // namespace slam2d
