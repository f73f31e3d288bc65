// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/slam/fusion/odometry_smoothing.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

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

// The drift fit y = s x + b x^2 (header, 2): samples y against the summed model variance x.
// The scale s with s, b >= 0 (least squares, the better of the constrained fits where the free one
// leaves the orthant), in three rounds, each trimming the samples beyond 16 times the last fit (a
// match gone wrong, an odometry jump). A round takes its samples one by one (add) and is then
// solved: the caller draws the samples anew for each round instead of holding them (eight lags of
// every scan: 70 MB on Intel played ten times).
class GrowthFit {
 public:
  static constexpr int kRounds = 3;

  void add(double x, double y) {
    if (done_ || (fitted_ && y > 16.0 * (s_ * x + b_ * x * x) + 1e-6)) return;
    x2_ += x * x, x3_ += x * x * x, x4_ += x * x * x * x, yx_ += y * x, yx2_ += y * x * x, y2_ += y * y;
  }

  // Ends the round: the fit of its samples (none: the last fit stays, and the rounds end).
  void solve() {
    if (done_) return;
    if (!(x2_ > 0.0)) {
      done_ = true;
      return;
    }
    const auto sse = [&](double ss, double bb) {
      return y2_ - 2 * ss * yx_ - 2 * bb * yx2_ + ss * ss * x2_ + 2 * ss * bb * x3_ + bb * bb * x4_;
    };
    const double det = x2_ * x4_ - x3_ * x3_;
    const double free_s = det > 0.0 ? (yx_ * x4_ - yx2_ * x3_) / det : -1.0;
    const double free_b = det > 0.0 ? (x2_ * yx2_ - x3_ * yx_) / det : -1.0;
    if (free_s >= 0.0 && free_b >= 0.0) {
      s_ = free_s, b_ = free_b;
    } else {
      const double only_s = std::max(yx_ / x2_, 0.0);
      const double only_b = x4_ > 0.0 ? std::max(yx2_ / x4_, 0.0) : 0.0;
      if (sse(only_s, 0.0) <= sse(0.0, only_b)) {
        s_ = only_s, b_ = 0.0;
      } else {
        s_ = 0.0, b_ = only_b;
      }
    }
    fitted_ = true;
    x2_ = x3_ = x4_ = yx_ = yx2_ = y2_ = 0.0;
  }

  double scale() const { return s_; }

 private:
  double s_ = 0.0, b_ = 0.0;
  bool fitted_ = false, done_ = false;
  double x2_ = 0.0, x3_ = 0.0, x4_ = 0.0, yx_ = 0.0, yx2_ = 0.0, y2_ = 0.0;
};

// The drift's scales (translation, rotation) from the samples `for_each_sample(visit)` draws,
// visit(translation x, translation y, rotation x, rotation y), once per round.
template <typename ForEachSample>
std::pair<double, double> fit_growth_scales(const ForEachSample& for_each_sample) {
  GrowthFit translation, rotation;
  for (int round = 0; round < GrowthFit::kRounds; ++round) {
    for_each_sample([&](double tx, double ty, double rx, double ry) {
      translation.add(tx, ty);
      rotation.add(rx, ry);
    });
    translation.solve();
    rotation.solve();
  }
  return {translation.scale(), rotation.scale()};
}

Eigen::Matrix3d rotation3(double theta) {
  const double c = std::cos(theta);
  const double s = std::sin(theta);
  Eigen::Matrix3d g;
  g << c, -s, 0, s, c, 0, 0, 0, 1;
  return g;
}

Eigen::Vector3d squared(const Eigen::Vector3d& sigma) { return sigma.cwiseProduct(sigma); }

// The method's slow error as the smoother carries it: per axis (x, y, theta) its variance
// sigma_b^2 and its factor phi = exp(-1 / tau) from one scan to the next (header, 3).
struct SlowError {
  Eigen::Vector3d variance = Eigen::Vector3d::Zero();
  Eigen::Vector3d factor = Eigen::Vector3d::Zero();
};

using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

// Floor of the slow error's variance in the smoother: where there is none, its states stay at 0
// and the covariance stays invertible.
constexpr double kMinSlowVariance = 1e-12;
// The prediction's variance of a pose after an increment refused (the chain is cut): unknown.
constexpr double kCutVariance = 1e6;

