// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/sim/fault_injection.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <optional>
#include <set>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/number_text.hpp"
#include "slam2d/core/odometry_chain.hpp"

namespace slam2d {

namespace {

using Messages = std::vector<SensorMessage>;
using Changes = std::vector<std::pair<std::string, double>>;

// ---------------------------------------------------------------------------------------------
// Specs: "kind:key=value,...".

struct Range {
  double low;
  double high;
  bool low_open = false;  // low itself is out
};

bool in_range(double value, const Range& range) {
  return (range.low_open ? value > range.low : value >= range.low) && value <= range.high;
}

std::string describe(const Range& range) {
  const std::string high = std::isinf(range.high) ? "inf)" : format_number(range.high) + "]";
  return (range.low_open ? "(" : "[") + format_number(range.low) + ", " + high;
}

constexpr double kInf = std::numeric_limits<double>::infinity();

// The key=value pairs of a spec, read by name; finish() refuses the keys nobody asked for.
class SpecArguments {
 public:
  SpecArguments(std::string spec, std::string kind, std::string_view parameters);

  [[noreturn]] void fail(const std::string& message) const {
    throw Error("--fault '" + spec_ + "': " + message);
  }
  double number(std::string_view key, double fallback, const Range& range);
  std::size_t count(std::string_view key, std::size_t fallback, std::size_t minimum);
  void finish() const;

 private:
  const std::string* value(std::string_view key);

