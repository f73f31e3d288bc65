// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/localization/markov_grid.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/localization/sensor_model.hpp"

namespace slam2d {

void validate(const MarkovGridConfig& config) { check_fields(config, "MarkovGridConfig"); }

MarkovGridLocalization::MarkovGridLocalization(const LocalizationMap& map, const MarkovGridConfig& config)
    : map_(map),
      config_(config),
      sensor_map_((validate(config), map.map()), with_sigma_hit(map.field().config(), config.sigma_hit)),
      status_(config.status),
      motion_noise_(config.motion, config.motion_noise) {
  const OccupancyMap& m = map_.map();
  T_map_grid_ = m.origin;
  width_ = std::max(1, static_cast<int>(std::ceil(m.width * m.resolution / config_.resolution)));
  height_ = std::max(1, static_cast<int>(std::ceil(m.height * m.resolution / config_.resolution)));
  check(static_cast<double>(width_) * height_ * config_.angles <= 2e8, "markov: the grid would exceed 2e8 cells; use a coarser resolution");
  angle_step_ = 2.0 * std::numbers::pi / config_.angles;
  free_.assign(static_cast<std::size_t>(width_) * height_, 0);
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) {
      const Eigen::Vector2d centre = T_map_grid_.act(Eigen::Vector2d((x + 0.5) * config_.resolution, (y + 0.5) * config_.resolution));
      free_[static_cast<std::size_t>(y) * width_ + x] = map_.is_free(centre) ? 1 : 0;
    }
  }
  check(std::find(free_.begin(), free_.end(), 1) != free_.end(), "markov: no grid cell centre lies in a free map cell");
  belief_.assign(static_cast<std::size_t>(config_.angles) * height_ * width_, 0.0f);
}

SE2 MarkovGridLocalization::cell_pose(int k, int y, int x) const {
  return T_map_grid_ * SE2((x + 0.5) * config_.resolution, (y + 0.5) * config_.resolution, -std::numbers::pi + k * angle_step_);
}

void MarkovGridLocalization::initialize_global() {
  for (int k = 0; k < config_.angles; ++k) {
    for (int y = 0; y < height_; ++y) {
      for (int x = 0; x < width_; ++x) belief_[index(k, y, x)] = free_[static_cast<std::size_t>(y) * width_ + x];
    }
  }
  box_ = {0, width_ - 1, 0, height_ - 1};
  normalize();
  initialized_ = true;
  started_ = false;
  status_.reset();
  motion_noise_.restart();
}

void MarkovGridLocalization::initialize(const SE2& T_map_robot, const Covariance3& covariance) {
  const Eigen::Matrix3d information = information_from_covariance(make_positive_definite(covariance, 1e-6));
  double total = 0.0;
  for (int k = 0; k < config_.angles; ++k) {
    for (int y = 0; y < height_; ++y) {
      for (int x = 0; x < width_; ++x) {
        float& p = belief_[index(k, y, x)];
        p = 0.0f;
        if (!free_[static_cast<std::size_t>(y) * width_ + x]) continue;
        const SE2 pose = cell_pose(k, y, x);
        const Eigen::Vector3d d(pose.x() - T_map_robot.x(), pose.y() - T_map_robot.y(),
                                angle_difference(pose.theta(), T_map_robot.theta()));
        const double e = d.dot(information * d);
        if (e < 50.0) p = static_cast<float>(std::exp(-0.5 * e));
        total += p;
      }
    }
  }
  check(total > 0.0, "markov: the initial pose is not in a free part of the map");
  box_ = {0, width_ - 1, 0, height_ - 1};
  normalize();
  initialized_ = true;
  started_ = false;
  status_.reset();
  motion_noise_.restart();
}