// The Rauch-Tung-Striebel smoother (header) on the state (x, b), the pose and the method's slow
// error in the map frame: Q[i] the odometry increment i-1 -> i's covariance in the robot frame,
// cut[i] the increments refused (the pose is then predicted as unknown, b carries on), jitter R's
// diagonal in the robot frame. The method's pose measures x + b. A method pose beyond the gate of
// its innovation keeps gate / m^2 of its information (counted in downweighted). The filtered state
// of every `segment`-th scan is kept (OdometrySmoothingConfig::checkpoint_interval).
std::vector<Eigen::Vector3d> rts_smoother(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                          const std::vector<Eigen::Vector3d>& Q, const std::vector<bool>& cut,
                                          const Eigen::Vector3d& jitter, const SlowError& slow, double gate,
                                          std::size_t segment, std::size_t& downweighted) {
  const Eigen::Matrix3d R_robot = jitter.asDiagonal();
  const auto R_map = [&](const SE2& pose) {
    const Eigen::Matrix3d g = rotation3(pose.theta());
    return Eigen::Matrix3d(g * R_robot * g.transpose());
  };
  const Eigen::Vector3d slow_variance = slow.variance.cwiseMax(kMinSlowVariance);
  const Eigen::Matrix3d F_b = slow.factor.asDiagonal();
  const Eigen::Matrix3d Q_b =
      (slow_variance.array() * (1.0 - slow.factor.array().square())).max(kMinSlowVariance).matrix().asDiagonal();
  Eigen::Matrix<double, 3, 6> H;
  H << Eigen::Matrix3d::Identity(), Eigen::Matrix3d::Identity();
  // The prediction of state i from state i-1 (its mean and covariance), with the transition's
  // Jacobian: computed again in the backward pass instead of kept (the smoother's memory: below).
  struct Prediction {
    Vector6 mean;
    Matrix6 covariance;
    Matrix6 transition;
  };
  const auto predict = [&](std::size_t i, const Vector6& previous, const Matrix6& P_previous) {
    const Eigen::Vector3d b = F_b * previous.tail<3>();
    Prediction p{.mean = Vector6::Zero(), .covariance = Matrix6::Zero(), .transition = Matrix6::Identity()};
    Matrix6& J = p.transition;
    J.bottomRightCorner<3, 3>() = F_b;
    Matrix6 process = Matrix6::Zero();
    process.bottomRightCorner<3, 3>() = Q_b;
    if (cut[i]) {  // the odometry's increment is refused: the pose is unknown, b carries on
      p.mean << method[i].vector() - b, b;
      J.topLeftCorner<3, 3>().setZero();
      process.topLeftCorner<3, 3>() = kCutVariance * Eigen::Matrix3d::Identity();
    } else {  // predict along the odometry's increment
      const SE2 u = odometry[i - 1].between(odometry[i]);
      const double c = std::cos(previous.z());
      const double s = std::sin(previous.z());
      p.mean << previous.x() + c * u.x() - s * u.y(), previous.y() + s * u.x() + c * u.y(), previous.z() + u.theta(), b;
      J(0, 2) = -s * u.x() - c * u.y();
      J(1, 2) = c * u.x() - s * u.y();
      const Eigen::Matrix3d G = rotation3(previous.z());
      process.topLeftCorner<3, 3>() = G * Eigen::Matrix3d(Q[i].asDiagonal()) * G.transpose();
    }
    p.covariance = J * P_previous * J.transpose() + process;
    return p;
  };
  // The filter's step to state i from the filtered state i - 1: predict, then update with the
  // method's pose, which measures x + b.
  const auto filter = [&](std::size_t i, const Vector6& previous, const Matrix6& P_previous, Vector6& state,
                          Matrix6& P_state) {
    const Prediction p = predict(i, previous, P_previous);
    const Eigen::Vector3d innovation = minus(method[i].vector(), H * p.mean);
    Eigen::Matrix3d R = R_map(method[i]);
    Eigen::Matrix3d S = H * p.covariance * H.transpose() + R;
    const double m2 = innovation.dot(S.ldlt().solve(innovation));
    const bool beyond_gate = m2 > gate;
    if (beyond_gate) {
      R *= m2 / gate;
      S = H * p.covariance * H.transpose() + R;
    }
    const Eigen::Matrix<double, 6, 3> K = (p.covariance * H.transpose()) * S.inverse();
    state = p.mean + K * innovation;
    const Matrix6 P = (Matrix6::Identity() - K * H) * p.covariance;
    P_state = 0.5 * (P + P.transpose());
    return beyond_gate;
  };
  // Forward, keeping the filtered state of every segment-th scan only (a checkpoint): the
  // backward pass filters each segment again from its checkpoint, to the bit the same states
  // (OdometrySmoothingConfig::checkpoint_interval).
  const std::size_t n = method.size();
  std::vector<Vector6> checkpoint_state((n + segment - 1) / segment);
  std::vector<Matrix6> checkpoint_P(checkpoint_state.size());
  // The first pose: x = m - b, b from its prior.
  Vector6 state;
  state << method[0].vector(), Eigen::Vector3d::Zero();
  const Eigen::Matrix3d B0 = slow_variance.asDiagonal();
  Matrix6 P_state;
  P_state << R_map(method[0]) + B0, -B0, -B0, B0;
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0 && filter(i, Vector6(state), Matrix6(P_state), state, P_state)) ++downweighted;
    if (i % segment == 0) checkpoint_state[i / segment] = state, checkpoint_P[i / segment] = P_state;
  }
  // Backward, segment by segment from the last: s(i) = f(i) + C (s(i+1) - p(i+1)),
  // C = P_f(i) J(i+1)^T P_p(i+1)^-1; the last state's smoothed value is its filtered one.
  std::vector<Eigen::Vector3d> poses(n);
  std::vector<Vector6> filtered(std::min(n, segment));
  std::vector<Matrix6> P_filtered(filtered.size());
  Vector6 next_smoothed = Vector6::Zero();  // s(i + 1)
  for (std::size_t k = checkpoint_state.size(); k-- > 0;) {
    const std::size_t first = k * segment;
    const std::size_t count = std::min(n - first, segment);
    filtered[0] = checkpoint_state[k], P_filtered[0] = checkpoint_P[k];
    for (std::size_t j = 1; j < count; ++j) filter(first + j, filtered[j - 1], P_filtered[j - 1], filtered[j], P_filtered[j]);
    for (std::size_t j = count; j-- > 0;) {
      const std::size_t i = first + j;
      Vector6 smoothed = filtered[j];
      if (i + 1 < n) {
        const Prediction p = predict(i + 1, filtered[j], P_filtered[j]);
        const Matrix6 C =
            p.covariance.transpose().ldlt().solve((P_filtered[j] * p.transition.transpose()).transpose()).transpose();
        Vector6 difference = next_smoothed - p.mean;
        difference(2) = normalize_angle(difference(2));
        smoothed += C * difference;
      }
      poses[i] = smoothed.head<3>();
      next_smoothed = smoothed;
    }
  }
  return poses;
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

