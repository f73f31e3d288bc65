// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A relation of Kuemmerle et al. 2009, "On measuring the accuracy of SLAM algorithms": the
// robot's pose at t2 in the frame of its pose at t1, what eval/relation_error.hpp scores a
// trajectory against (io/relations.hpp reads and writes them).

#include <cstddef>

#include "slam2d/core/se2.hpp"

namespace slam2d {

struct Relation {
  double stamp_from = 0.0;  // s, t1
  double stamp_to = 0.0;    // s, t2
  SE2 T_from_to;            // pose at t2 in the frame of the pose at t1
  std::size_t line = 0;     // 1-based line in the file (0 when not read from a file)
};

}  // namespace slam2d