void MarkovGridLocalization::motion_update(const OdometryControl& u) {
  std::fill(scratch_.begin(), scratch_.end(), 0.0f);
  scratch_.resize(belief_.size(), 0.0f);
  const CellRange source = box_;
  const double turn = (u.rot1 + u.rot2) / angle_step_;
  const int k_shift = static_cast<int>(std::floor(turn));
  const double ft = turn - k_shift;
  const int n = config_.angles;
  for (int k = 0; k < n; ++k) {
    // The layer's own displacement, in cells (Eq. 5.37 in the grid frame).
    const double heading = -std::numbers::pi + k * angle_step_ + u.rot1;
    const double dx = u.trans * std::cos(heading) / config_.resolution;
    const double dy = u.trans * std::sin(heading) / config_.resolution;
    const int ix = static_cast<int>(std::floor(dx));
    const int iy = static_cast<int>(std::floor(dy));
    const double fx = dx - ix;
    const double fy = dy - iy;
    const int k0 = ((k + k_shift) % n + n) % n;
    const int k1 = (k0 + 1) % n;
    const double w[2][2][2] = {{{(1 - fx) * (1 - fy) * (1 - ft), fx * (1 - fy) * (1 - ft)}, {(1 - fx) * fy * (1 - ft), fx * fy * (1 - ft)}},
                               {{(1 - fx) * (1 - fy) * ft, fx * (1 - fy) * ft}, {(1 - fx) * fy * ft, fx * fy * ft}}};
    for (int y = source.y0; y <= source.y1; ++y) {
      for (int x = source.x0; x <= source.x1; ++x) {
        const float p = belief_[index(k, y, x)];
        if (p == 0.0f) continue;
        for (int a = 0; a < 2; ++a) {
          for (int b = 0; b < 2; ++b) {
            const int ty = y + iy + b;
            if (ty < 0 || ty >= height_) continue;
            for (int c = 0; c < 2; ++c) {
              const int tx = x + ix + c;
              if (tx < 0 || tx >= width_) continue;
              scratch_[index(a == 0 ? k0 : k1, ty, tx)] += static_cast<float>(p * w[a][b][c]);
            }
          }
        }
      }
    }
  }
  belief_.swap(scratch_);
  // Binomial passes (variance 1/2 cell^2 each) that cover the motion model's noise for u.
  const Eigen::Matrix3d noise = control_covariance(u, motion_noise_.model());  // rot1, trans, rot2
  const double variance_xy = std::max(noise(1, 1), u.trans * u.trans * noise(0, 0));
  const double variance_theta = noise(0, 0) + noise(2, 2);
  const auto passes = [](double variance, double step) {
    return std::max(1, static_cast<int>(std::ceil(2.0 * variance / (step * step))));
  };
  const int xy_passes = passes(variance_xy, config_.resolution);
  const int theta_passes = std::min(passes(variance_theta, angle_step_), config_.angles);
  // The mass moved at most trans + 1 cells, and each pass spreads it by one more.
  const int reach = static_cast<int>(std::ceil(u.trans / config_.resolution)) + 1 + xy_passes;
  box_ = {std::max(0, source.x0 - reach), std::min(width_ - 1, source.x1 + reach), std::max(0, source.y0 - reach),
          std::min(height_ - 1, source.y1 + reach)};
  blur(xy_passes, theta_passes);
  // A robot cannot stand in a wall or in unknown space.
  for (int k = 0; k < n; ++k) {
    for (int y = box_.y0; y <= box_.y1; ++y) {
      for (int x = box_.x0; x <= box_.x1; ++x) {
        if (!free_[static_cast<std::size_t>(y) * width_ + x]) belief_[index(k, y, x)] = 0.0f;
      }
    }
  }
  normalize();
}

void MarkovGridLocalization::blur(int xy_passes, int theta_passes) {
  const int n = config_.angles;
  const CellRange b = box_;
  // Every pass writes inside the box only; the scratch belief outside stays zero, as the belief is.
  std::fill(scratch_.begin(), scratch_.end(), 0.0f);
  for (int pass = 0; pass < xy_passes; ++pass) {
    // Along x.
    for (int k = 0; k < n; ++k) {
      for (int y = b.y0; y <= b.y1; ++y) {
        const float* row = &belief_[index(k, y, 0)];
        float* out = &scratch_[index(k, y, 0)];
        for (int x = b.x0; x <= b.x1; ++x) {
          const float left = x > 0 ? row[x - 1] : 0.0f;
          const float right = x + 1 < width_ ? row[x + 1] : 0.0f;
          out[x] = 0.25f * left + 0.5f * row[x] + 0.25f * right;
        }
      }
    }
    // Along y.
    for (int k = 0; k < n; ++k) {
      for (int y = b.y0; y <= b.y1; ++y) {
        float* out = &belief_[index(k, y, 0)];
        const float* mid = &scratch_[index(k, y, 0)];
        const float* down = y > 0 ? &scratch_[index(k, y - 1, 0)] : nullptr;
        const float* up = y + 1 < height_ ? &scratch_[index(k, y + 1, 0)] : nullptr;
        for (int x = b.x0; x <= b.x1; ++x) {
          out[x] = 0.5f * mid[x] + 0.25f * (down ? down[x] : 0.0f) + 0.25f * (up ? up[x] : 0.0f);
        }
      }
    }
  }
  // Along theta (circular).
  for (int pass = 0; pass < theta_passes; ++pass) {
    for (int k = 0; k < n; ++k) {
      const int previous = (k + n - 1) % n;
      const int next = (k + 1) % n;
      for (int y = b.y0; y <= b.y1; ++y) {
        for (int x = b.x0; x <= b.x1; ++x) {
          scratch_[index(k, y, x)] =
              0.5f * belief_[index(k, y, x)] + 0.25f * (belief_[index(previous, y, x)] + belief_[index(next, y, x)]);
        }
      }
    }
    belief_.swap(scratch_);
  }
}