  std::string spec_;
  std::string kind_;
  std::vector<std::pair<std::string, std::string>> pairs_;
  std::vector<std::string> known_;
};

SpecArguments::SpecArguments(std::string spec, std::string kind, std::string_view parameters)
    : spec_(std::move(spec)), kind_(std::move(kind)) {
  if (parameters.empty()) return;
  for (std::size_t begin = 0; begin <= parameters.size();) {
    const std::size_t comma = std::min(parameters.find(',', begin), parameters.size());
    const std::string_view pair = parameters.substr(begin, comma - begin);
    const std::size_t equals = pair.find('=');
    if (equals == std::string_view::npos || equals == 0) fail("expected key=value, got '" + std::string(pair) + "'");
    std::string key(pair.substr(0, equals));
    for (const auto& [seen, unused] : pairs_) {
      if (seen == key) fail("key '" + key + "' given twice");
    }
    pairs_.emplace_back(std::move(key), std::string(pair.substr(equals + 1)));
    begin = comma + 1;
  }
}

const std::string* SpecArguments::value(std::string_view key) {
  known_.emplace_back(key);
  for (const auto& [name, text] : pairs_) {
    if (name == key) return &text;
  }
  return nullptr;
}

double SpecArguments::number(std::string_view key, double fallback, const Range& range) {
  const std::string* text = value(key);
  if (text == nullptr) return fallback;
  const std::optional<double> parsed = parse_double(*text);
  if (!parsed || !std::isfinite(*parsed)) fail(std::string(key) + " is not a number: '" + *text + "'");
  if (!in_range(*parsed, range)) fail(std::string(key) + "=" + *text + " is out of range " + describe(range));
  return *parsed;
}

std::size_t SpecArguments::count(std::string_view key, std::size_t fallback, std::size_t minimum) {
  const std::string* text = value(key);
  if (text == nullptr) return fallback;
  const std::optional<int> parsed = parse_int(*text);
  if (!parsed) fail(std::string(key) + " is not an integer: '" + *text + "'");
  if (*parsed < static_cast<int>(minimum)) fail(std::string(key) + "=" + *text + " must be >= " + std::to_string(minimum));
  return static_cast<std::size_t>(*parsed);
}

void SpecArguments::finish() const {
  for (const auto& [key, text] : pairs_) {
    if (std::find(known_.begin(), known_.end(), key) != known_.end()) continue;
    std::string keys;
    for (const std::string& name : known_) keys += (keys.empty() ? "" : ", ") + name;
    fail("unknown key '" + key + "' for " + kind_ + " (keys: " + keys + ")");
  }
}

const Range kProbability{0.0, 1.0};
const Range kPositive{0.0, kInf, true};
const Range kFactor{0.0, 10.0, true};

FaultWindows parse_windows(SpecArguments& arguments) {
  FaultWindows windows;
  windows.every = arguments.number("every", windows.every, kPositive);
  windows.start = arguments.number("start", windows.every, {0.0, kInf});
  windows.duration = arguments.number("duration", windows.duration, kPositive);
  if (!(windows.duration < windows.every)) arguments.fail("duration must be shorter than every");
  return windows;
}

// p, min and max of a fault that makes spurious returns in a band of ranges.
template <typename SpuriousFault>
Fault parse_spurious(SpecArguments& arguments) {
  SpuriousFault f;
  f.p = arguments.number("p", f.p, kProbability);
  f.min = arguments.number("min", f.min, {0.0, kInf});
  f.max = arguments.number("max", f.max, kPositive);
  if (!(f.min < f.max)) arguments.fail("min must be less than max");
  return f;
}

using FaultParser = std::function<Fault(SpecArguments&)>;

// Kind names and their parsers, in the order of docs/faults.md.
const std::vector<std::pair<std::string, FaultParser>>& fault_table() {
  static const std::vector<std::pair<std::string, FaultParser>> table = {
      {"stall", [](SpecArguments& a) -> Fault { return StallFault{parse_windows(a)}; }},
      {"odom-gap", [](SpecArguments& a) -> Fault { return OdomGapFault{parse_windows(a)}; }},
      {"odom-reset", [](SpecArguments& a) -> Fault {
         OdomResetFault f;
         f.every = a.number("every", f.every, kPositive);
         f.start = a.number("start", f.every, {0.0, kInf});
         return f;
       }},
      {"wheel-scale", [](SpecArguments& a) -> Fault {
         WheelScaleFault f;
         f.translation = a.number("translation", f.translation, kFactor);
         f.rotation = a.number("rotation", f.rotation, kFactor);
         return f;
       }},
      {"heading-drift", [](SpecArguments& a) -> Fault {
         return HeadingDriftFault{a.number("rate", HeadingDriftFault{}.rate_deg_per_m, {-90.0, 90.0})};
       }},
      {"odom-noise", [](SpecArguments& a) -> Fault {
         OdomNoiseFault f;
         f.translation = a.number("translation", f.translation, {0.0, 10.0});
         f.heading = a.number("heading", f.heading, {0.0, 10.0});
         f.rotation = a.number("rotation", f.rotation, {0.0, 10.0});
         return f;
       }},
      {"odom-shift", [](SpecArguments& a) -> Fault { return OdomShiftFault{a.number("by", OdomShiftFault{}.by, {-5.0, 5.0})}; }},
      {"scan-gap", [](SpecArguments& a) -> Fault { return ScanGapFault{parse_windows(a)}; }},
      {"decimate", [](SpecArguments& a) -> Fault { return DecimateFault{a.count("k", DecimateFault{}.k, 1)}; }},
      {"scan-rate", [](SpecArguments& a) -> Fault { return ScanRateFault{a.number("hz", ScanRateFault{}.hz, {0.0, 1000.0, true})}; }},
      {"jitter", [](SpecArguments& a) -> Fault { return JitterFault{a.number("sigma", JitterFault{}.sigma, {0.0, 60.0})}; }},
      {"duplicate", [](SpecArguments& a) -> Fault { return DuplicateFault{a.number("p", DuplicateFault{}.p, kProbability)}; }},
      {"backwards", [](SpecArguments& a) -> Fault {
         BackwardsFault f;
         f.p = a.number("p", f.p, kProbability);
         f.by = a.number("by", f.by, kPositive);
         return f;
       }},
      {"range-noise", [](SpecArguments& a) -> Fault {
         return RangeNoiseFault{a.number("sigma", RangeNoiseFault{}.sigma, {0.0, 100.0})};
       }},
      {"spurious-max", [](SpecArguments& a) -> Fault { return SpuriousMaxFault{a.number("p", SpuriousMaxFault{}.p, kProbability)}; }},
      {"spurious-short", parse_spurious<SpuriousShortFault>},
      {"spurious-far", parse_spurious<SpuriousFarFault>},
      {"mixed-pixels", [](SpecArguments& a) -> Fault {
         MixedPixelsFault f;
         f.p = a.number("p", f.p, kProbability);
         f.jump = a.number("jump", f.jump, kPositive);
         f.alternate = a.count("alternate", f.alternate, 0);
         if (f.alternate > 100) a.fail("alternate must be at most 100");
         return f;
       }},
      {"glass", [](SpecArguments& a) -> Fault {
         GlassFault f;
         f.sectors = a.count("sectors", f.sectors, 1);
         if (f.sectors > 100) a.fail("sectors must be at most 100");
         f.width_deg = a.number("width", f.width_deg, {0.0, 360.0, true});
         return f;
       }},
      {"laser-noise", [](SpecArguments& a) -> Fault {
         LaserNoiseFault f;
         f.sigma = a.number("sigma", f.sigma, {0.0, 100.0});
         f.bearing_deg = a.number("bearing", f.bearing_deg, {0.0, 90.0});
         return f;
       }},
      {"beams", [](SpecArguments& a) -> Fault { return BeamsFault{a.count("k", BeamsFault{}.k, 1)}; }},
      {"fov", [](SpecArguments& a) -> Fault { return FovFault{a.number("deg", FovFault{}.deg, {0.0, 360.0, true})}; }},
      {"range-max", [](SpecArguments& a) -> Fault { return RangeMaxFault{a.number("max", RangeMaxFault{}.max, kPositive)}; }},
      {"repeat", [](SpecArguments& a) -> Fault {
         const std::size_t back = a.count("back", 0, 0);
         if (back > 1) a.fail("back must be 0 or 1");
         const RepeatFault f{a.count("times", RepeatFault{}.times, 1), back == 1};
         if (f.times > 1000) a.fail("times must be at most 1000");
         return f;
       }},
  };
  return table;
}

// The kind and the parameters of each fault, in spec order.
using Parameters = std::pair<std::string, Changes>;

Changes window_parameters(const FaultWindows& w) {
  return {{"every", w.every}, {"start", w.start}, {"duration", w.duration}};
}
double as_number(std::size_t k) { return static_cast<double>(k); }

Parameters parameters(const StallFault& f) { return {"stall", window_parameters(f.windows)}; }
Parameters parameters(const OdomGapFault& f) { return {"odom-gap", window_parameters(f.windows)}; }
Parameters parameters(const OdomResetFault& f) { return {"odom-reset", {{"every", f.every}, {"start", f.start}}}; }
Parameters parameters(const WheelScaleFault& f) {
  return {"wheel-scale", {{"translation", f.translation}, {"rotation", f.rotation}}};
}
Parameters parameters(const HeadingDriftFault& f) { return {"heading-drift", {{"rate", f.rate_deg_per_m}}}; }
Parameters parameters(const OdomNoiseFault& f) {
  return {"odom-noise", {{"translation", f.translation}, {"heading", f.heading}, {"rotation", f.rotation}}};
}
Parameters parameters(const OdomShiftFault& f) { return {"odom-shift", {{"by", f.by}}}; }
Parameters parameters(const ScanGapFault& f) { return {"scan-gap", window_parameters(f.windows)}; }
Parameters parameters(const DecimateFault& f) { return {"decimate", {{"k", as_number(f.k)}}}; }
Parameters parameters(const ScanRateFault& f) { return {"scan-rate", {{"hz", f.hz}}}; }
Parameters parameters(const JitterFault& f) { return {"jitter", {{"sigma", f.sigma}}}; }
Parameters parameters(const DuplicateFault& f) { return {"duplicate", {{"p", f.p}}}; }
Parameters parameters(const BackwardsFault& f) { return {"backwards", {{"p", f.p}, {"by", f.by}}}; }
Parameters parameters(const RangeNoiseFault& f) { return {"range-noise", {{"sigma", f.sigma}}}; }
Parameters parameters(const SpuriousMaxFault& f) { return {"spurious-max", {{"p", f.p}}}; }
Parameters parameters(const SpuriousShortFault& f) {
  return {"spurious-short", {{"p", f.p}, {"min", f.min}, {"max", f.max}}};
}
Parameters parameters(const SpuriousFarFault& f) {
  return {"spurious-far", {{"p", f.p}, {"min", f.min}, {"max", f.max}}};
}
Parameters parameters(const MixedPixelsFault& f) {
  return {"mixed-pixels", {{"p", f.p}, {"jump", f.jump}, {"alternate", as_number(f.alternate)}}};
}
Parameters parameters(const GlassFault& f) { return {"glass", {{"sectors", as_number(f.sectors)}, {"width", f.width_deg}}}; }
Parameters parameters(const LaserNoiseFault& f) { return {"laser-noise", {{"sigma", f.sigma}, {"bearing", f.bearing_deg}}}; }
Parameters parameters(const BeamsFault& f) { return {"beams", {{"k", as_number(f.k)}}}; }
Parameters parameters(const FovFault& f) { return {"fov", {{"deg", f.deg}}}; }
Parameters parameters(const RangeMaxFault& f) { return {"range-max", {{"max", f.max}}}; }
Parameters parameters(const RepeatFault& f) {
  Parameters p{"repeat", {{"times", as_number(f.times)}}};
  if (f.back) p.second.push_back({"back", 1.0});
  return p;
}

// ---------------------------------------------------------------------------------------------
// Messages: stamps, odometry chains, laser lines.

enum Chain : std::size_t { kLaserChain = 0, kOdomChain = 1 };

std::optional<Chain> chain_of(const SensorMessage& message) {
  if (const auto* laser = std::get_if<LaserMessage>(&message)) {
    return laser->has_poses ? std::optional<Chain>(kLaserChain) : std::nullopt;
  }
  if (std::holds_alternative<ImuMessage>(message)) return std::nullopt;  // no pose
  return std::holds_alternative<OdometryMessage>(message) ? kOdomChain : kLaserChain;
}

// m, the length of the laser chain's odometry path in file order.
double laser_path_length(const Messages& messages) {
  double length = 0.0;
  std::optional<SE2> previous;
  for (const SensorMessage& message : messages) {
    if (chain_of(message) != kLaserChain) continue;
    const SE2 pose = odometry_pose(message);
    if (previous) length += (pose.translation() - previous->translation()).norm();
    previous = pose;
  }
  return length;
}

void remove_marked(Messages& messages, const std::vector<bool>& keep) {
  std::size_t out = 0;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (!keep[i]) continue;
    if (out != i) messages[out] = std::move(messages[i]);
    ++out;
  }
  messages.resize(out);
}

template <typename Function>
void for_each_laser(Messages& messages, Function&& function) {
  for (SensorMessage& message : messages) {
    if (auto* laser = std::get_if<LaserMessage>(&message)) function(*laser);
  }
}

// The window containing `stamp`, counted from the first, if any.
class WindowClock {
 public:
  WindowClock(const Messages& messages, const FaultWindows& windows)
      : t0_(messages.empty() ? 0.0 : stamp_of(messages.front())), windows_(windows) {}

