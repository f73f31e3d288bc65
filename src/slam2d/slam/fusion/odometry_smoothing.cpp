// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/slam/fusion/odometry_smoothing.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/jackknife.hpp"

namespace slam2d {

namespace {

// Floor of a jitter's variance: a stream the hat finds noiseless still carries its rounding.
constexpr double kMinJitterVariance = 1e-10;
// The lags of the drift fit (scans).
constexpr std::array<std::size_t, 8> kLags{1, 2, 3, 4, 6, 8, 12, 16};

// b in a's frame as (x, y, theta), theta wrapped.
Eigen::Vector3d relative(const SE2& a, const SE2& b) {
  const SE2 r = a.between(b);
  return {r.x(), r.y(), normalize_angle(r.theta())};
}

// x - y with the heading's difference wrapped.
Eigen::Vector3d minus(const Eigen::Vector3d& x, const Eigen::Vector3d& y) {
  Eigen::Vector3d d = x - y;
  d.z() = normalize_angle(d.z());
  return d;
}

// The second difference of a pose stream at scan i (0 < i < n - 1), in pose i's frame: the change
// of velocity, plus 6 times the stream's white variance.
Eigen::Vector3d second_difference(const std::vector<SE2>& poses, std::size_t i) {
  Eigen::Vector3d d = relative(poses[i], poses[i + 1]) + relative(poses[i], poses[i - 1]);
  d.z() = normalize_angle(d.z());
  return d;
}

// The odometry's systematic scale against the method's, per axis (x, y share the distance's),
// from their increments over kCalibrationLag scans, where the white noises are small against the
// motion: sum(m o) / sum(m m). A wheel's scale error would otherwise make the robot's own change
// of velocity look like noise of one stream and, at low scan rates, hide the other's.
constexpr std::size_t kCalibrationLag = 16;

Eigen::Vector3d odometry_scale(const std::vector<SE2>& method, const std::vector<SE2>& odometry) {
  double mm_t = 0.0, mo_t = 0.0, mm_r = 0.0, mo_r = 0.0;
  for (std::size_t i = 0; i + kCalibrationLag < method.size(); ++i) {
    const Eigen::Vector3d m = relative(method[i], method[i + kCalibrationLag]);
    const Eigen::Vector3d o = relative(odometry[i], odometry[i + kCalibrationLag]);
    const double dm = m.head<2>().norm();
    mm_t += dm * dm, mo_t += dm * o.head<2>().norm(), mm_r += m.z() * m.z(), mo_r += m.z() * o.z();
  }
  const auto ratio = [](double mo, double mm) {
    const double r = mm > 0.0 ? mo / mm : 1.0;
    return std::isfinite(r) && r > 0.5 && r < 2.0 ? r : 1.0;  // beyond: no scale this could be
  };
  const double t = ratio(mo_t, mm_t);
  return {t, t, ratio(mo_r, mm_r)};
}

// Per axis, the white variances of the two streams from their second differences (header, 1),
// the odometry's divided by its scale first; the method's at `confidence` jackknife standard
// errors below the estimate.
void estimate_jitter(const std::vector<SE2>& method, const std::vector<SE2>& odometry, double trim_quantile,
                     double confidence, PoseStreamNoise& noise) {
  const std::size_t n = method.size();
  const Eigen::Vector3d scale = odometry_scale(method, odometry);
  std::vector<Eigen::Vector3d> l;
  std::vector<Eigen::Vector3d> o;
  l.reserve(n - 2);
  o.reserve(n - 2);
  for (std::size_t i = 1; i + 1 < n; ++i) {
    l.push_back(second_difference(method, i));
    o.push_back(second_difference(odometry, i).cwiseQuotient(scale));
  }
  // Sums per contiguous block, for the estimate and its jackknife standard error.
  constexpr std::size_t kBlocks = 20;
  struct Sums {
    Eigen::Vector3d ll = Eigen::Vector3d::Zero(), oo = Eigen::Vector3d::Zero(), lo = Eigen::Vector3d::Zero();
    Eigen::Vector3d count = Eigen::Vector3d::Zero();
    Sums& operator+=(const Sums& o) {
      ll += o.ll, oo += o.oo, lo += o.lo, count += o.count;
      return *this;
    }
  };
  std::array<Sums, kBlocks> blocks{};
  std::vector<double> gap(l.size());
  for (int axis = 0; axis < 3; ++axis) {
    for (std::size_t k = 0; k < l.size(); ++k) gap[k] = std::abs(l[k][axis] - o[k][axis]);
    std::vector<double> sorted = gap;
    const auto nth = sorted.begin() + static_cast<std::ptrdiff_t>(trim_quantile * static_cast<double>(sorted.size() - 1));
    std::nth_element(sorted.begin(), nth, sorted.end());
    const double limit = *nth;
    for (std::size_t k = 0; k < l.size(); ++k) {
      if (gap[k] > limit) continue;
      Sums& b = blocks[k * kBlocks / l.size()];
      b.ll[axis] += l[k][axis] * l[k][axis];
      b.oo[axis] += o[k][axis] * o[k][axis];
      b.lo[axis] += l[k][axis] * o[k][axis];
      b.count[axis] += 1.0;
    }
  }
  // (R, W) variances from sums: translation isotropic (the mean of x's and y's: apart, a stream's
  // lateral jitter came out near 0 where the robot's own change of velocity hid it, scans 0.5 s
  // apart, and the smoother trusted that stream's sideways motion: Intel at 2 Hz 0.0135 -> 0.0167 m
  // at 10 s; isotropic 0.0137).
  const auto variances = [](const Sums& s) {
    Eigen::Vector3d r, w;
    for (int axis = 0; axis < 3; ++axis) {
      const double count = std::max(s.count[axis], 1.0);
      r[axis] = (s.ll[axis] - s.lo[axis]) / count / 6.0;
      w[axis] = (s.oo[axis] - s.lo[axis]) / count / 6.0;
    }
    r.x() = r.y() = 0.5 * (r.x() + r.y());
    w.x() = w.y() = 0.5 * (w.x() + w.y());
    return std::pair{r, w};
  };
  Sums all;
  for (const Sums& b : blocks) all += b;
  const auto [r, w] = variances(all);
  // The jackknife over the blocks: where the robot's change of velocity between two scans dwarfs
  // the noises (low scan rates), the differences above are small differences of large sums.
  std::array<std::vector<double>, 3> leave_one_out;
  for (const Sums& b : blocks) {
    Sums rest = all;
    rest.ll -= b.ll, rest.oo -= b.oo, rest.lo -= b.lo, rest.count -= b.count;
    const Eigen::Vector3d r_rest = variances(rest).first;
    for (int axis = 0; axis < 3; ++axis) leave_one_out[axis].push_back(r_rest[axis]);
  }
  Eigen::Vector3d r_error;
  for (int axis = 0; axis < 3; ++axis) r_error[axis] = jackknife_standard_error(leave_one_out[axis]);
  // The method's jitter at its lower confidence bound: where the estimate is unsure, the method's
  // poses are left more as they are (do no harm).
  noise.method_jitter = (r - confidence * r_error).cwiseMax(0.0).cwiseSqrt();
  noise.odometry_jitter = w.cwiseMax(0.0).cwiseSqrt();
}

// Samples y against the summed model variance x of the drift fit y = s x + b x^2.
struct GrowthSamples {
  std::vector<double> x;
  std::vector<double> y;
};

// The scale s of y = s x + b x^2 with s, b >= 0 (least squares, the better of the constrained
// fits where the free one leaves the orthant), three times, trimming samples beyond 16 times the
// fit (a match gone wrong, an odometry jump).
double fit_growth_scale(const GrowthSamples& samples) {
  double s = 0.0, b = 0.0;
  bool fitted = false;
  for (int round = 0; round < 3; ++round) {
    double x2 = 0, x3 = 0, x4 = 0, yx = 0, yx2 = 0, y2 = 0;
    for (std::size_t k = 0; k < samples.x.size(); ++k) {
      const double x = samples.x[k];
      const double y = samples.y[k];
      if (fitted && y > 16.0 * (s * x + b * x * x) + 1e-6) continue;
      x2 += x * x, x3 += x * x * x, x4 += x * x * x * x, yx += y * x, yx2 += y * x * x, y2 += y * y;
    }
    if (!(x2 > 0.0)) break;
    const auto sse = [&](double ss, double bb) {
      return y2 - 2 * ss * yx - 2 * bb * yx2 + ss * ss * x2 + 2 * ss * bb * x3 + bb * bb * x4;
    };
    const double det = x2 * x4 - x3 * x3;
    double free_s = det > 0.0 ? (yx * x4 - yx2 * x3) / det : -1.0;
    double free_b = det > 0.0 ? (x2 * yx2 - x3 * yx) / det : -1.0;
    if (free_s >= 0.0 && free_b >= 0.0) {
      s = free_s, b = free_b;
    } else {
      const double only_s = std::max(yx / x2, 0.0);
      const double only_b = x4 > 0.0 ? std::max(yx2 / x4, 0.0) : 0.0;
      if (sse(only_s, 0.0) <= sse(0.0, only_b)) {
        s = only_s, b = 0.0;
      } else {
        s = 0.0, b = only_b;
      }
    }
    fitted = true;
  }
  return s;
}

Eigen::Matrix3d rotation3(double theta) {
  const double c = std::cos(theta);
  const double s = std::sin(theta);
  Eigen::Matrix3d g;
  g << c, -s, 0, s, c, 0, 0, 0, 1;
  return g;
}

Eigen::Vector3d squared(const Eigen::Vector3d& sigma) { return sigma.cwiseProduct(sigma); }

// The Rauch-Tung-Striebel smoother (header): Q[i] the odometry increment i-1 -> i's covariance in
// the robot frame, cut[i] the increments refused (the filter restarts at the method's pose), jitter
// R's diagonal in the robot frame. A method pose beyond the gate of its innovation keeps gate / m^2
// of its information (counted in downweighted).
std::vector<Eigen::Vector3d> rts_smoother(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                          const std::vector<Eigen::Vector3d>& Q, const std::vector<bool>& cut,
                                          const Eigen::Vector3d& jitter, double gate, std::size_t& downweighted) {
  const Eigen::Matrix3d R_robot = jitter.asDiagonal();
  const auto R_map = [&](const SE2& pose) {
    const Eigen::Matrix3d g = rotation3(pose.theta());
    return Eigen::Matrix3d(g * R_robot * g.transpose());
  };
  const std::size_t n = method.size();
  std::vector<Eigen::Vector3d> filtered(n), predicted(n);
  std::vector<Eigen::Matrix3d> P_filtered(n), P_predicted(n), transition(n);
  filtered[0] = method[0].vector();
  P_filtered[0] = R_map(method[0]);
  for (std::size_t i = 1; i < n; ++i) {
    if (cut[i]) {
      filtered[i] = method[i].vector();
      P_filtered[i] = R_map(method[i]);
      continue;
    }
    const SE2 u = odometry[i - 1].between(odometry[i]);
    // Predict along the odometry's increment.
    const Eigen::Vector3d& x = filtered[i - 1];
    const double c = std::cos(x.z());
    const double s = std::sin(x.z());
    predicted[i] = Eigen::Vector3d(x.x() + c * u.x() - s * u.y(), x.y() + s * u.x() + c * u.y(), x.z() + u.theta());
    Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
    J(0, 2) = -s * u.x() - c * u.y();
    J(1, 2) = c * u.x() - s * u.y();
    transition[i] = J;
    const Eigen::Matrix3d G = rotation3(x.z());
    P_predicted[i] = J * P_filtered[i - 1] * J.transpose() + G * Eigen::Matrix3d(Q[i].asDiagonal()) * G.transpose();
    // Update with the method's pose.
    const Eigen::Vector3d innovation = minus(method[i].vector(), predicted[i]);
    Eigen::Matrix3d R = R_map(method[i]);
    Eigen::Matrix3d S = P_predicted[i] + R;
    const double m2 = innovation.dot(S.ldlt().solve(innovation));
    if (m2 > gate) {
      R *= m2 / gate;
      S = P_predicted[i] + R;
      ++downweighted;
    }
    const Eigen::Matrix3d K = S.transpose().ldlt().solve(P_predicted[i].transpose()).transpose();
    filtered[i] = predicted[i] + K * innovation;
    const Eigen::Matrix3d P = (Eigen::Matrix3d::Identity() - K) * P_predicted[i];
    P_filtered[i] = 0.5 * (P + P.transpose());
  }
  // Backward: x_s(i) = x_f(i) + C (x_s(i+1) - x_p(i+1)), C = P_f(i) J(i+1)^T P_p(i+1)^-1.
  std::vector<Eigen::Vector3d> smoothed = filtered;
  for (std::size_t i = n - 1; i-- > 0;) {
    if (cut[i + 1]) continue;
    const Eigen::Matrix3d C =
        P_predicted[i + 1].transpose().ldlt().solve((P_filtered[i] * transition[i + 1].transpose()).transpose()).transpose();
    smoothed[i] = filtered[i] + C * minus(smoothed[i + 1], predicted[i + 1]);
  }
  return smoothed;
}

// The motion noise model's variances (x, y, theta) of each odometry increment i-1 -> i (entry 0
// zero), before the scales the data give them: the model's form without its online learning.
std::vector<Eigen::Vector3d> model_variances(const std::vector<SE2>& odometry, const OdometryNoiseConfig& config) {
  OdometryNoiseConfig form = config;
  form.window = 0.0;
  const OdometryNoiseModel model(form);
  std::vector<Eigen::Vector3d> variances(odometry.size(), Eigen::Vector3d::Zero());
  for (std::size_t i = 1; i < odometry.size(); ++i) {
    const Covariance3 q = model.covariance(odometry[i - 1].between(odometry[i]));
    variances[i] = Eigen::Vector3d(q(0, 0), q(1, 1), q(2, 2));
  }
  return variances;
}

// estimate_pose_stream_noise (header), given the model's variances of each increment.
PoseStreamNoise estimate_noise(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                               const std::vector<Eigen::Vector3d>& model, const OdometrySmoothingConfig& config) {
  PoseStreamNoise noise;
  estimate_jitter(method, odometry, config.trim_quantile, config.jitter_confidence, noise);
  const Eigen::Vector3d white = squared(noise.method_jitter) + squared(noise.odometry_jitter);

  // The odometry's drift (header, 2): cumulative model variances along the increments.
  const std::size_t n = method.size();
  std::vector<double> translation_sum(n, 0.0);
  std::vector<double> rotation_sum(n, 0.0);
  for (std::size_t i = 1; i < n; ++i) {
    translation_sum[i] = translation_sum[i - 1] + model[i].x();
    rotation_sum[i] = rotation_sum[i - 1] + model[i].z();
  }
  GrowthSamples translation, rotation;
  for (const std::size_t k : kLags) {
    for (std::size_t i = 0; i + k < n; ++i) {
      const Eigen::Vector3d d = minus(relative(method[i], method[i + k]), relative(odometry[i], odometry[i + k]));
      translation.x.push_back(translation_sum[i + k] - translation_sum[i]);
      translation.y.push_back(0.5 * (d.x() * d.x() + d.y() * d.y()) - (white.x() + white.y()));
      rotation.x.push_back(rotation_sum[i + k] - rotation_sum[i]);
      rotation.y.push_back(d.z() * d.z() - 2.0 * white.z());
    }
  }
  noise.translation_scale = std::clamp(fit_growth_scale(translation), config.min_scale, config.max_scale);
  noise.rotation_scale = std::clamp(fit_growth_scale(rotation), config.min_scale, config.max_scale);
  return noise;
}

}  // namespace

void validate(const OdometrySmoothingConfig& config) {
  check_fields(config, "OdometrySmoothingConfig");
  check(config.min_scale <= config.max_scale, "OdometrySmoothingConfig: min_scale must be <= max_scale");
  validate(config.odometry_noise);
}

PoseStreamNoise estimate_pose_stream_noise(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                           const OdometrySmoothingConfig& config) {
  check(method.size() == odometry.size() && method.size() >= 5,
        "estimate_pose_stream_noise: two streams of the same length, at least 5 poses");
  return estimate_noise(method, odometry, model_variances(odometry, config.odometry_noise), config);
}

std::vector<SE2> smooth_with_odometry(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                      const OdometrySmoothingConfig& config, OdometrySmoothingStats* stats) {
  validate(config);
  OdometrySmoothingStats local;
  OdometrySmoothingStats& out = stats != nullptr ? *stats : local;
  out = {};
  out.poses = method.size();
  if (!config.enabled) {
    out.skipped = "disabled";
    return method;
  }
  if (method.size() != odometry.size()) {
    out.skipped = "the method gave a pose to a different number of scans than the odometry";
    return method;
  }
  if (method.size() < config.min_poses) {
    out.skipped = "fewer poses than min_poses";
    return method;
  }
  const std::vector<Eigen::Vector3d> model = model_variances(odometry, config.odometry_noise);
  const PoseStreamNoise noise = estimate_noise(method, odometry, model, config);
  out.noise = noise;
  const Eigen::Vector3d jitter = squared(noise.method_jitter).cwiseMax(kMinJitterVariance);
  const Eigen::Vector3d odometry_white = squared(noise.odometry_jitter);
  const std::size_t n = method.size();
  // The odometry's covariance per step, and the steps cut from the chain: the odometry's increment
  // against the method's own, beyond the gate.
  std::vector<Eigen::Vector3d> Q(n, Eigen::Vector3d::Zero());
  std::vector<bool> cut(n, false);
  for (std::size_t i = 1; i < n; ++i) {
    const SE2 u = odometry[i - 1].between(odometry[i]);
    Q[i] = Eigen::Vector3d(noise.translation_scale * model[i].x() + 2.0 * odometry_white.x(),
                           noise.translation_scale * model[i].y() + 2.0 * odometry_white.y(),
                           noise.rotation_scale * model[i].z() + 2.0 * odometry_white.z());
    const Eigen::Vector3d step = minus(relative(method[i - 1], method[i]), u.vector());
    const double step_m2 = step.cwiseProduct(step).cwiseQuotient(Q[i] + 2.0 * jitter).sum();
    if (!std::isfinite(step_m2) || step_m2 > config.gate_chi2) {
      cut[i] = true;
      ++out.steps_refused;
    }
  }
  const std::vector<Eigen::Vector3d> smoothed =
      rts_smoother(method, odometry, Q, cut, jitter, config.gate_chi2, out.poses_downweighted);
  std::vector<SE2> poses;
  poses.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const SE2 pose(smoothed[i].x(), smoothed[i].y(), normalize_angle(smoothed[i].z()));
    if (!pose.vector().allFinite()) {  // never pass a NaN on (a method pose that was not finite)
      out.skipped = "a pose was not finite";
      return method;
    }
    out.max_change_m = std::max(out.max_change_m, (pose.translation() - method[i].translation()).norm());
    poses.push_back(pose);
  }
  out.applied = true;
  return poses;
}

}  // namespace slam2d
