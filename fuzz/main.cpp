// SPDX-License-Identifier: BSD-3-Clause
// libFuzzer's entry point for one target: the executable fuzz_NAME is built with
// -DSLAM2D_FUZZ_TARGET=NAME (fuzz/CMakeLists.txt).

#include <cstddef>
#include <cstdint>

#include "targets.hpp"

#define SLAM2D_STRINGIFY2(x) #x
#define SLAM2D_STRINGIFY(x) SLAM2D_STRINGIFY2(x)

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const slam2d::fuzz::Target run = slam2d::fuzz::target(SLAM2D_STRINGIFY(SLAM2D_FUZZ_TARGET));
  run(data, size);
  return 0;
}