  std::optional<long> window(double stamp) const {
    const double since_start = stamp - t0_ - windows_.start;
    if (!(since_start >= 0.0)) return std::nullopt;
    const double m = std::floor(since_start / windows_.every);
    if (since_start - m * windows_.every >= windows_.duration) return std::nullopt;
    return static_cast<long>(m);
  }

 private:
  double t0_;
  FaultWindows windows_;
};

// ---------------------------------------------------------------------------------------------
// Odometry faults.

struct HoldCounts {
  std::set<long> windows;          // windows that froze or removed something
  std::size_t frozen = 0;          // odometry poses changed
  std::size_t removed = 0;         // ODOM lines removed
  double max_catch_up_m = 0.0;     // largest jump of the laser chain after a window
  double max_catch_up_rad = 0.0;
};

// Freezes each chain at its last pose before every window (stall); with `remove_odom`, the ODOM
// lines inside the windows are removed instead of frozen (odom-gap).
HoldCounts hold_odometry(Messages& messages, const FaultWindows& windows, bool remove_odom) {
  struct ChainState {
    std::optional<SE2> last_original;  // the chain's previous pose as logged
    std::optional<long> window;        // the window the chain is in
    SE2 held;
  };
  const WindowClock clock(messages, windows);
  std::array<ChainState, 2> states;
  std::vector<bool> keep(messages.size(), true);
  HoldCounts counts;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    const std::optional<Chain> chain = chain_of(messages[i]);
    if (!chain) continue;
    ChainState& state = states[*chain];
    const SE2 pose = odometry_pose(messages[i]);
    const std::optional<long> window = clock.window(stamp_of(messages[i]));
    if (!window) {
      if (state.window && *chain == kLaserChain) {  // the catch-up jump
        const SE2 jump = state.held.between(pose);
        counts.max_catch_up_m = std::max(counts.max_catch_up_m, jump.translation().norm());
        counts.max_catch_up_rad = std::max(counts.max_catch_up_rad, std::abs(jump.theta()));
      }
      state.window.reset();
    } else if (remove_odom && *chain == kOdomChain) {
      keep[i] = false;
      ++counts.removed;
      counts.windows.insert(*window);
    } else {
      if (state.window != window) state.held = state.last_original.value_or(pose);
      state.window = window;
      counts.windows.insert(*window);
      if (!(state.held == pose)) {
        set_odometry_pose(messages[i], state.held);
        ++counts.frozen;
      }
    }
    state.last_original = pose;
  }
  remove_marked(messages, keep);
  return counts;
}

Changes hold_changes(const HoldCounts& counts, const char* windows_name) {
  return {{windows_name, static_cast<double>(counts.windows.size())},
          {"odometry_poses_frozen", static_cast<double>(counts.frozen)},
          {"odom_lines_removed", static_cast<double>(counts.removed)},
          {"max_catch_up_m", counts.max_catch_up_m},
          {"max_catch_up_rad", counts.max_catch_up_rad}};
}

