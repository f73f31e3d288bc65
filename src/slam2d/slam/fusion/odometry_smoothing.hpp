// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A mapping method's per-scan poses smoothed with the wheel odometry they were given, each
// weighed by a noise the data itself shows.
//
// Every mapping method places each scan by matching it; the odometry measures the motion between
// two scans once more. A matched pose has an error of its own at each scan (a scan turned by its
// scanner, a noisy or thin scan matched a little off): it does not drift, but it jitters, and on
// relations a few seconds long the jitter of the two ends is the whole error. The odometry
// drifts, but from one scan to the next it is smooth. So the best per-scan pose is the product of
// both: the method's pose as an absolute measurement with the covariance R of its jitter, the
// odometry's increment as a relative one with the covariance Q_i of its motion noise, combined by
// a Rauch-Tung-Striebel smoother (a Kalman filter forward, its gains backward), extended to SE(2).
//
// Neither covariance is assumed: both are estimated from the two pose streams.
// 1. The jitter of each (the three-cornered hat, two-sensor form: J. E. Gray and D. W. Allan, "A
//    method for estimating the frequency stability of an individual oscillator", 1974, in the
//    form of F. E. Grubbs, 1948). The second difference of a pose stream at scan i, in its own
//    frame, (p_i^-1 p_{i+1}) + (p_i^-1 p_{i-1}), is the robot's change of velocity plus 6 times
//    the stream's white variance. The robot's part is common to both streams; the two noises are
//    independent. So per axis (x, y, theta of the robot frame), with l and o the two streams'
//    second differences: R = (E[l^2] - E[l o]) / 6 and the odometry's own white variance
//    W = (E[o^2] - E[l o]) / 6. A sample whose |l - o| lies beyond the 99th percentile (a match
//    gone wrong, an odometry jump) is left out. The odometry's second differences are divided by
//    its systematic scale first (a wheel's: the two streams' increments over 16 scans, regressed),
//    or a scale error of a few percent would pass the robot's own accelerations off as noise.
//    Translation is taken as isotropic (the mean of x's and y's variances): apart, the lateral
//    jitter of a stream could come out near 0 where the robot's change of velocity hides it.
//    Where that change dwarfs the noises (scans far apart) R is a small difference of large sums:
//    R is taken at its lower confidence bound, jitter_confidence jackknife standard errors (20
//    contiguous blocks) below the estimate, so that an unsure estimate leaves the method's poses.
// 2. The odometry's drift: the disagreement of the two streams over k scans (k = 1, 2, 3, 4, 6, 8,
//    12, 16), less the white part 2 (R + W), against the sum of the motion noise model's variances
//    along those k increments (core/motion_fusion.hpp, unscaled): a scale s times that sum plus a
//    quadratic term for systematic error (a wheel's scale), fitted by non-negative least squares,
//    three times, trimming samples beyond 16 times the fit. Q_i = s q_i + 2 W.
//    The method's own drift is indistinguishable from the odometry's there and is counted as the
//    odometry's: it makes the smoother trust the method more, never less.
// 3. With a third stream (scan odometry: scan-to-scan matches, whose error is a random walk of its
//    own), the two-stream estimate of 2. is replaced. Two streams cannot tell a slow error of the
//    method (a tracker following its local map for seconds, under a noisy laser) from the
//    odometry's drift: the fit above counts it as the odometry's (Intel with a noisy laser: a drift
//    scale of 5.5 against 1.8 clean) and the smoother passes it on. Three can, with the
//    three-cornered hat on the increments themselves, at every lag and with no shape assumed: for
//    the increments over k scans of the method m, the odometry o and the scan odometry s (each in
//    its own first pose's frame), E[(m - o) . (s - o)] is the odometry's error variance and
//    E[(m - o) . (m - s)] the method's, the three errors being independent. The drift fit of 2.
//    runs on the first (lags 1-16; 1 % of the samples, the largest disagreements, left out). The
//    second, over lags 1-64, gives the method a Gauss-Markov error b besides its jitter:
//    b_{i+1} = phi b_i + w, phi = exp(-1 / tau), whose increments' variance 2 sigma_b^2 (1 - phi^k)
//    is fitted with a white part beside it to the method's variances by non-negative least squares
//    relative to each lag's value, per axis group (translation, rotation), tau the best of 1, 2,
//    4, ... max_time_constant scans (16, the longest lag of the drift fit: a slower error of the
//    method nothing tells from the odometry's drift); the translation's variances first less the
//    lever of the heading's jitter (half the increment's squared length times it). The smoother
//    then carries b as three more states (the method's pose is x + b + its jitter) and lets the
//    odometry carry the motion over the seconds b is slow. The scan odometry must be independent
//    of the other two; it is not quite (apps' map_job.cpp says which way it leans), so this is an
//    option (`slam2d map --smoothing-third-stream`).
// Then forward over the scans: the odometry's increment predicts; it is refused (the chain is cut
// and the filter restarts at the method's pose) where it disagrees with the method's own increment
// beyond a chi-square gate under Q_i + 2R (a jump, a stall, a slip); the method's pose updates,
// with R inflated by m^2 / gate where its innovation's squared Mahalanobis distance m^2 is beyond
// the gate (a Huber-like weight: a wrong match loses weight, never all of it, so that a filter
// that has gone wrong cannot refuse every pose after). Backward: the RTS gains.
//
// Where the method is sure and the odometry noisy, R is near 0 and the poses stay the method's;
// where the laser is noisy and the odometry good, the poses follow the odometry between scans and
// the method over longer spans. The map stays the method's (it was built from its own poses).
//
// A localizer's run is smoothed the same way over each stretch where it was localized
// (smooth_trusted_with_odometry; `slam2d localize`).

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "slam2d/core/config_fields.hpp"
#include "slam2d/core/motion_fusion.hpp"
#include "slam2d/core/se2.hpp"