void MarkovGridLocalization::sensor_update(const std::vector<Eigen::Vector2d>& points_robot) {
  const float peak = belief_[argmax()];
  const double threshold = (status_.localized() ? config_.selective_threshold : config_.prune_threshold) * peak;
  log_likelihoods_.resize(belief_.size(), 0.0f);
  double best = -std::numeric_limits<double>::infinity();
  evaluated_last_ = 0;
  const CellRange b = box_;
  for (int k = 0; k < config_.angles; ++k) {
    for (int y = b.y0; y <= b.y1; ++y) {
      for (int x = b.x0; x <= b.x1; ++x) {
        const std::size_t i = index(k, y, x);
        if (!(belief_[i] > threshold)) {
          belief_[i] = 0.0f;
          continue;
        }
        const double log_likelihood = sensor_map_.scan_log_likelihood(points_robot, cell_pose(k, y, x));
        log_likelihoods_[i] = static_cast<float>(log_likelihood);
        best = std::max(best, log_likelihood);
        ++evaluated_last_;
      }
    }
  }
  // Bayes' rule, scaled by the best likelihood so the floats stay in range; the box shrinks to
  // the cells that still carry mass.
  CellRange next{width_, -1, height_, -1};
  for (int k = 0; k < config_.angles; ++k) {
    for (int y = b.y0; y <= b.y1; ++y) {
      for (int x = b.x0; x <= b.x1; ++x) {
        const std::size_t i = index(k, y, x);
        if (belief_[i] == 0.0f) continue;
        belief_[i] = static_cast<float>(belief_[i] * std::exp(log_likelihoods_[i] - best));
        next = {std::min(next.x0, x), std::max(next.x1, x), std::min(next.y0, y), std::max(next.y1, y)};
      }
    }
  }
  if (next.x1 >= 0) box_ = next;
  normalize();
  ++sensor_updates_;
}

std::size_t MarkovGridLocalization::argmax() const {
  std::size_t best = 0;
  float peak = -1.0f;
  for (int k = 0; k < config_.angles; ++k) {
    for (int y = box_.y0; y <= box_.y1; ++y) {
      for (int x = box_.x0; x <= box_.x1; ++x) {
        const std::size_t i = index(k, y, x);
        if (belief_[i] > peak) {
          peak = belief_[i];
          best = i;
        }
      }
    }
  }
  return best;
}

void MarkovGridLocalization::normalize() {
  double total = 0.0;
  for (int k = 0; k < config_.angles; ++k) {
    for (int y = box_.y0; y <= box_.y1; ++y) {
      for (int x = box_.x0; x <= box_.x1; ++x) total += belief_[index(k, y, x)];
    }
  }
  if (!(total > 0.0)) return;
  const float scale = static_cast<float>(1.0 / total);
  for (int k = 0; k < config_.angles; ++k) {
    for (int y = box_.y0; y <= box_.y1; ++y) {
      for (int x = box_.x0; x <= box_.x1; ++x) belief_[index(k, y, x)] *= scale;
    }
  }
}