// Eq. (1): T'_k = T'_{k-1} * rule(T_{k-1}^-1 T_k) along each chain, from the log's first
// odometry pose. Returns the number of poses changed.
std::size_t reintegrate(Messages& messages, const std::function<SE2(const SE2&)>& rule) {
  const auto first = std::find_if(messages.begin(), messages.end(), [](const SensorMessage& m) { return chain_of(m).has_value(); });
  if (!rule || first == messages.end()) return 0;
  const SE2 anchor = odometry_pose(*first);
  std::array<SE2, 2> previous_original = {anchor, anchor};
  std::array<SE2, 2> previous_new = {anchor, anchor};
  std::size_t changed = 0;
  for (SensorMessage& message : messages) {
    const std::optional<Chain> chain = chain_of(message);
    if (!chain) continue;
    const SE2 pose = odometry_pose(message);
    previous_new[*chain] = previous_new[*chain] * rule(previous_original[*chain].between(pose));
    previous_original[*chain] = pose;
    if (!(previous_new[*chain] == pose)) {
      set_odometry_pose(message, previous_new[*chain]);
      ++changed;
    }
  }
  return changed;
}

Changes reintegrate_with_report(Messages& messages, const std::function<SE2(const SE2&)>& rule) {
  const double before = laser_path_length(messages);
  const std::size_t changed = reintegrate(messages, rule);
  return {{"odometry_poses_changed", static_cast<double>(changed)},
          {"laser_path_length_before_m", before},
          {"laser_path_length_after_m", laser_path_length(messages)}};
}

Changes apply(const StallFault& fault, Messages& messages, Rng&) {
  return hold_changes(hold_odometry(messages, fault.windows, false), "stalls");
}

Changes apply(const OdomGapFault& fault, Messages& messages, Rng&) {
  return hold_changes(hold_odometry(messages, fault.windows, true), "gaps");
}

Changes apply(const OdomResetFault& fault, Messages& messages, Rng&) {
  const double t0 = messages.empty() ? 0.0 : stamp_of(messages.front());
  // The restart a stamp comes after (-1: before the first).
  const auto restart = [&](double stamp) {
    const double since_start = stamp - t0 - fault.start;
    return since_start >= 0.0 ? static_cast<long>(std::floor(since_start / fault.every)) : -1L;
  };
  struct ChainState {
    long restart = -1;
    SE2 T_origin_odom;  // the current odometry frame in the logged one's
  };
  std::array<ChainState, 2> states;
  std::set<long> restarts;
  std::size_t changed = 0;
  double max_jump_m = 0.0;
  for (SensorMessage& message : messages) {
    const std::optional<Chain> chain = chain_of(message);
    if (!chain) continue;
    ChainState& state = states[*chain];
    const SE2 pose = odometry_pose(message);
    const long m = restart(stamp_of(message));
    if (m > state.restart) {  // the first pose after a restart is the new origin
      if (*chain == kLaserChain) max_jump_m = std::max(max_jump_m, state.T_origin_odom.between(pose).translation().norm());
      state.restart = m;
      state.T_origin_odom = pose;
      restarts.insert(m);
    }
    if (state.restart < 0) continue;
    set_odometry_pose(message, state.T_origin_odom.between(pose));
    ++changed;
  }
  return {{"restarts", static_cast<double>(restarts.size())},
          {"odometry_poses_changed", static_cast<double>(changed)},
          {"max_restart_jump_m", max_jump_m}};
}

Changes apply(const WheelScaleFault& fault, Messages& messages, Rng&) {
  if (fault.translation == 1.0 && fault.rotation == 1.0) return reintegrate_with_report(messages, nullptr);
  return reintegrate_with_report(messages, [&fault](const SE2& increment) {
    return SE2(Eigen::Vector2d(fault.translation * increment.translation()), fault.rotation * increment.theta());
  });
}

Changes apply(const HeadingDriftFault& fault, Messages& messages, Rng&) {
  if (fault.rate_deg_per_m == 0.0) return reintegrate_with_report(messages, nullptr);
  const double rate = deg_to_rad(fault.rate_deg_per_m);  // rad per metre
  return reintegrate_with_report(messages, [rate](const SE2& increment) {
    return SE2(increment.translation(), increment.theta() + rate * increment.x());
  });
}

// A Brownian motion W(s), s >= 0: W(0) = 0, W(s + step) - W(s) ~ N(0, sigma^2 step), linear
// between the samples. The samples are drawn in order of s, however W is asked, so every query
// of the same s gives the same value.
class RandomWalk {
 public:
  RandomWalk(Rng rng, double sigma, double step) : rng_(std::move(rng)), sigma_step_(sigma * std::sqrt(step)), step_(step) {}

  double operator()(double s) {
    const double position = s / step_;
    const auto i = static_cast<std::size_t>(position);
    while (samples_.size() < i + 2) samples_.push_back(samples_.back() + sigma_step_ * rng_.gaussian());
    const double fraction = position - static_cast<double>(i);
    return samples_[i] + fraction * (samples_[i + 1] - samples_[i]);
  }

 private:
  Rng rng_;
  double sigma_step_;
  double step_;
  std::vector<double> samples_{0.0};
};

