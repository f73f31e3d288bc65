// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Relations files of Kuemmerle et al. 2009, "On measuring the accuracy of SLAM algorithms":
// one relation per line, "t1 t2 x y z roll pitch yaw" (s, m, rad): the pose of the robot at t2
// in the frame of the robot at t1. z, roll and pitch are ignored in 2D.

#include <string>
#include <vector>

#include "slam2d/core/relation.hpp"

namespace slam2d {

/// Throws Error if unreadable, ParseError("PATH:LINE: ...") on a malformed line.
std::vector<Relation> read_relations(const std::string& path);
/// Atomic; numbers in shortest exact form.
void write_relations(const std::string& path, const std::vector<Relation>& relations);

}  // namespace slam2d