LocalizationEstimate MarkovGridLocalization::summarize(const std::vector<Eigen::Vector2d>& points_robot) {
  const std::size_t best = argmax();
  const int bk = static_cast<int>(best / (static_cast<std::size_t>(width_) * height_));
  const int by = static_cast<int>((best / width_) % height_);
  const int bx = static_cast<int>(best % width_);
  const SE2 mode = cell_pose(bk, by, bx);
  // The mean of the mass near the mode.
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
  double c = 0.0;
  double s = 0.0;
  double local = 0.0;
  const int r = static_cast<int>(std::ceil(config_.estimate_radius / config_.resolution));
  const int rk = static_cast<int>(std::ceil(0.5 / angle_step_));
  for (int dk = -rk; dk <= rk; ++dk) {
    const int k = ((bk + dk) % config_.angles + config_.angles) % config_.angles;
    for (int y = std::max(0, by - r); y <= std::min(height_ - 1, by + r); ++y) {
      for (int x = std::max(0, bx - r); x <= std::min(width_ - 1, bx + r); ++x) {
        const double p = belief_[index(k, y, x)];
        if (p == 0.0) continue;
        const SE2 pose = cell_pose(k, y, x);
        t += p * pose.translation();
        c += p * std::cos(pose.theta());
        s += p * std::sin(pose.theta());
        local += p;
      }
    }
  }
  LocalizationEstimate estimate;
  estimate.pose = local > 0.0 ? SE2(t / local, std::atan2(s, c)) : mode;
  // The spread of the whole belief about the estimate.
  Covariance3 cov = Covariance3::Zero();
  for (int k = 0; k < config_.angles; ++k) {
    const double theta_offset = angle_difference(-std::numbers::pi + k * angle_step_ + T_map_grid_.theta(), estimate.pose.theta());
    for (int y = box_.y0; y <= box_.y1; ++y) {
      for (int x = box_.x0; x <= box_.x1; ++x) {
        const double p = belief_[index(k, y, x)];
        if (p == 0.0) continue;
        const Eigen::Vector2d centre = T_map_grid_.act(Eigen::Vector2d((x + 0.5) * config_.resolution, (y + 0.5) * config_.resolution));
        const Eigen::Vector3d d(centre.x() - estimate.pose.x(), centre.y() - estimate.pose.y(), theta_offset);
        cov += p * d * d.transpose();
      }
    }
  }
  const double q = config_.resolution * config_.resolution / 12.0;
  cov.diagonal() += Eigen::Vector3d(q, q, angle_step_ * angle_step_ / 12.0);
  estimate.covariance = cov;
  estimate.plausibility = map_.plausibility(points_robot, estimate.pose, config_.status.plausibility_distance);
  const bool was_localized = status_.localized();
  estimate.localized = status_.update(estimate.covariance, estimate.plausibility);
  if (was_localized && !estimate.localized) initialize_global();  // lost: start over from the uniform belief
  return estimate;
}

LocalizationEstimate MarkovGridLocalization::update(const SE2& T_odom_robot, const LaserScan& scan) {
  check(initialized_, "markov: initialize() or initialize_global() before update()");
  if (started_) {
    if (!moved_enough(odom_at_update_, T_odom_robot, config_.update_distance, config_.update_angle)) {
      return follow_odometry(estimate_, motion_noise_.corrected(odom_at_update_.between(T_odom_robot)));
    }
    motion_update(motion_noise_.move(odom_at_update_.between(T_odom_robot)));
  }
  started_ = true;
  odom_at_update_ = T_odom_robot;
  const ScanBeams beams = select_beams(scan, config_.max_beams, config_.usable_range);
  sensor_update(beams.points_robot);
  if (!(belief_[argmax()] > 0.0f)) initialize_global();
  estimate_ = summarize(beams.points_robot);
  // The learner's measurement, made only where a stretch ends and only while localized.
  if (motion_noise_.wants_measurement()) {
    motion_noise_.measured(estimate_.localized ? map_.match(beams.points_robot, estimate_.pose, config_.motion_noise_matcher) : std::nullopt);
  }
  return estimate_;
}

std::size_t MarkovGridLocalization::active_cells() const {
  return static_cast<std::size_t>(std::count_if(belief_.begin(), belief_.end(), [](float p) { return p > 0.0f; }));
}

std::size_t MarkovGridLocalization::memory_bytes() const {
  return sizeof(*this) + sensor_map_.memory_bytes() + free_.capacity() + (belief_.capacity() + scratch_.capacity()) * sizeof(float) +
         log_likelihoods_.capacity() * sizeof(float);
}

}  // namespace slam2d
