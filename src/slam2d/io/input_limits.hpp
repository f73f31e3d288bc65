// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The bounds on what a file may make slam2d allocate (issue 25): a hostile or broken input
// (a gzip or zstd bomb, a size field of 2^63, a line that never ends, a scan of a billion beams)
// is refused with a clear error naming the file and the limit, never an allocation that takes
// the machine down. One table for every reader; the defaults sit far above any real log (a
// 1080-beam scanner at 40 Hz, bags of hours) and below what a 2 GiB process can hold.
//
// Overridable without rebuilding: SLAM2D_LIMITS="max_beams=200000,max_line_bytes=268435456"
// (read once, at the first use; an unknown key or a bad value is an error naming the variable).

#include <cstddef>
#include <cstdint>
#include <string>

#include "slam2d/core/config_fields.hpp"

namespace slam2d {

struct InputLimits {
  std::uint64_t max_line_bytes = std::uint64_t{64} << 20;
  std::uint64_t max_beams = 100000;
  std::uint64_t max_decompressed_bytes = std::uint64_t{1} << 30;
  std::uint64_t max_compression_ratio = 1000;
  std::uint64_t max_map_cells = std::uint64_t{1} << 28;
  std::uint64_t max_graph_elements = 50000000;
};

template <typename Fields>
void describe(Fields& f, InputLimits& c) {
  f.number("max_line_bytes", c.max_line_bytes, "bytes", at_least(1), "a line of a text file (CARMEN, relations, trajectories, g2o)");
  f.number("max_beams", c.max_beams, "1", at_least(1), "beams of one scan (CARMEN, LaserScan)");
  f.number("max_decompressed_bytes", c.max_decompressed_bytes, "bytes", at_least(1), "one compressed chunk of a bag, inflated");
  f.number("max_compression_ratio", c.max_compression_ratio, "1", at_least(1), "a chunk's inflated size over its compressed size");
  f.number("max_map_cells", c.max_map_cells, "cells", at_least(1), "a map image's width times height");
  f.number("max_graph_elements", c.max_graph_elements, "1", at_least(1), "vertices plus edges of a pose graph file");
}

/// The limits in force: the defaults, overridden by $SLAM2D_LIMITS. Throws Error when the
/// variable does not parse.
const InputLimits& input_limits();

/// The limits from a SLAM2D_LIMITS-style text ("key=value,..."; empty: the defaults). Throws
/// Error naming `source` on an unknown key or a value out of range.
InputLimits parse_input_limits(const std::string& text, const std::string& source = "SLAM2D_LIMITS");

/// "raise it with SLAM2D_LIMITS=KEY=..." for messages.
std::string limit_hint(const char* key);

/// Throws Error when a scan's beam count is over max_beams (the bag decoders; the CARMEN reader
/// names the line itself).
void check_beam_count(std::size_t beams);

}  // namespace slam2d
