// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// The fuzz targets (issue 25): one function per parser, each taking arbitrary bytes. A target
// returns normally when the parser accepts the input or refuses it with slam2d::Error (the clear
// "PATH:LINE: message" every parser owes bad input); anything else escapes: a crash, a sanitizer
// report, another exception, an allocation past the fuzzer's limit. The same functions run under
// libFuzzer (fuzz/main.cpp, -DSLAM2D_FUZZ=ON) and over the saved inputs of tests/fixtures/fuzz
// in the regression test (tests/fuzz/fuzz_regression_test.cpp), so a crash once found stays found.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace slam2d::fuzz {

using Target = void (*)(const std::uint8_t* data, std::size_t size);

struct NamedTarget {
  const char* name;
  Target run;
};

/// Every target by name: carmen, carmen_gz, relations, trajectory, pose_graph_g2o, pose_graph_toro,
/// map_yaml, pgm, png, config, ros1_bag, mcap, rosbag2_db3, cdr, ros1_message.
const std::vector<NamedTarget>& targets();

/// The target `name`; throws std::invalid_argument for an unknown one.
Target target(const std::string& name);

}  // namespace slam2d::fuzz