// The lags of the method's slow error (scans; at most a quarter of the run).
constexpr std::array<std::size_t, 12> kSlowLags{1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64};

// One sample of the three-cornered hat on increments (header, 3): for the increments over k scans
// from scan i, a = m - o, b = s - o, c = m - s; a . b estimates the odometry's error variance, a . c
// the method's (translation: the mean of x's and y's).
struct HatSample {
  std::size_t first = 0;  // i
  double odometry_translation = 0.0, odometry_rotation = 0.0;
  double method_translation = 0.0, method_rotation = 0.0;
};

// The samples of lag k, the trim_quantile with the smallest disagreements |a| + |b| + |c|
// (translation, L1) kept: a match gone wrong, an odometry jump.
std::vector<HatSample> hat_samples(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                   const std::vector<SE2>& scan, std::size_t k, double trim_quantile) {
  std::vector<HatSample> samples;
  std::vector<double> size;
  for (std::size_t i = 0; i + k < method.size(); ++i) {
    const Eigen::Vector3d m = relative(method[i], method[i + k]);
    const Eigen::Vector3d o = relative(odometry[i], odometry[i + k]);
    const Eigen::Vector3d s = relative(scan[i], scan[i + k]);
    const Eigen::Vector3d a = minus(m, o), b = minus(s, o), c = minus(m, s);
    samples.push_back({i, 0.5 * (a.x() * b.x() + a.y() * b.y()), a.z() * b.z(), 0.5 * (a.x() * c.x() + a.y() * c.y()),
                       a.z() * c.z()});
    size.push_back(a.head<2>().lpNorm<1>() + b.head<2>().lpNorm<1>() + c.head<2>().lpNorm<1>());
  }
  if (samples.empty()) return samples;
  std::vector<double> sorted = size;
  const auto nth = sorted.begin() + static_cast<std::ptrdiff_t>(trim_quantile * static_cast<double>(sorted.size() - 1));
  std::nth_element(sorted.begin(), nth, sorted.end());
  std::vector<HatSample> kept;
  for (std::size_t j = 0; j < samples.size(); ++j) {
    if (size[j] <= *nth) kept.push_back(samples[j]);
  }
  return kept;
}

