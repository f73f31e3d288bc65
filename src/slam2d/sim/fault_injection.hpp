// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Fault injection for CARMEN logs: deterministic perturbations of a recorded log's odometry,
// timing and laser scans, to measure how a method degrades (docs/faults.md has every fault, its
// parameters, units and defaults, and why).
//
// A log is its messages in file order (std::vector<SensorMessage>, as CarmenReader gives them).
// The laser geometry travels in every LaserMessage (angles, field of view, maximum range,
// mounting); write_carmen_log (io/carmen_log.hpp) declares it again with PARAM lines, so faults
// that change it (beams, fov, range-max) read back exactly. Faults are applied in the order
// given; fault i draws from its own stream Rng(seed).split(i), so a log, a list of faults and a
// seed give the same messages on every platform, and adding a fault at the end does not change
// what the earlier ones did.
//
// Odometry is sampled twice in a CARMEN log: by the ODOM lines, and by the odometry pose of every
// laser line (and TRUEPOS). The faults treat them as two chains, each in file order: the laser
// chain and the ODOM chain. (Neither one merged order is a smooth path: Intel's stamps step back
// in file order, FR079's laser lines come after ODOM lines stamped later; each chain alone is
// smooth. In the SLAM-corrected logs the two are not even the same odometry.) Increment-wise
// faults re-integrate each chain from a common anchor, the log's first odometry pose, by the same
// rule (Eq. 1 of docs/faults.md): T'_k = T'_{k-1} * rule(T_{k-1}^-1 * T_k), T'_anchor = T_anchor.
// A laser line's estimated-pose triple follows its odometry pose when it repeats it (raw logs)
// and is kept otherwise; ROBOTLASER1 keeps its laser-on-robot mounting.
//
// Time windows (stall, odom-gap, scan-gap) are [t0 + start + m every, t0 + start + m every +
// duration), m = 0, 1, ..., with t0 the stamp of the log's first message.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "slam2d/core/rng.hpp"
#include "slam2d/core/sensor_log.hpp"