namespace slam2d {

struct OdometrySmoothingConfig {
  bool enabled = true;
  double gate_chi2 = kMotionGateChi2;  // 1, the chi-square gate of the step test and the update
  double trim_quantile = 0.99;         // 1, the hat's samples kept by |l - o|
  double jitter_confidence = 2.0;      // jackknife standard errors taken off the method's jitter
  double min_scale = 0.05;             // 1, lower bound of the odometry drift's scale s
  double max_scale = 100.0;            // 1, upper bound
  std::size_t min_poses = 50;          // fewer: the poses are left as they are
  // scans, the longest time constant of the method's slow error: the longest lag at which the
  // odometry's drift is fitted (16), beyond which nothing tells the two apart (Intel at 1 Hz, graph
  // SLAM, over all relations: 0.019 m with two streams, 0.045 with 64, 0.027 with 16)
  double max_time_constant = 16.0;
  // The smoother keeps the filtered state of every n-th scan only and filters each stretch again
  // on its way back, to the bit the same states (a checkpointed Rauch-Tung-Striebel smoother):
  // it holds two stretches' states, not the run's (336 bytes a scan; ten passes of Intel held 46
  // MB), for one more forward pass. The run's size alone does not change the poses.
  std::size_t checkpoint_interval = 1024;  // scans
  OdometryNoiseConfig odometry_noise{};  // the motion noise model's form (its online scale is unused)
};

template <typename Fields>
void describe(Fields& f, OdometrySmoothingConfig& c) {
  f.flag("enabled", c.enabled, "smooth the method's per-scan poses with the odometry (false: the method's poses)");
  f.number("gate_chi2", c.gate_chi2, "1", greater_than(0), "chi-square gate (3 degrees of freedom) of the step test and the update");
  f.number("trim_quantile", c.trim_quantile, "1", between(0.5, 1), "quantile of |l - o| kept when the jitters are estimated");
  f.number("jitter_confidence", c.jitter_confidence, "1", at_least(0),
           "standard errors (jackknife over 20 blocks) taken off the method's jitter: unsure, leave its poses");
  f.number("min_scale", c.min_scale, "1", greater_than(0), "lower bound of the odometry drift's scale");
  f.number("max_scale", c.max_scale, "1", at_least(1), "upper bound of the odometry drift's scale");
  f.number("min_poses", c.min_poses, "1", at_least(5), "shorter runs are left as they are");
  f.number("max_time_constant", c.max_time_constant, "scans", between(1, 1024),
           "longest time constant of the method's slow error (three streams: header, 3)");
  f.number("checkpoint_interval", c.checkpoint_interval, "scans", at_least(1),
           "the smoother keeps every n-th filtered state and filters each stretch again backward (1: keeps them all)");
  f.section("odometry_noise", c.odometry_noise, "the form of the odometry's motion noise (core/motion_fusion.hpp)");
}

/// Throws Error for out-of-range values.
void validate(const OdometrySmoothingConfig& config);

/// What the data showed of the two streams (standard deviations per axis of the robot frame:
/// x, y in m, the same for both, theta in rad).
struct PoseStreamNoise {
  Eigen::Vector3d method_jitter = Eigen::Vector3d::Zero();    // sqrt(R)
  Eigen::Vector3d odometry_jitter = Eigen::Vector3d::Zero();  // sqrt(W)
  double translation_scale = 1.0;  // s of the odometry's drift, translation
  double rotation_scale = 1.0;     // ... rotation
  // The method's slow (Gauss-Markov) error, estimated with a third stream only (header, 3):
  Eigen::Vector3d method_slow = Eigen::Vector3d::Zero();  // sigma_b per axis (x, y the same; theta)
  Eigen::Vector2d method_time_constant{1.0, 1.0};         // tau, scans: translation, rotation
  std::size_t streams = 2;                                // 3 with the scan odometry
};

struct OdometrySmoothingStats {
  bool applied = false;
  std::string skipped;            // why not, when not applied
  PoseStreamNoise noise;
  std::size_t poses = 0;
  std::size_t steps_refused = 0;      // odometry increments cut from the chain
  std::size_t poses_downweighted = 0; // method poses whose weight the update reduced
  double max_change_m = 0.0;          // the largest move of a pose
  std::size_t stretches = 0;          // stretches smoothed (1 for a whole run)
};

/// The noise of the streams, as estimated above. `method` and `odometry` have one pose per scan,
/// same size, at least 5 poses; `scan_odometry`, when given with the same size, is the third
/// stream (header, 3).
PoseStreamNoise estimate_pose_stream_noise(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                           const OdometrySmoothingConfig& config = {},
                                           const std::vector<SE2>* scan_odometry = nullptr);

/// The smoothed poses, one per scan. Returns `method` itself when smoothing is disabled, the run
/// is shorter than min_poses or the sizes differ (stats->skipped says which). A `scan_odometry` of
/// another size than `method` is not used (two streams).
std::vector<SE2> smooth_with_odometry(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                      const OdometrySmoothingConfig& config = {},
                                      OdometrySmoothingStats* stats = nullptr,
                                      const std::vector<SE2>* scan_odometry = nullptr);

/// The same over the stretches where `trusted` holds (a localizer's localized steps): each stretch
/// of at least min_poses is smoothed on its own, with its own noise; the poses outside (a filter
/// lost, or still converging, whose pose is no measurement) are left as they are. `stats` sums the
/// stretches (`noise` is the longest smoothed stretch's); `stretches` counts those smoothed.
std::vector<SE2> smooth_trusted_with_odometry(const std::vector<SE2>& method, const std::vector<SE2>& odometry,
                                              const std::vector<bool>& trusted,
                                              const OdometrySmoothingConfig& config = {},
                                              OdometrySmoothingStats* stats = nullptr);

}  // namespace slam2d