// The best non-negative x of min |A x - y|^2 over the few columns of A: every subset of columns
// solved freely, the feasible solution of least residual kept.
template <int N>
Eigen::Matrix<double, N, 1> non_negative_least_squares(const Eigen::Matrix<double, Eigen::Dynamic, N>& A,
                                                       const Eigen::VectorXd& y) {
  Eigen::Matrix<double, N, 1> best = Eigen::Matrix<double, N, 1>::Zero();
  double best_sse = y.squaredNorm();
  for (int subset = 1; subset < (1 << N); ++subset) {
    std::vector<int> columns;
    for (int c = 0; c < N; ++c) {
      if (subset & (1 << c)) columns.push_back(c);
    }
    Eigen::MatrixXd B(A.rows(), static_cast<Eigen::Index>(columns.size()));
    for (std::size_t c = 0; c < columns.size(); ++c) B.col(static_cast<Eigen::Index>(c)) = A.col(columns[c]);
    const Eigen::VectorXd solution = B.colPivHouseholderQr().solve(y);
    if (!solution.allFinite() || solution.minCoeff() < 0.0) continue;
    const double sse = (B * solution - y).squaredNorm();
    if (sse < best_sse) {
      best_sse = sse;
      best.setZero();
      for (std::size_t c = 0; c < columns.size(); ++c) best(columns[c]) = solution(static_cast<Eigen::Index>(c));
    }
  }
  return best;
}

// The method's variances at one lag of the increments (header, 3), per axis group, and the mean
// squared length of its increments there (a heading error of the first pose moves the increment's
// end by the increment's length times that error: the translation grows with it, not slowly).
struct LagVariance {
  double lag = 0.0;                   // scans
  double translation = 0.0, rotation = 0.0;
  double lever = 0.0;                 // half the mean squared length of the increments, m^2
};

// The slow error's variance and time constant of one axis group (header, 3): V = w + 2 sigma_b^2
// (1 - exp(-k / tau)), the white part w and sigma_b^2 non-negative, by least squares relative to
// each lag's V; tau the best of 1, 2, 4, ... max_time_constant. For translation, V is first rid of
// the lever term: L times the variance of the method's heading (`heading_variance`).
std::pair<double, double> fit_slow_error(const std::vector<LagVariance>& lags, bool translation,
                                         double heading_variance, double max_time_constant) {
  const auto rows = static_cast<Eigen::Index>(lags.size());
  double best_sse = std::numeric_limits<double>::infinity(), best_variance = 0.0, best_tau = 1.0;
  for (double tau = 1.0; tau <= max_time_constant; tau *= 2.0) {
    Eigen::Matrix<double, Eigen::Dynamic, 2> A(rows, 2);
    Eigen::VectorXd y(rows);
    for (Eigen::Index j = 0; j < rows; ++j) {
      const LagVariance& v = lags[static_cast<std::size_t>(j)];
      const double value = translation ? v.translation - v.lever * heading_variance : v.rotation;
      const double weight = 1.0 / std::max(std::abs(translation ? v.translation : v.rotation), 1e-12);
      A.row(j) << weight, weight * 2.0 * (1.0 - std::exp(-v.lag / tau));
      y(j) = weight * value;
    }
    const Eigen::Vector2d x = non_negative_least_squares<2>(A, y);
    const double sse = (A * x - y).squaredNorm();
    if (sse < best_sse) best_sse = sse, best_variance = x(1), best_tau = tau;
  }
  return {best_variance, best_tau};
}