// The leading chain (the laser chain; the ODOM chain when no laser line carries odometry, as in a
// bag) is re-integrated (Eq. 1) with noisy increments: the increment from s to s + d travelled
// (and r to r + |dtheta| turned) gets the along-track error W_t(s + d) - W_t(s) and the heading
// error W_h(s + d) - W_h(s) + W_r(r + |dtheta|) - W_r(r). Every other odometry pose T gets the
// correction C T, with C = T' T^-1 of the leading chain's message nearest in stamp among the one
// before and the one after it in file order: the chains stay one odometry.
Changes apply(const OdomNoiseFault& fault, Messages& messages, Rng& rng) {
  if (fault.translation == 0.0 && fault.heading == 0.0 && fault.rotation == 0.0) return reintegrate_with_report(messages, nullptr);
  const double length_before = laser_path_length(messages);
  const bool has_laser_chain =
      std::any_of(messages.begin(), messages.end(), [](const SensorMessage& m) { return chain_of(m) == kLaserChain; });
  const Chain leader = has_laser_chain ? kLaserChain : kOdomChain;
  constexpr double kStep = 0.01;  // m and rad between the walks' samples
  RandomWalk along(rng.split(0), fault.translation, kStep);
  RandomWalk heading(rng.split(1), fault.heading, kStep);
  RandomWalk turning(rng.split(2), fault.rotation, kStep);
  // Pass 1: the leading chain, and its corrections C = T' T^-1 by message index.
  std::vector<std::pair<std::size_t, SE2>> corrections;
  std::optional<SE2> previous_original, previous_new;
  double travelled = 0.0, turned = 0.0;  // m, rad
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (chain_of(messages[i]) != leader) continue;
    const SE2 pose = odometry_pose(messages[i]);
    if (!previous_original) {
      previous_new = pose;
    } else {
      const SE2 increment = previous_original->between(pose);
      const double d = increment.translation().norm();
      const double s = travelled, r = turned;
      travelled += d;
      turned += std::abs(increment.theta());
      const double error_along = along(travelled) - along(s);
      const double error_heading = heading(travelled) - heading(s) + turning(turned) - turning(r);
      const Eigen::Vector2d t = d > 0.0 ? Eigen::Vector2d((1.0 + error_along / d) * increment.translation()) : increment.translation();
      previous_new = *previous_new * SE2(t, increment.theta() + error_heading);
    }
    previous_original = pose;
    corrections.emplace_back(i, *previous_new * pose.inverse());
  }
  // Pass 2: every odometry pose gets its correction.
  std::size_t changed = 0;
  std::size_t next = 0;  // the first leading message at or after i
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (!chain_of(messages[i]) || corrections.empty()) continue;
    while (next < corrections.size() && corrections[next].first < i) ++next;
    const SE2 pose = odometry_pose(messages[i]);
    SE2 correction;
    if (next < corrections.size() && corrections[next].first == i) {
      correction = corrections[next].second;
    } else if (next == 0) {
      correction = corrections.front().second;
    } else if (next == corrections.size()) {
      correction = corrections.back().second;
    } else {
      const double stamp = stamp_of(messages[i]);
      const double before = std::abs(stamp - stamp_of(messages[corrections[next - 1].first]));
      const double after = std::abs(stamp_of(messages[corrections[next].first]) - stamp);
      correction = (after < before ? corrections[next] : corrections[next - 1]).second;
    }
    const SE2 new_pose = correction * pose;
    if (new_pose == pose) continue;
    set_odometry_pose(messages[i], new_pose);
    ++changed;
  }
  return {{"odometry_poses_changed", static_cast<double>(changed)},
          {"laser_path_length_before_m", length_before},
          {"laser_path_length_after_m", laser_path_length(messages)}};
}

// Both odometry chains (core/odometry_chain.hpp has their clock and the shift along it).
std::array<OdometryChain, 2> odometry_chains(const Messages& messages) {
  std::array<std::vector<ChainSample>, 2> samples;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (const std::optional<Chain> chain = chain_of(messages[i])) samples[*chain].push_back({i, stamp_of(messages[i]), odometry_pose(messages[i])});
  }
  return {OdometryChain(std::move(samples[kLaserChain])), OdometryChain(std::move(samples[kOdomChain]))};
}

Changes apply(const OdomShiftFault& fault, Messages& messages, Rng&) {
  std::size_t shifted = 0;
  double largest_m = 0.0;  // the laser chain's largest pose change
  const std::array<OdometryChain, 2> chains = odometry_chains(messages);
  for (std::size_t c = 0; c < chains.size(); ++c) {
    const OdometryChain& chain = chains[c];
    for (std::size_t k = 0; k < chain.size(); ++k) {
      const SE2 pose = chain.shifted(k, fault.by);
      if (pose == chain[k].pose) continue;
      set_odometry_pose(messages[chain[k].message], pose);
      ++shifted;
      if (c == kLaserChain) largest_m = std::max(largest_m, (pose.translation() - chain[k].pose.translation()).norm());
    }
  }
  return {{"odometry_poses_shifted", static_cast<double>(shifted)}, {"max_pose_change_m", largest_m}};
}

// ---------------------------------------------------------------------------------------------
// Timing faults.

Changes apply(const ScanGapFault& fault, Messages& messages, Rng&) {
  const WindowClock clock(messages, fault.windows);
  std::vector<bool> keep(messages.size(), true);
  std::set<long> windows;
  std::size_t removed = 0;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    if (!std::holds_alternative<LaserMessage>(messages[i])) continue;
    if (const std::optional<long> window = clock.window(stamp_of(messages[i]))) {
      keep[i] = false;
      windows.insert(*window);
      ++removed;
    }
  }
  remove_marked(messages, keep);
  return {{"gaps", static_cast<double>(windows.size())}, {"laser_lines_removed", static_cast<double>(removed)}};
}

// Removes the laser lines that keep(laser, state) refuses, each laser type with its own State
// (State{} at its first line). Returns the change "laser_lines_removed".
template <typename State, typename Keep>
Changes thin_laser_lines(Messages& messages, Keep&& keep) {
  std::vector<bool> kept(messages.size(), true);
  std::vector<std::pair<std::string, State>> states;  // laser type -> its state
  std::size_t removed = 0;
  for (std::size_t i = 0; i < messages.size(); ++i) {
    const auto* laser = std::get_if<LaserMessage>(&messages[i]);
    if (laser == nullptr) continue;
    auto it = std::find_if(states.begin(), states.end(), [&](const auto& s) { return s.first == laser->type; });
    if (it == states.end()) it = states.insert(states.end(), {laser->type, State{}});
    kept[i] = keep(*laser, it->second);
    removed += kept[i] ? 0 : 1;
  }
  remove_marked(messages, kept);
  return {{"laser_lines_removed", static_cast<double>(removed)}};
}

Changes apply(const DecimateFault& fault, Messages& messages, Rng&) {
  return thin_laser_lines<std::size_t>(messages, [&](const LaserMessage&, std::size_t& seen) { return seen++ % fault.k == 0; });
}

// A stamp that steps back (Intel) is within 1/hz of the last kept one, so it is dropped.
Changes apply(const ScanRateFault& fault, Messages& messages, Rng&) {
  constexpr double kSlack = 1e-6;  // s, below the microseconds stamps are written in: 0.3 - 0.2 < 0.1 in doubles
  const double period = 1.0 / fault.hz;
  return thin_laser_lines<std::optional<double>>(messages, [&](const LaserMessage& laser, std::optional<double>& last_kept) {
    if (last_kept && laser.scan.stamp - *last_kept < period - kSlack) return false;
    last_kept = laser.scan.stamp;
    return true;
  });
}

