// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/slam/fusion/discontinuity_smoothing.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <deque>

#include "slam2d/core/angles.hpp"

namespace slam2d {

void validate(const DiscontinuitySmoothingConfig& config) { check_fields(config, "DiscontinuitySmoothingConfig"); }

namespace {

Eigen::Vector3d vector_of(const SE2& step) { return {step.x(), step.y(), step.theta()}; }
SE2 step_of(const Eigen::Vector3d& v) { return SE2(v.x(), v.y(), normalize_angle(v.z())); }

/// The mean of the last `window` steps kept.
class RecentSteps {
 public:
  explicit RecentSteps(std::size_t window) : window_(window) {}
  bool empty() const { return steps_.empty(); }
  void add(const Eigen::Vector3d& step) {
    steps_.push_back(step);
    sum_ += step;
    if (steps_.size() > window_) {
      sum_ -= steps_.front();
      steps_.pop_front();
    }
  }
  Eigen::Vector3d mean() const { return sum_ / static_cast<double>(steps_.size()); }

 private:
  std::size_t window_;
  std::deque<Eigen::Vector3d> steps_;
  Eigen::Vector3d sum_ = Eigen::Vector3d::Zero();
};

bool is_jump(const Eigen::Vector3d& step, const Eigen::Vector3d& mean, const DiscontinuitySmoothingConfig& config) {
  const double jump_bound = std::max(config.min_jump, config.factor * mean.head<2>().norm());
  const double turn_bound = std::max(config.min_turn, config.factor * std::abs(mean.z()));
  return step.head<2>().norm() > jump_bound || std::abs(step.z()) > turn_bound;
}

}  // namespace

SmoothingResult smooth_discontinuities(const Trajectory& dense, const DiscontinuitySmoothingConfig& config) {
  validate(config);
  SmoothingResult result;
  if (dense.empty()) return result;
  result.trajectory.reserve(dense.size());
  result.trajectory.push_back(dense[0].stamp, dense[0].pose);
  RecentSteps recent(config.window);
  for (std::size_t i = 1; i < dense.size(); ++i) {
    SE2 step = dense[i - 1].pose.inverse() * dense[i].pose;
    if (std::abs(dense[i].stamp - dense[i - 1].stamp) <= config.max_dt) {
      const Eigen::Vector3d v = vector_of(step);
      if (!recent.empty() && is_jump(v, recent.mean(), config)) {
        step = step_of(recent.mean());
        result.jumps.push_back(i);
      } else {
        recent.add(v);
      }
    }
    result.trajectory.push_back(dense[i].stamp, result.trajectory.back().pose * step);
  }
  return result;
}

}  // namespace slam2d