// With the third stream (header, 3): the odometry's drift scales from its own variances, and the
// method's slow error from its own.
void estimate_with_scan_odometry(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                 const std::vector<SE2>& scan, const std::vector<double>& translation_sum,
                                 const std::vector<double>& rotation_sum, const OdometrySmoothingConfig& config,
                                 PoseStreamNoise& noise) {
  const Eigen::Vector3d odometry_white = squared(noise.odometry_jitter);
  // The drift fit on the odometry's variances, each lag's samples drawn anew for each round.
  const auto [translation_scale, rotation_scale] = fit_growth_scales([&](const auto& visit) {
    for (const std::size_t k : kLags) {
      for (const HatSample& h : hat_samples(method, odometry, scan, k, config.trim_quantile)) {
        visit(translation_sum[h.first + k] - translation_sum[h.first],
              h.odometry_translation - (odometry_white.x() + odometry_white.y()),
              rotation_sum[h.first + k] - rotation_sum[h.first], h.odometry_rotation - 2.0 * odometry_white.z());
      }
    }
  });
  noise.translation_scale = std::clamp(translation_scale, config.min_scale, config.max_scale);
  noise.rotation_scale = std::clamp(rotation_scale, config.min_scale, config.max_scale);
  // The method's slow error on its own variances.
  std::vector<LagVariance> lags;
  for (const std::size_t k : kSlowLags) {
    if (4 * k > method.size()) break;
    const std::vector<HatSample> samples = hat_samples(method, odometry, scan, k, config.trim_quantile);
    if (samples.empty()) break;
    LagVariance v{.lag = static_cast<double>(k)};
    for (const HatSample& h : samples) {
      v.translation += h.method_translation, v.rotation += h.method_rotation;
      v.lever += 0.5 * relative(method[h.first], method[h.first + k]).head<2>().squaredNorm();
    }
    const auto count = static_cast<double>(samples.size());
    v.translation /= count, v.rotation /= count, v.lever /= count;
    lags.push_back(v);
  }
  // The heading's jitter moves each increment's end by the increment's length times it (a slow
  // heading error turns the poses around it with their positions, and the increments do not see it).
  const auto [br, taur] = fit_slow_error(lags, false, 0.0, config.max_time_constant);
  const auto [bt, taut] = fit_slow_error(lags, true, squared(noise.method_jitter).z(), config.max_time_constant);
  noise.method_slow = Eigen::Vector3d(std::sqrt(bt), std::sqrt(bt), std::sqrt(br));
  noise.method_time_constant = Eigen::Vector2d(taut, taur);
  noise.streams = 3;
}

// estimate_pose_stream_noise (header), given the model's variances of each increment.
PoseStreamNoise estimate_noise(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                               const std::vector<Eigen::Vector3d>& model, const OdometrySmoothingConfig& config,
                               const std::vector<SE2>* scan) {
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
  if (scan != nullptr) {
    estimate_with_scan_odometry(method, odometry, *scan, translation_sum, rotation_sum, config, noise);
    return noise;
  }
  const auto [translation_scale, rotation_scale] = fit_growth_scales([&](const auto& visit) {
    for (const std::size_t k : kLags) {
      for (std::size_t i = 0; i + k < n; ++i) {
        const Eigen::Vector3d d = minus(relative(method[i], method[i + k]), relative(odometry[i], odometry[i + k]));
        visit(translation_sum[i + k] - translation_sum[i], 0.5 * (d.x() * d.x() + d.y() * d.y()) - (white.x() + white.y()),
              rotation_sum[i + k] - rotation_sum[i], d.z() * d.z() - 2.0 * white.z());
      }
    }
  });
  noise.translation_scale = std::clamp(translation_scale, config.min_scale, config.max_scale);
  noise.rotation_scale = std::clamp(rotation_scale, config.min_scale, config.max_scale);
  return noise;
}

}  // namespace

void validate(const OdometrySmoothingConfig& config) {
  check_fields(config, "OdometrySmoothingConfig");
  check(config.min_scale <= config.max_scale, "OdometrySmoothingConfig: min_scale must be <= max_scale");
  validate(config.odometry_noise);
}

PoseStreamNoise estimate_pose_stream_noise(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                           const OdometrySmoothingConfig& config, const std::vector<SE2>* scan_odometry) {
  check(method.size() == odometry.size() && method.size() >= 5,
        "estimate_pose_stream_noise: two streams of the same length, at least 5 poses");
  check(scan_odometry == nullptr || scan_odometry->size() == method.size(),
        "estimate_pose_stream_noise: the scan odometry must have one pose per scan");
  return estimate_noise(method, odometry, model_variances(odometry, config.odometry_noise), config, scan_odometry);
}