Changes apply(const JitterFault& fault, Messages& messages, Rng& rng) {
  std::size_t changed = 0;
  double largest = 0.0;
  for_each_laser(messages, [&](LaserMessage& laser) {
    const double shift = rng.gaussian(0.0, fault.sigma);
    laser.scan.stamp += shift;
    changed += shift != 0.0 ? 1 : 0;
    largest = std::max(largest, std::abs(shift));
  });
  return {{"laser_stamps_changed", static_cast<double>(changed)}, {"max_shift_s", largest}};
}

Changes apply(const DuplicateFault& fault, Messages& messages, Rng& rng) {
  Messages out;
  out.reserve(messages.size());
  std::size_t duplicated = 0;
  for (SensorMessage& message : messages) {
    const bool twice = std::holds_alternative<LaserMessage>(message) && rng.bernoulli(fault.p);
    out.push_back(std::move(message));
    if (twice) {
      out.push_back(out.back());
      ++duplicated;
    }
  }
  messages = std::move(out);
  return {{"laser_lines_duplicated", static_cast<double>(duplicated)}};
}

Changes apply(const BackwardsFault& fault, Messages& messages, Rng& rng) {
  std::size_t moved = 0;
  for_each_laser(messages, [&](LaserMessage& laser) {
    if (!rng.bernoulli(fault.p)) return;
    laser.scan.stamp -= fault.by;
    ++moved;
  });
  return {{"laser_stamps_moved_back", static_cast<double>(moved)}};
}

// ---------------------------------------------------------------------------------------------
// Range faults.

bool is_valid_reading(const LaserScan& scan, double range) {
  return std::isfinite(range) && range >= scan.range_min && range < scan.range_max;
}

// Calls change(laser, logged) for every laser line, `logged` its ranges before; counts the
// readings it changed.
template <typename Change>
Changes change_scans(Messages& messages, Change&& change) {
  std::size_t changed = 0;
  std::size_t readings = 0;
  for_each_laser(messages, [&](LaserMessage& laser) {
    const std::vector<double> logged = laser.scan.ranges;
    change(laser, logged);
    for (std::size_t k = 0; k < logged.size(); ++k) changed += laser.scan.ranges[k] != logged[k] ? 1 : 0;
    readings += logged.size();
  });
  return {{"readings_changed", static_cast<double>(changed)}, {"readings", static_cast<double>(readings)}};
}

// Calls change(scan, range) for every reading; it returns the new range. Counts the changes.
template <typename Change>
Changes change_readings(Messages& messages, Change&& change) {
  return change_scans(messages, [&](LaserMessage& laser, const std::vector<double>&) {
    for (double& range : laser.scan.ranges) range = change(laser.scan, range);
  });
}

// A valid reading plus N(0, sigma^2), clamped at 0; a no-return stays one.
double noisy_range(const LaserScan& scan, double range, double sigma, Rng& rng) {
  if (!is_valid_reading(scan, range)) return range;
  return std::max(0.0, range + rng.gaussian(0.0, sigma));
}

Changes apply(const RangeNoiseFault& fault, Messages& messages, Rng& rng) {
  return change_readings(messages, [&](const LaserScan& scan, double range) { return noisy_range(scan, range, fault.sigma, rng); });
}

Changes apply(const SpuriousMaxFault& fault, Messages& messages, Rng& rng) {
  return change_readings(messages, [&](const LaserScan& scan, double range) {
    const bool spurious = rng.bernoulli(fault.p);  // drawn for every reading: the pattern ignores validity
    return spurious && is_valid_reading(scan, range) ? scan.range_max : range;
  });
}

Changes apply(const SpuriousShortFault& fault, Messages& messages, Rng& rng) {
  return change_readings(messages, [&](const LaserScan&, double range) {
    return rng.bernoulli(fault.p) ? rng.uniform(fault.min, fault.max) : range;
  });
}

// Where a laser line is, for messages: "FLASER (line 12)".
std::string where(const LaserMessage& laser) { return laser.type + " (line " + std::to_string(laser.line) + ")"; }

Changes apply(const SpuriousFarFault& fault, Messages& messages, Rng& rng) {
  for_each_laser(messages, [&](LaserMessage& laser) {
    if (!(fault.min < laser.scan.range_max)) {
      throw Error("spurious-far: min=" + format_number(fault.min) + " m is not below the maximum range " +
                  format_number(laser.scan.range_max) + " m of " + where(laser));
    }
  });
  return change_readings(messages, [&](const LaserScan& scan, double range) {
    if (!rng.bernoulli(fault.p)) return range;
    const double far = rng.uniform(fault.min, std::min(fault.max, scan.range_max));  // drawn whatever the reading
    // uniform(a, b) can round up to b: stay a return
    return is_valid_reading(scan, range) ? std::min(far, std::nextafter(scan.range_max, 0.0)) : range;
  });
}

// Mixed pixels. The edges are found on the logged readings, so one edge's changes do not make
// or hide another's.
Changes apply(const MixedPixelsFault& fault, Messages& messages, Rng& rng) {
  std::size_t edges = 0;
  std::size_t mixed = 0;
  Changes changes = change_scans(messages, [&](LaserMessage& laser, const std::vector<double>& logged) {
    const LaserScan& scan = laser.scan;
    std::vector<double>& ranges = laser.scan.ranges;
    const auto n = static_cast<std::ptrdiff_t>(logged.size());
    for (std::ptrdiff_t k = 0; k + 1 < n; ++k) {
      const double a = logged[k], b = logged[k + 1];
      if (!is_valid_reading(scan, a) || !is_valid_reading(scan, b) || !(std::abs(a - b) > fault.jump)) continue;
      ++edges;
      if (!rng.bernoulli(fault.p)) continue;
      ++mixed;
      const double near = std::min(a, b);
      const std::ptrdiff_t step = b > a ? 1 : -1;  // from the edge into the far side
      const std::ptrdiff_t first = b > a ? k + 1 : k;
      if (fault.alternate == 0) {
        ranges[first] = rng.uniform(near, std::max(a, b));
        continue;
      }
      for (std::ptrdiff_t j = 0; j < static_cast<std::ptrdiff_t>(fault.alternate); ++j) {
        const std::ptrdiff_t beam = first + j * step;
        if (beam < 0 || beam >= n || !is_valid_reading(scan, logged[beam]) || !(logged[beam] > near + fault.jump)) break;
        if (j % 2 == 0) ranges[beam] = near;
      }
    }
  });
  changes.insert(changes.begin(), {{"edges", static_cast<double>(edges)}, {"edges_mixed", static_cast<double>(mixed)}});
  return changes;
}