namespace slam2d {

/// Repeating time windows, relative to the log's first stamp.
struct FaultWindows {
  double every = 60.0;     // s between window starts, > 0
  double start = 60.0;     // s from the log's first stamp to the first window, >= 0 (parse default: every)
  double duration = 1.2;   // s, in (0, every)
};

/// Odometry stalls, then catches up: in each window every odometry pose (laser lines, ODOM, TRUEPOS)
/// holds its chain's last pose before the window; tv/rv are kept. After it, the true odometry.
struct StallFault {
  FaultWindows windows;
};
/// Odometry missing: ODOM lines in each window are removed; laser lines hold the odometry pose
/// of the last laser line before the window, as a logger holds the last odometry received.
struct OdomGapFault {
  FaultWindows windows;
};
/// Odometry restarts (a driver or controller reset): at t0 + start + m every (m = 0, 1, ...) each
/// chain's odometry starts again from the origin: every later pose is re-expressed in the frame of
/// the chain's first pose at or after that moment, which becomes (0, 0, 0). One increment per
/// restart jumps by the inverse of where the odometry had got to; all others are kept.
struct OdomResetFault {
  double every = 120.0;  // s between restarts, > 0
  double start = 120.0;  // s from the log's first stamp to the first restart, >= 0 (parse default: every)
};
/// Wheel-scale error: increments scaled, re-integrated (Eq. 1). Factors of exactly 1 change nothing.
struct WheelScaleFault {
  double translation = 1.05;  // factor on the increments' translation, in (0, 10]
  double rotation = 1.0;      // factor on the increments' rotation, in (0, 10]
};
/// Heading drift: each increment turns by an extra rate * (its signed forward travel), re-integrated (Eq. 1).
struct HeadingDriftFault {
  double rate_deg_per_m = 0.5;  // deg per metre travelled forward, |rate| <= 90
};
/// Random odometry error, the noise Gutmann et al. (IROS 1998) added to the odometry to compare
/// localizers: each increment's translation is lengthened or shortened and its heading turned by
/// Gaussian noise whose variance grows with the motion, a random walk in the distance travelled
/// and the angle turned (so the error after L m has standard deviation translation * sqrt(L),
/// however often the log samples the odometry). The laser chain (the ODOM chain in a log whose
/// laser lines carry no odometry) is re-integrated with the noisy increments (Eq. 1); the other
/// chain gets the same correction (T' T^-1 of the nearest laser line), so both stay one odometry.
/// All zero changes nothing. A robot standing still gets no error.
struct OdomNoiseFault {
  double translation = 0.05;  // m per sqrt(m) travelled: along-track error, in [0, 10]
  double heading = 0.02;      // rad per sqrt(m) travelled: heading error from driving, in [0, 10]
  double rotation = 0.05;     // rad per sqrt(rad) turned: heading error from turning, in [0, 10]
};
/// Odometry and laser out of step (unsynchronised clocks): every odometry pose becomes its chain's
/// pose at its own stamp + by, interpolated along the chain (linear in translation, shortest arc in
/// heading) and held at the chain's ends. by > 0: the odometry runs ahead of the laser (the pose
/// beside a scan is where the robot is `by` seconds later). The shift is the one the time-offset
/// compensation undoes (OdometryChain, core/odometry_chain.hpp): each chain in file order with its
/// stamps lowered to be non-decreasing (Intel's late stamps), so a stamp that steps back does not
/// make the path zigzag; tv and rv are kept.
struct OdomShiftFault {
  double by = 0.6;  // s, |by| <= 5
};
/// Scan dropouts: every laser line in each window is removed (odometry kept).
struct ScanGapFault {
  FaultWindows windows;
};
/// Keeps laser lines 0, k, 2k, ... of each laser type.
struct DecimateFault {
  std::size_t k = 2;  // >= 1
};
/// A slower scanner: a laser line is kept when at least 1/hz s passed since the last kept one of
/// its laser type (1 us of slack for stamps written in microseconds); odometry kept.
struct ScanRateFault {
  double hz = 1.0;  // Hz, in (0, 1000]
};
/// Laser stamps get Gaussian noise.
struct JitterFault {
  double sigma = 0.01;  // s, in [0, 60]
};
/// Each laser line is written twice with probability p.
struct DuplicateFault {
  double p = 0.01;  // in [0, 1]
};
/// With probability p a laser line's stamp moves back by `by` (out-of-order stamps).
struct BackwardsFault {
  double p = 0.01;  // in [0, 1]
  double by = 0.5;  // s, > 0
};
/// Gaussian range noise on every valid reading, clamped at 0.
struct RangeNoiseFault {
  double sigma = 0.03;  // m, in [0, 100]
};
/// With probability p a valid reading becomes a no-return (the scan's maximum range).
struct SpuriousMaxFault {
  double p = 0.01;  // in [0, 1]
};
/// With probability p a reading becomes a short return, uniform in [min, max).
struct SpuriousShortFault {
  double p = 0.01;    // in [0, 1]
  double min = 0.05;  // m, >= 0
  double max = 0.5;   // m, > min
};
/// With probability p a valid reading becomes a far spurious return (a reflection off glass or a
/// mirror), uniform in [min, min(max, the scan's maximum range)): never a no-return.
struct SpuriousFarFault {
  double p = 0.01;   // in [0, 1]
  double min = 20.0;  // m, >= 0, below every scan's maximum range
  double max = 50.0;  // m, > min
};
/// Mixed pixels at depth edges (a beam's footprint straddles a near and a far surface): for each
/// pair of neighbouring valid readings whose ranges differ by more than `jump`, with probability p
/// the beam on the far side of the edge gets a range uniform in [near, far), or, with
/// `alternate` = n > 0, the n beams beyond the edge on the far side alternate: the 1st, 3rd, ...
/// get the near range, the others keep theirs (the stretch ends at the next beam that is no longer
/// behind the edge). Edges are found on the readings as logged.
struct MixedPixelsFault {
  double p = 0.5;           // probability per edge, in [0, 1]
  double jump = 0.5;        // m, > 0: a range difference that makes an edge
  std::size_t alternate = 0;  // beams in an alternating stretch, 0 (a single mixed pixel) to 100
};
/// Glass: `sectors` sectors of bearing fixed in the odometry frame, each `width` wide and centred
/// at seeded random bearings, in which every reading becomes a no-return (the scan's maximum
/// range): panes the laser passes through, on a fixed side of the building. A laser line without
/// an odometry pose (a bag's) uses its sensor frame.
struct GlassFault {
  std::size_t sectors = 2;  // in [1, 100]
  double width_deg = 30.0;  // deg, in (0, 360]
};
/// A noisy laser over good odometry: each scan turned by N(0, bearing^2) about the sensor (its
/// ranges resampled at the turned bearings), then N(0, sigma^2) on every valid reading, clamped at 0.
struct LaserNoiseFault {
  double sigma = 0.05;       // m, in [0, 100]
  double bearing_deg = 0.5;  // deg, in [0, 90]
};
/// Fewer beams: keeps beams 0, k, 2k, ... (same first beam and field of view, k times the resolution).
struct BeamsFault {
  std::size_t k = 2;  // >= 1
};
/// Narrower field of view: keeps the beams within +-deg/2 of the sensor's axis.
struct FovFault {
  double deg = 90.0;  // deg, in (0, 360]
};
/// A shorter scanner: readings at or beyond `max` become no-returns (= max), and max is declared.
struct RangeMaxFault {
  double max = 30.0;  // m, > 0 and at most the log's maximum range
};

/// The whole log played `times` times end to end, as a robot that drives the same route again and
/// again (a long-run memory test): every copy's stamps follow the previous copy's last one after
/// the log's median laser period; its poses are the log's own (the robot is back at the start).
struct RepeatFault {
  std::size_t times = 2;  // >= 1, at most 1000
  bool back = false;      // every other copy played backwards: the robot drives the route back to its start
};

using Fault = std::variant<StallFault, OdomGapFault, OdomResetFault, WheelScaleFault, HeadingDriftFault, OdomNoiseFault,
                           OdomShiftFault, ScanGapFault, DecimateFault, ScanRateFault, JitterFault, DuplicateFault,
                           BackwardsFault, RangeNoiseFault, SpuriousMaxFault, SpuriousShortFault, SpuriousFarFault,
                           MixedPixelsFault, GlassFault, LaserNoiseFault, BeamsFault, FovFault, RangeMaxFault, RepeatFault>;

/// What one fault changed: its canonical spec and named counts or sizes (e.g. {"stalls", 22}).
struct FaultReport {
  std::string spec;
  std::vector<std::pair<std::string, double>> changes;
};

/// The fault kinds, as spelled in specs ("stall", "odom-gap", ...).
std::vector<std::string> fault_kinds();

/// Parses "KIND[:key=value,...]". Throws Error naming the spec on an unknown kind or key, a
/// repeated key, a value that is not a number (or not an integer where one is needed) or one out
/// of its range.
Fault parse_fault(std::string_view spec);

/// The canonical spec of a fault, with every parameter: parse_fault(fault_spec(f)) gives f back.
std::string fault_spec(const Fault& fault);

/// Applies one fault to the messages (file order), drawing from `rng`. Throws Error when the
/// fault cannot apply to a scan (fov keeping no beam, range-max beyond the scan's maximum range,
/// spurious-far's min not below it).
FaultReport apply_fault(const Fault& fault, std::vector<SensorMessage>& messages, Rng& rng);

/// Applies the faults in order, fault i with Rng(seed).split(i).
std::vector<FaultReport> apply_faults(const std::vector<Fault>& faults, std::vector<SensorMessage>& messages,
                                      std::uint64_t seed);

}  // namespace slam2d