namespace {

// What both entry points check first; false (with `out.skipped` saying why) leaves the poses.
bool may_smooth(const OdometrySmoothingConfig& config, bool sizes_agree, std::size_t poses, OdometrySmoothingStats& out) {
  validate(config);
  out = {};
  out.poses = poses;
  if (!config.enabled) out.skipped = "disabled";
  else if (!sizes_agree) out.skipped = "the method gave a pose to a different number of scans than the odometry";
  return out.skipped.empty();
}

}  // namespace

std::vector<SE2> smooth_with_odometry(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                      const OdometrySmoothingConfig& config, OdometrySmoothingStats* stats,
                                      const std::vector<SE2>* scan_odometry) {
  OdometrySmoothingStats local;
  OdometrySmoothingStats& out = stats != nullptr ? *stats : local;
  if (!may_smooth(config, method.size() == odometry.size(), method.size(), out)) return method;
  if (method.size() < config.min_poses) {
    out.skipped = "fewer poses than min_poses";
    return method;
  }
  const std::vector<Eigen::Vector3d> model = model_variances(odometry, config.odometry_noise);
  const bool third_stream = scan_odometry != nullptr && scan_odometry->size() == method.size();
  const PoseStreamNoise noise = estimate_noise(method, odometry, model, config, third_stream ? scan_odometry : nullptr);
  out.noise = noise;
  const Eigen::Vector3d jitter = squared(noise.method_jitter).cwiseMax(kMinJitterVariance);
  const Eigen::Vector3d odometry_white = squared(noise.odometry_jitter);
  SlowError slow;
  slow.variance = squared(noise.method_slow);
  const Eigen::Vector3d tau(noise.method_time_constant.x(), noise.method_time_constant.x(), noise.method_time_constant.y());
  slow.factor = (-tau.cwiseInverse()).array().exp().matrix();
  // The method's own increment from scan to scan: twice its jitter and its slow error's step.
  const Eigen::Vector3d method_step = 2.0 * jitter + 2.0 * slow.variance.cwiseProduct(Eigen::Vector3d::Ones() - slow.factor);
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
    const double step_m2 = step.cwiseProduct(step).cwiseQuotient(Q[i] + method_step).sum();
    if (!std::isfinite(step_m2) || step_m2 > config.gate_chi2) {
      cut[i] = true;
      ++out.steps_refused;
    }
  }
  const std::vector<Eigen::Vector3d> smoothed =
      rts_smoother(method, odometry, Q, cut, jitter, slow, config.gate_chi2, config.checkpoint_interval,
                   out.poses_downweighted);
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
  out.stretches = 1;
  return poses;
}

std::vector<SE2> smooth_trusted_with_odometry(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                              const std::vector<bool>& trusted, const OdometrySmoothingConfig& config,
                                              OdometrySmoothingStats* stats) {
  OdometrySmoothingStats local;
  OdometrySmoothingStats& out = stats != nullptr ? *stats : local;
  const bool sizes_agree = method.size() == odometry.size() && method.size() == trusted.size();
  if (!may_smooth(config, sizes_agree, method.size(), out)) return method;
  std::vector<SE2> poses = method;
  std::size_t longest = 0;
  for (std::size_t begin = 0; begin < method.size();) {
    if (!trusted[begin]) {
      ++begin;
      continue;
    }
    std::size_t end = begin;
    while (end < method.size() && trusted[end]) ++end;
    const auto first = static_cast<std::ptrdiff_t>(begin);
    const auto last = static_cast<std::ptrdiff_t>(end);
    OdometrySmoothingStats stretch;
    const std::vector<SE2> smoothed =
        smooth_with_odometry({method.begin() + first, method.begin() + last},
                             {odometry.begin() + first, odometry.begin() + last}, config, &stretch);
    if (stretch.applied) {
      std::copy(smoothed.begin(), smoothed.end(), poses.begin() + first);
      ++out.stretches;
      out.steps_refused += stretch.steps_refused;
      out.poses_downweighted += stretch.poses_downweighted;
      out.max_change_m = std::max(out.max_change_m, stretch.max_change_m);
      if (end - begin > longest) {
        longest = end - begin;
        out.noise = stretch.noise;
      }
    }
    begin = end;
  }
  out.applied = out.stretches > 0;
  if (!out.applied) out.skipped = "no trusted stretch of min_poses poses";
  return poses;
}

}  // namespace slam2d