// Glass: a reading whose bearing in the odometry frame (heading + mounting + beam angle) lies in
// a sector becomes a no-return. Sectors fixed on the scanner would be a narrower field of view
// (fov); fixed in the world they sweep across the scans as the robot turns, as panes do.
Changes apply(const GlassFault& fault, Messages& messages, Rng& rng) {
  std::vector<double> centres(fault.sectors);  // rad, in the odometry frame
  for (double& centre : centres) centre = rng.uniform(-std::numbers::pi, std::numbers::pi);
  const double half = 0.5 * deg_to_rad(fault.width_deg);
  Changes changes = change_scans(messages, [&](LaserMessage& laser, const std::vector<double>&) {
    LaserScan& scan = laser.scan;
    const double heading = (laser.has_poses ? laser.odom_pose.theta() : 0.0) + scan.T_robot_sensor.theta();
    for (std::size_t k = 0; k < scan.size(); ++k) {
      const double bearing = heading + scan.angle(k);
      const bool behind_glass = std::any_of(centres.begin(), centres.end(), [&](double centre) {
        return std::abs(angle_difference(bearing, centre)) <= half;
      });
      if (behind_glass) scan.ranges[k] = scan.range_max;
    }
  });
  for (std::size_t s = 0; s < centres.size(); ++s) {
    changes.emplace_back("sector_" + std::to_string(s + 1) + "_deg", rad_to_deg(centres[s]));
  }
  return changes;
}

// The range along the fractional beam index `position` of the logged ranges: linear between two
// neighbouring valid readings on one surface, the nearer beam's across an edge or a no-return (no
// point made up between two surfaces), the end beam's beyond the ends.
double resampled_range(const LaserScan& scan, const std::vector<double>& logged, double position) {
  const double edge = MixedPixelsFault{}.jump;  // m, the depth step that makes an edge
  position = std::clamp(position, 0.0, static_cast<double>(logged.size() - 1));
  const auto i = static_cast<std::size_t>(position);
  if (i + 1 >= logged.size()) return logged.back();
  const double f = position - static_cast<double>(i);
  const double a = logged[i], b = logged[i + 1];
  if (!is_valid_reading(scan, a) || !is_valid_reading(scan, b) || std::abs(a - b) > edge) return f < 0.5 ? a : b;
  return a + f * (b - a);
}

// A noisy laser: each scan as a scanner turned by delta ~ N(0, bearing^2) measures it (beam k
// reads the range along angle(k) + delta, so its points turn by -delta), then range noise.
Changes apply(const LaserNoiseFault& fault, Messages& messages, Rng& rng) {
  Rng turns = rng.split(0);
  Rng noise = rng.split(1);
  const double sigma_rad = deg_to_rad(fault.bearing_deg);
  double largest = 0.0;  // rad
  Changes changes = change_scans(messages, [&](LaserMessage& laser, const std::vector<double>& logged) {
    LaserScan& scan = laser.scan;
    const double delta = turns.gaussian(0.0, sigma_rad);
    largest = std::max(largest, std::abs(delta));
    if (delta != 0.0 && scan.size() > 1 && scan.angle_increment != 0.0) {
      for (std::size_t k = 0; k < scan.size(); ++k) {
        scan.ranges[k] = resampled_range(scan, logged, static_cast<double>(k) + delta / scan.angle_increment);
      }
    }
    for (double& range : scan.ranges) range = noisy_range(scan, range, fault.sigma, noise);
  });
  changes.emplace_back("max_turn_deg", rad_to_deg(largest));
  return changes;
}

// ---------------------------------------------------------------------------------------------
// Geometry faults. FLASER/RLASER keep their first beam at -field_of_view / 2, the geometry that
// PARAM lines declare (io/carmen_log.hpp).

bool is_old_laser(const LaserMessage& laser) { return laser.type == "FLASER" || laser.type == "RLASER"; }

// Keeps beams first, first + step, ... (up to `count` of them) and their intensities.
void keep_beams(LaserScan& scan, std::size_t first, std::size_t step, std::size_t count) {
  const auto select = [&](std::vector<double>& values) {
    if (values.empty()) return;
    for (std::size_t j = 0; j < count; ++j) values[j] = values[first + j * step];
    values.resize(count);
  };
  scan.angle_min = scan.angle(first);
  scan.angle_increment *= static_cast<double>(step);
  select(scan.ranges);
  select(scan.intensities);
}

Changes apply(const BeamsFault& fault, Messages& messages, Rng&) {
  std::size_t removed = 0;
  for_each_laser(messages, [&](LaserMessage& laser) {
    const std::size_t n = laser.scan.size();
    const std::size_t kept = (n + fault.k - 1) / fault.k;
    if (fault.k == 1 || n == 0) return;
    keep_beams(laser.scan, 0, fault.k, kept);
    removed += n - kept;
  });
  return {{"beams_removed", static_cast<double>(removed)}};
}

Changes apply(const FovFault& fault, Messages& messages, Rng&) {
  constexpr double kTolerance = 1e-9;  // rad, a beam on the edge is kept
  const double half = 0.5 * deg_to_rad(fault.deg);
  std::size_t removed = 0;
  for_each_laser(messages, [&](LaserMessage& laser) {
    LaserScan& scan = laser.scan;
    const std::size_t n = scan.size();
    std::size_t first = 0;
    while (first < n && scan.angle(first) < -half - kTolerance) ++first;
    std::size_t end = first;
    while (end < n && scan.angle(end) <= half + kTolerance) ++end;
    if (end == first) throw Error("fov: deg=" + format_number(fault.deg) + " keeps no beam of " + where(laser));
    if (first == 0 && end == n) return;
    keep_beams(scan, first, 1, end - first);
    removed += n - (end - first);
    if (!is_old_laser(laser)) {
      laser.field_of_view = std::min(laser.field_of_view, deg_to_rad(fault.deg));
    } else if (scan.angle_min < 0.0) {
      laser.field_of_view = -2.0 * scan.angle_min;
    } else {
      throw Error("fov: deg=" + format_number(fault.deg) + " keeps no beam left of the axis of " + where(laser) +
                  "; PARAM lines declare a first beam at -fov/2 < 0");
    }
  });
  return {{"beams_removed", static_cast<double>(removed)}};
}

Changes apply(const RangeMaxFault& fault, Messages& messages, Rng&) {
  for_each_laser(messages, [&](LaserMessage& laser) {
    if (fault.max > laser.scan.range_max) {
      throw Error("range-max: max=" + format_number(fault.max) + " m is beyond the maximum range " +
                  format_number(laser.scan.range_max) + " m of " + where(laser));
    }
  });
  Changes changes = change_readings(messages, [&](const LaserScan&, double range) {
    return range >= fault.max ? fault.max : range;
  });
  for_each_laser(messages, [&](LaserMessage& laser) { laser.scan.range_max = fault.max; });
  return changes;
}

void shift_stamp(SensorMessage& message, double by) {
  struct Shift {
    double by;
    void operator()(LaserMessage& m) const { m.scan.stamp += by; }
    void operator()(OdometryMessage& m) const { m.reading.stamp += by; }
    void operator()(TruePoseMessage& m) const { m.stamp += by; }
    void operator()(ImuMessage& m) const { m.reading.stamp += by; }
  };
  std::visit(Shift{by}, message);
}

// The message as the robot driving backwards would record it, at stamp `mirror` - stamp: the same
// poses and ranges, velocities and the yaw rate negated.
void reverse_in_time(SensorMessage& message, double mirror) {
  struct Reverse {
    double mirror;
    void operator()(LaserMessage& m) const { m.scan.stamp = mirror - m.scan.stamp; }
    void operator()(OdometryMessage& m) const {
      m.reading.stamp = mirror - m.reading.stamp;
      m.reading.tv = -m.reading.tv;
      m.reading.rv = -m.reading.rv;
    }
    void operator()(TruePoseMessage& m) const { m.stamp = mirror - m.stamp; }
    void operator()(ImuMessage& m) const {
      m.reading.stamp = mirror - m.reading.stamp;
      m.reading.yaw_rate = -m.reading.yaw_rate;
    }
  };
  std::visit(Reverse{mirror}, message);
}

// The median gap between consecutive laser stamps (0.1 s without two scans).
double median_laser_period(const Messages& messages) {
  std::vector<double> gaps;
  std::optional<double> previous;
  for (const SensorMessage& message : messages) {
    if (const auto* laser = std::get_if<LaserMessage>(&message)) {
      if (previous && laser->scan.stamp > *previous) gaps.push_back(laser->scan.stamp - *previous);
      previous = laser->scan.stamp;
    }
  }
  if (gaps.empty()) return 0.1;
  std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2), gaps.end());
  return gaps[gaps.size() / 2];
}

Changes apply(const RepeatFault& fault, Messages& messages, Rng&) {
  if (messages.empty() || fault.times == 1) return {{"copies", 1.0}};
  double first = stamp_of(messages.front());
  double last = first;
  for (const SensorMessage& message : messages) {
    first = std::min(first, stamp_of(message));
    last = std::max(last, stamp_of(message));
  }
  const double period = (last - first) + median_laser_period(messages);
  const std::size_t n = messages.size();
  messages.reserve(n * fault.times);
  for (std::size_t copy = 1; copy < fault.times; ++copy) {
    const double start = static_cast<double>(copy) * period;  // the copy's first stamp, less `first`
    if (fault.back && copy % 2 == 1) {  // backwards: the last message first, at the copy's start
      for (std::size_t i = n; i-- > 0;) {
        messages.push_back(messages[i]);
        reverse_in_time(messages.back(), first + last + start);
      }
    } else {
      for (std::size_t i = 0; i < n; ++i) {
        messages.push_back(messages[i]);
        shift_stamp(messages.back(), start);
      }
    }
  }
  return {{"copies", static_cast<double>(fault.times)}, {"period_s", period}};
}

}  // namespace

std::vector<std::string> fault_kinds() {
  std::vector<std::string> kinds;
  for (const auto& [name, parser] : fault_table()) kinds.push_back(name);
  return kinds;
}

Fault parse_fault(std::string_view spec) {
  const std::size_t colon = std::min(spec.find(':'), spec.size());
  const std::string kind(spec.substr(0, colon));
  const std::string_view parameters = colon < spec.size() ? spec.substr(colon + 1) : std::string_view();
  const auto& table = fault_table();
  const auto entry = std::find_if(table.begin(), table.end(), [&](const auto& e) { return e.first == kind; });
  if (entry == table.end()) {
    std::string kinds;
    for (const std::string& name : fault_kinds()) kinds += (kinds.empty() ? "" : ", ") + name;
    throw Error("--fault '" + std::string(spec) + "': unknown fault kind '" + kind + "' (kinds: " + kinds + ")");
  }
  SpecArguments arguments(std::string(spec), kind, parameters);
  const Fault fault = entry->second(arguments);
  arguments.finish();
  return fault;
}

std::string fault_spec(const Fault& fault) {
  const auto [kind, values] = std::visit([](const auto& f) { return parameters(f); }, fault);
  std::string spec = kind;
  for (std::size_t i = 0; i < values.size(); ++i) {
    spec += (i == 0 ? ":" : ",") + values[i].first + "=" + format_number(values[i].second);
  }
  return spec;
}

FaultReport apply_fault(const Fault& fault, std::vector<SensorMessage>& messages, Rng& rng) {
  FaultReport report;
  report.spec = fault_spec(fault);
  report.changes = std::visit([&](const auto& f) { return apply(f, messages, rng); }, fault);
  return report;
}

std::vector<FaultReport> apply_faults(const std::vector<Fault>& faults, std::vector<SensorMessage>& messages,
                                      std::uint64_t seed) {
  std::vector<FaultReport> reports;
  for (std::size_t i = 0; i < faults.size(); ++i) {
    Rng rng = Rng(seed).split(i);
    reports.push_back(apply_fault(faults[i], messages, rng));
  }
  return reports;
}

}  // namespace slam2d
