// SPDX-License-Identifier: BSD-3-Clause
// Reader for CARMEN 0.7 logger files (carmen/src/logger, "message formats defined: ...").
//
// Every message ends in "ipc_timestamp ipc_hostname logger_timestamp"; old logs may stop after
// ipc_timestamp (or after the hostname), so 1 to 3 trailing fields are accepted. The ipc timestamp
// is the message's stamp. Numbers are parsed strictly (std::from_chars, whole token, finite;
// ranges also non-negative). The reader holds one line at a time.
//
// CARMEN parameters used for the old FLASER/RLASER messages (carmen.ini names; front / rear):
//   laser_front_laser_fov          / laser_rear_laser_fov           field of view, degrees
//   laser_front_laser_resolution   / laser_rear_laser_resolution    angle between beams, degrees
//   robot_frontlaser_offset        / robot_rearlaser_offset         x of the sensor on the robot, m
//   robot_frontlaser_side_offset   / robot_rearlaser_side_offset    y of the sensor on the robot, m
//   robot_frontlaser_angular_offset/ robot_rearlaser_angular_offset sensor yaw on the robot, rad
//   robot_front_laser_max          / robot_rear_laser_max           maximum range, m
// laser_frontlaser_fov/_resolution and laser_rearlaser_fov/_resolution (the robot_ spelling, seen
// in the FHW log) are read as aliases: the beam-count check below catches a wrong value either way.
// Offsets are taken in the robot frame (x forward, y left), so a rear scanner behind the centre
// has a negative robot_rearlaser_offset. The rear scanner faces backwards: its yaw is
// robot_rearlaser_angular_offset + pi.
//
// The geometry check (docs/sensor_geometry.md). A PARAM line comes before the lasers, but the
// beam count n is known only at a laser line, so the geometry is decided at the first FLASER
// (RLASER) line of each beam count and kept for the lines that follow, until a PARAM line changes
// that laser's geometry. With s = n - 1 steps for odd n (beams at both ends) and s = n otherwise:
//   consistent:   |n x increment - field_of_view| <= increment (+ the rounding of the printed fov)
//   no PARAM:     the convention, 180 deg and increment = 180 deg / s
//   fov only:     increment = fov / s; the fov in degrees, or in radians when that is 180 deg
//   resolution:   fov = 180 deg if consistent, else s x increment
//   both:         the unit reading (degrees, or radians for a value <= 2 pi) that is consistent
// A unit is guessed only when one reading fits and the other does not, or, as both in degrees
// and both in radians always fit together, when the convention's 180 deg picks one of them.
// PARAM lines that fit in no unit fall back to the convention (with a warning) when it agrees
// with one of them; otherwise the log is wrong and the error names the PARAM's line. An option
// (override) beats a PARAM; a PARAM that contradicts an override is dropped with a warning.
// angle_min is -fov / 2 unless overridden.

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/core.h>

#include "slam2d/core/angles.hpp"
#include "slam2d/core/error.hpp"
#include "slam2d/core/odometry_repair.hpp"
#include "slam2d/io/carmen.hpp"
#include "slam2d/io/input_limits.hpp"
#include "slam2d/io/detail/number_format.hpp"
#include "slam2d/io/detail/text_input.hpp"

namespace slam2d {

namespace {

// ---------------------------------------------------------------------------------------------
// Tokens and numbers.

// Why `token` (parsed as `value`) is not a finite number; empty when it is one.
std::string number_problem(std::string_view token, const std::optional<double>& value) {
  if (!value) return "is not a number: '" + std::string(token) + "'";
  if (std::isnan(*value)) return "is NaN";
  if (std::isinf(*value)) return "is infinite or out of range: '" + std::string(token) + "'";
  return {};
}

// ---------------------------------------------------------------------------------------------
// One line's fields, with error messages that name the message type and the field.

class Fields {
 public:
  Fields(const LineReader& reader, const std::vector<std::string_view>& tokens)
      : reader_(reader), tokens_(tokens) {}

  std::size_t size() const { return tokens_.size(); }
  std::string_view type() const { return tokens_[0]; }
  std::string_view token(std::size_t i) const { return tokens_[i]; }

  [[noreturn]] void fail(const std::string& message) const {
    reader_.fail(std::string(type()) + ": " + message);
  }

  /// A finite number.
  double number(std::size_t i, std::string_view name) const {
    const std::optional<double> value = parse_double(tokens_[i]);
    const std::string problem = number_problem(tokens_[i], value);
    if (!problem.empty()) fail(std::string(name) + " " + problem);
    return *value;
  }

  /// A count of beams: a count within max_beams.
  std::size_t beams(std::size_t i, std::string_view name) const {
    const std::size_t n = count(i, name);
    if (n > input_limits().max_beams) {
      fail(std::string(name) + " " + std::to_string(n) + " is over max_beams (" + std::to_string(input_limits().max_beams) +
           "; " + limit_hint("max_beams") + ")");
    }
    return n;
  }

  /// A count (a non-negative integer).
  std::size_t count(std::size_t i, std::string_view name) const {
    const std::string_view t = tokens_[i];
    std::size_t value = 0;
    const auto [ptr, ec] = std::from_chars(t.data(), t.data() + t.size(), value);
    if (ec != std::errc() || ptr != t.data() + t.size()) {
      fail(std::string(name) + " is not a count: '" + std::string(t) + "'");
    }
    return value;
  }

  /// `n` values starting at token `first`: finite, and non-negative unless `allow_negative`.
  std::vector<double> values(std::size_t first, std::size_t n, std::string_view name,
                             bool allow_negative) const {
    std::vector<double> out(n);
    for (std::size_t k = 0; k < n; ++k) {
      const std::string_view t = tokens_[first + k];
      const std::optional<double> value = parse_double(t);
      const std::string problem = number_problem(t, value);
      if (!problem.empty()) fail(value_name(name, k, n) + " " + problem);
      out[k] = *value;
      if (!allow_negative && out[k] < 0.0) fail(value_name(name, k, n) + " is negative: " + std::string(t));
    }
    return out;
  }

  SE2 pose(std::size_t i, std::string_view prefix) const {
    const std::string p(prefix);
    return SE2(number(i, p + "x"), number(i + 1, p + "y"), number(i + 2, p + "theta"));
  }

  /// The trailing "ipc_timestamp [ipc_hostname [logger_timestamp]]" from token `i`; returns the stamp.
  double stamp_tail(std::size_t i) const {
    const double stamp = number(i, "ipc_timestamp");
    if (i + 2 < tokens_.size()) number(i + 2, "logger_timestamp");
    return stamp;
  }

 private:
  static std::string value_name(std::string_view name, std::size_t k, std::size_t n) {
    return std::string(name) + " " + std::to_string(k + 1) + " of " + std::to_string(n);
  }

  const LineReader& reader_;
  const std::vector<std::string_view>& tokens_;
};

constexpr std::size_t kMinTail = 1;  // ipc_timestamp
constexpr std::size_t kMaxTail = 3;  // ipc_timestamp ipc_hostname logger_timestamp

bool tail_fits(std::size_t available, std::size_t fixed) {
  return available >= fixed + kMinTail && available <= fixed + kMaxTail;
}

// ---------------------------------------------------------------------------------------------
// Geometry of the old FLASER/RLASER messages: PARAM lines as written.

struct DeclaredParam {
  std::string name;       // as written (an alias stays an alias)
  std::string canonical;  // the carmen.ini name it stands for
  std::string token;      // the value as written
  double value = 0.0;     // in the unit it was written in (unknown for angles until checked)
  double rounding = 0.0;  // half a unit of its last printed decimal; 0 for an integer
  std::size_t line = 0;
};

struct OldLaserParams {
  std::optional<DeclaredParam> field_of_view;  // CARMEN: degrees
  std::optional<DeclaredParam> resolution;     // CARMEN: degrees
  std::optional<DeclaredParam> range_max;      // m
  double offset_x = 0.0;                       // m
  double offset_y = 0.0;                       // m
  double offset_theta = 0.0;                   // rad
  std::map<std::size_t, std::size_t> decided;  // beams -> index in CarmenStats::old_laser_geometries
};

enum class ParamKind { kFieldOfView, kResolution, kRangeMax, kOffsetX, kOffsetY, kOffsetTheta };

struct ParamBinding {
  std::string_view name;
  bool rear;
  ParamKind kind;
  std::string_view canonical;  // the carmen.ini name when `name` is an alias, else empty
};

constexpr ParamBinding kParamBindings[] = {
    {"laser_front_laser_fov", false, ParamKind::kFieldOfView, ""},
    {"laser_front_laser_resolution", false, ParamKind::kResolution, ""},
    {"laser_frontlaser_fov", false, ParamKind::kFieldOfView, "laser_front_laser_fov"},
    {"laser_frontlaser_resolution", false, ParamKind::kResolution, "laser_front_laser_resolution"},
    {"robot_front_laser_max", false, ParamKind::kRangeMax, ""},
    {"robot_frontlaser_offset", false, ParamKind::kOffsetX, ""},
    {"robot_frontlaser_side_offset", false, ParamKind::kOffsetY, ""},
    {"robot_frontlaser_angular_offset", false, ParamKind::kOffsetTheta, ""},
    {"laser_rear_laser_fov", true, ParamKind::kFieldOfView, ""},
    {"laser_rear_laser_resolution", true, ParamKind::kResolution, ""},
    {"laser_rearlaser_fov", true, ParamKind::kFieldOfView, "laser_rear_laser_fov"},
    {"laser_rearlaser_resolution", true, ParamKind::kResolution, "laser_rear_laser_resolution"},
    {"robot_rear_laser_max", true, ParamKind::kRangeMax, ""},
    {"robot_rearlaser_offset", true, ParamKind::kOffsetX, ""},
    {"robot_rearlaser_side_offset", true, ParamKind::kOffsetY, ""},
    {"robot_rearlaser_angular_offset", true, ParamKind::kOffsetTheta, ""},
};

// Half a unit of the last decimal printed in `token` ("3.14159" -> 5e-6); 0 without a fraction.
double printed_rounding(std::string_view token) {
  const std::size_t point = token.find('.');
  if (point == std::string_view::npos) return 0.0;
  std::size_t decimals = 0;
  while (point + 1 + decimals < token.size() && token[point + 1 + decimals] >= '0' && token[point + 1 + decimals] <= '9') {
    ++decimals;
  }
  const std::size_t exponent_at = token.find_first_of("eE");
  const int exponent = exponent_at == std::string_view::npos ? 0 : parse_int(token.substr(exponent_at + 1)).value_or(0);
  return 0.5 * std::pow(10.0, static_cast<double>(exponent) - static_cast<double>(decimals));
}

void apply_param(OldLaserParams& params, const ParamBinding& binding, double value, const Fields& fields,
                 std::size_t line) {
  const bool must_be_positive = binding.kind == ParamKind::kFieldOfView || binding.kind == ParamKind::kResolution ||
                                binding.kind == ParamKind::kRangeMax;
  if (must_be_positive && !(value > 0.0)) {
    fields.fail(std::string(fields.token(1)) + " must be positive, got " + std::string(fields.token(2)));
  }
  if (binding.kind == ParamKind::kFieldOfView && value > 360.0) {
    fields.fail(std::string(fields.token(1)) + " is more than a full turn in degrees or radians, got " +
                std::string(fields.token(2)));
  }
  DeclaredParam declared{std::string(binding.name),
                         std::string(binding.canonical.empty() ? binding.name : binding.canonical),
                         std::string(fields.token(2)), value, printed_rounding(fields.token(2)), line};
  switch (binding.kind) {
    case ParamKind::kFieldOfView: params.field_of_view = std::move(declared); break;
    case ParamKind::kResolution: params.resolution = std::move(declared); break;
    case ParamKind::kRangeMax: params.range_max = std::move(declared); break;
    case ParamKind::kOffsetX: params.offset_x = value; break;
    case ParamKind::kOffsetY: params.offset_y = value; break;
    case ParamKind::kOffsetTheta: params.offset_theta = value; break;
  }
  params.decided.clear();  // the next laser line of each beam count decides again
}

// ---------------------------------------------------------------------------------------------
// The geometry check: field of view and increment from the options, the PARAM lines, the beam
// count and the convention (see the top of this file).

constexpr double kPi = std::numbers::pi;
constexpr double kAngleSlack = 1e-9;  // rad, floating-point slack of the comparisons
// Relative slack of beams x increment: an increment printed with %g's six significant digits
// (0.00872665 for 0.5 deg) is off by up to 5e-6 of itself, and that error grows with the beams.
constexpr double kPrintedIncrementSlack = 1e-5;

// One way to read a declared angle.
struct AngleReading {
  double value = 0.0;     // rad
  double rounding = 0.0;  // rad, of the value as printed
  GeometrySource source = GeometrySource::kParam;
  std::string name;       // "PARAM laser_front_laser_fov 3.14159 (line 3)", or "override"
  std::string text;       // the name and the unit read: "... read as radians"
  std::size_t line = 0;   // the PARAM's line; 0 for an override
};

struct AngleDecision {
  GeometryValue field_of_view;
  GeometryValue angle_increment;
  std::vector<std::string> warnings;
};

std::string degrees(double radians) { return fmt::format("{:.6g} deg", rad_to_deg(radians)); }


// beams x increment = field of view, within one beam step (n or n - 1 steps) and the rounding of
// the printed values.
bool fits(double fov, double fov_rounding, double increment, std::size_t beams) {
  if (beams < 2) return true;  // one beam says nothing about the field of view
  const double spanned = static_cast<double>(beams) * increment;
  return std::abs(spanned - fov) <= increment + fov_rounding + kPrintedIncrementSlack * spanned + kAngleSlack;
}

std::string describe(const DeclaredParam& param) {
  std::string text = "PARAM " + param.name + " " + param.token + " (line " + std::to_string(param.line);
  if (param.name != param.canonical) text += ", taken as " + param.canonical;
  return text + ")";
}

// The readings of a declared field of view or increment (`what`): the override alone, or the
// PARAM in degrees (CARMEN's unit) and, for a value <= 2 pi, in radians.
std::vector<AngleReading> readings_of(const std::optional<double>& override_rad, const std::optional<DeclaredParam>& param,
                                      const std::string& what) {
  if (override_rad) return {{*override_rad, 0.0, GeometrySource::kOverride, "the " + what + " override", "override", 0}};
  if (!param) return {};
  const std::string name = describe(*param);
  std::vector<AngleReading> out{{deg_to_rad(param->value), deg_to_rad(param->rounding), GeometrySource::kParam, name,
                                 name + " in degrees", param->line}};
  if (param->value <= 2.0 * kPi + kAngleSlack) {
    out.push_back({param->value, param->rounding, GeometrySource::kParamUnitGuess, name, name + " read as radians",
                   param->line});
  }
  return out;
}

GeometryValue value_of(const AngleReading& reading, const std::string& why) {
  return {reading.value, reading.source, why.empty() ? reading.text : reading.text + ": " + why};
}

// A field of view that agrees with the convention's 180 deg within one beam step; one that
// equals pi within its printed rounding (3.14159) is pi.
bool near_convention(const AngleReading& fov, std::size_t beams) {
  return std::abs(fov.value - kPi) <= kPi / static_cast<double>(beam_steps(beams)) + fov.rounding + kAngleSlack;
}
GeometryValue convention_value_of(const AngleReading& fov, const std::string& why) {
  GeometryValue value = value_of(fov, why);
  if (std::abs(fov.value - kPi) <= fov.rounding + kAngleSlack) value.value = kPi;
  return value;
}

AngleDecision from_field_of_view(const GeometryValue& fov, std::size_t beams) {
  const std::size_t steps = beam_steps(beams);
  return {fov, {fov.value / static_cast<double>(steps), GeometrySource::kDerived,
                fmt::format("field of view / {} steps", steps)}, {}};
}

AngleDecision from_increment(const GeometryValue& increment, std::size_t beams) {
  const std::size_t steps = beam_steps(beams);
  return {{static_cast<double>(steps) * increment.value, GeometrySource::kDerived,
           fmt::format("{} steps x increment", steps)}, increment, {}};
}

const GeometryValue kConventionFov{kPi, GeometrySource::kConvention, "CARMEN convention"};

std::string fit_text(std::size_t beams, double increment) {
  return fmt::format("{} beams x {}", beams, degrees(increment));
}

// A field of view alone: degrees, unless the value read as radians is the convention's 180 deg.
AngleDecision fov_alone(const std::vector<AngleReading>& fovs, std::size_t beams) {
  if (fovs.size() == 1) return from_field_of_view(value_of(fovs[0], ""), beams);
  const AngleReading& in_degrees = fovs[0];
  const AngleReading& in_radians = fovs[1];
  if (near_convention(in_radians, beams)) {
    return from_field_of_view(convention_value_of(in_radians, "the CARMEN convention's 180 deg; in degrees " +
                                                                  degrees(in_degrees.value) + " over " +
                                                                  std::to_string(beams) + " beams"),
                              beams);
  }
  AngleDecision decision = from_field_of_view(value_of(in_degrees, ""), beams);
  decision.warnings.push_back(in_degrees.text + " is <= 2 pi; read as radians it would be " +
                              degrees(in_radians.value) + ": if so, override the field of view");
  return decision;
}

// A resolution alone: with the convention's 180 deg if it fits, else spanning s steps.
AngleDecision increment_alone(const std::vector<AngleReading>& valid, std::size_t beams) {
  for (const AngleReading& r : valid) {
    if (!fits(kPi, 0.0, r.value, beams)) continue;
    const std::string why = r.source == GeometrySource::kParamUnitGuess
                                ? fit_text(beams, r.value) + " fit the CARMEN convention's 180 deg; in degrees they would not"
                                : "";
    return {{kPi, GeometrySource::kConvention, "CARMEN convention, which " + fit_text(beams, r.value) + " fit"},
            value_of(r, why), {}};
  }
  AngleDecision decision = from_increment(value_of(valid[0], ""), beams);
  if (valid[0].source != GeometrySource::kOverride) {
    decision.warnings.push_back(valid[0].text + ": " + fit_text(beams, valid[0].value) + " span " +
                                degrees(decision.field_of_view.value) + ", not the CARMEN convention's 180 deg");
  }
  return decision;
}

// Both declared, and fitting in no unit: an override wins, else the convention if it agrees with one PARAM.
AngleDecision contradiction(const std::vector<AngleReading>& fovs, const std::vector<AngleReading>& increments,
                            std::size_t beams, const std::string& path) {
  const AngleReading& fov = fovs[0];
  const AngleReading& increment = increments[0];
  const std::string clash = fov.name + " and " + increment.name + " do not fit " + std::to_string(beams) +
                            " beams in any unit (" + fit_text(beams, increment.value) + " = " +
                            degrees(static_cast<double>(beams) * increment.value) + ")";
  const bool fov_override = fov.source == GeometrySource::kOverride;
  const bool increment_override = increment.source == GeometrySource::kOverride;
  if (fov_override || increment_override) {
    AngleDecision decision = !increment_override ? from_field_of_view(value_of(fov, ""), beams)
                             : !fov_override     ? from_increment(value_of(increment, ""), beams)
                                                 : AngleDecision{value_of(fov, ""), value_of(increment, ""), {}};
    decision.warnings.push_back(clash + (fov_override && increment_override ? ": both kept as given"
                                         : fov_override ? ": the PARAM increment is dropped"
                                                        : ": the PARAM field of view is dropped"));
    return decision;
  }
  for (const AngleReading& r : increments) {
    if (!fits(kPi, 0.0, r.value, beams)) continue;
    return {{kPi, GeometrySource::kConvention, "CARMEN convention (the PARAM field of view is dropped)"},
            value_of(r, fit_text(beams, r.value) + " fit the convention"),
            {clash + ": the field of view falls back to the CARMEN convention's 180 deg, which the resolution fits"}};
  }
  for (const AngleReading& r : fovs) {
    if (!near_convention(r, beams)) continue;
    AngleDecision decision = from_field_of_view(convention_value_of(r, "the CARMEN convention's 180 deg"), beams);
    decision.warnings.push_back(clash + ": the increment falls back to the CARMEN convention (180 deg over the beams)");
    return decision;
  }
  throw ParseError(path, fov.line,
                   clash + ", nor the CARMEN convention of 180 deg; override the field of view and increment");
}

// Both declared: the one pair of readings that fits; between both-in-degrees and both-in-radians
// (which always fit together) the one giving the convention's 180 deg, else degrees with a warning.
AngleDecision fov_and_increment(const std::vector<AngleReading>& fovs, const std::vector<AngleReading>& increments,
                                std::size_t beams, const std::string& path) {
  std::vector<std::pair<const AngleReading*, const AngleReading*>> fitting;
  for (const AngleReading& f : fovs) {
    for (const AngleReading& i : increments) {
      if (fits(f.value, f.rounding, i.value, beams)) fitting.emplace_back(&f, &i);
    }
  }
  if (fitting.empty()) return contradiction(fovs, increments, beams, path);
  auto take = [&](const auto& pair, const std::string& note) {
    const std::string why = fit_text(beams, pair.second->value) + note;
    AngleDecision decision{value_of(*pair.first, why), value_of(*pair.second, ""), {}};
    // A field of view printed with fewer digits than the increment (3.14159 for 360 x 0.5 deg) is that product, rounded.
    const double spanned = static_cast<double>(beam_steps(beams)) * pair.second->value;
    if (pair.first->rounding > 0.0 && std::abs(pair.first->value - spanned) <= pair.first->rounding + kAngleSlack) {
      decision.field_of_view.value = spanned;
    }
    return decision;
  };
  if (fitting.size() == 1) {
    const bool guessed = fitting[0].first->source == GeometrySource::kParamUnitGuess ||
                         fitting[0].second->source == GeometrySource::kParamUnitGuess;
    return take(fitting[0], guessed ? " fit; in CARMEN's degrees they would not" : " fit");
  }
  std::vector<std::size_t> at_convention;
  for (std::size_t k = 0; k < fitting.size(); ++k) {
    const auto& [f, i] = fitting[k];
    if (std::abs(f->value - kPi) <= i->value + f->rounding + kAngleSlack) at_convention.push_back(k);
  }
  if (at_convention.size() == 1) {
    return take(fitting[at_convention[0]], " fit; read otherwise they fit too, and the CARMEN convention's 180 deg decides");
  }
  AngleDecision decision = take(fitting[0], " fit");
  decision.warnings.push_back(fitting[0].first->name + " and " + fitting[0].second->name + " also fit " +
                              std::to_string(beams) + " beams read otherwise (as a field of view of " +
                              degrees(fitting[1].first->value) + "); kept in degrees, CARMEN's unit");
  return decision;
}

// The increment readings whose beams span at most a full turn; an override is kept regardless,
// with a warning. A PARAM with no such reading is a ParseError at its line.
std::vector<AngleReading> within_a_turn(const std::vector<AngleReading>& increments, std::size_t beams,
                                        const std::string& path, std::vector<std::string>& warnings) {
  std::vector<AngleReading> valid;
  for (const AngleReading& r : increments) {
    if (static_cast<double>(beam_steps(beams)) * r.value <= 2.0 * kPi + kAngleSlack) valid.push_back(r);
  }
  if (!valid.empty() || increments.empty()) return valid;
  if (increments[0].source == GeometrySource::kOverride) {
    warnings.push_back(increments[0].name + ": " + fit_text(beams, increments[0].value) + " span more than a full turn");
    return increments;
  }
  throw ParseError(path, increments[0].line,
                   increments[0].text + ": " + fit_text(beams, increments[0].value) +
                       " span more than a full turn in degrees and in radians; override the increment and field of view");
}

AngleDecision decide_angles(const std::vector<AngleReading>& fovs, const std::vector<AngleReading>& all_increments,
                            std::size_t beams, const std::string& path) {
  std::vector<std::string> warnings;
  const std::vector<AngleReading> increments = within_a_turn(all_increments, beams, path, warnings);
  AngleDecision decision = fovs.empty() && increments.empty() ? from_field_of_view(kConventionFov, beams)
                           : increments.empty()               ? fov_alone(fovs, beams)
                           : fovs.empty()                     ? increment_alone(increments, beams)
                                                              : fov_and_increment(fovs, increments, beams, path);
  decision.warnings.insert(decision.warnings.begin(), warnings.begin(), warnings.end());
  return decision;
}

GeometryValue decide_range_max(const CarmenReaderOptions& options, const OldLaserParams& params) {
  if (options.geometry.range_max) return {*options.geometry.range_max, GeometrySource::kOverride, "override"};
  if (params.range_max) return {params.range_max->value, GeometrySource::kParam, describe(*params.range_max)};
  return {options.default_range_max, GeometrySource::kConvention, "default (SICK LMS, 80 m mode)"};
}

OldLaserGeometry decide_geometry(const CarmenReaderOptions& options, const OldLaserParams& params, bool rear,
                                 std::size_t beams, std::size_t line, const std::string& path) {
  AngleDecision angles = decide_angles(readings_of(options.geometry.field_of_view, params.field_of_view, "field of view"),
                                       readings_of(options.geometry.angle_increment, params.resolution, "increment"), beams, path);
  OldLaserGeometry geometry;
  geometry.rear = rear;
  geometry.beams = beams;
  geometry.first_line = line;
  geometry.field_of_view = std::move(angles.field_of_view);
  geometry.angle_increment = std::move(angles.angle_increment);
  geometry.warnings = std::move(angles.warnings);
  if (options.geometry.angle_min) {
    geometry.angle_min = {*options.geometry.angle_min, GeometrySource::kOverride, "override"};
  } else {
    const GeometrySource source = geometry.field_of_view.source == GeometrySource::kConvention
                                      ? GeometrySource::kConvention
                                      : GeometrySource::kDerived;
    geometry.angle_min = {-0.5 * geometry.field_of_view.value, source, "-field of view / 2"};
  }
  geometry.range_max = decide_range_max(options, params);
  return geometry;
}

void validate_options(const CarmenReaderOptions& options) {
  check_overrides(options.geometry, "CARMEN reader options");
  check(options.default_range_max > 0.0 && std::isfinite(options.default_range_max),
        "CARMEN reader options: default_range_max must be positive");
  check(options.range_min >= 0.0 && std::isfinite(options.range_min), "CARMEN reader options: range_min must be >= 0");
}

// The uncompressed size of the file in bytes: the gzip trailer's ISIZE (size mod 2^32 of the
// last member) for gzip files, else the file size; negative when it cannot be found.
double uncompressed_size(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char magic[2] = {0, 0};
  if (!in.read(reinterpret_cast<char*>(magic), 2)) return -1.0;
  if (magic[0] != 0x1f || magic[1] != 0x8b) {
    std::error_code error;
    const auto size = std::filesystem::file_size(path, error);
    return error ? -1.0 : static_cast<double>(size);
  }
  unsigned char isize[4] = {0, 0, 0, 0};
  if (!in.seekg(-4, std::ios::end) || !in.read(reinterpret_cast<char*>(isize), 4)) return -1.0;
  return static_cast<double>(isize[0] | (isize[1] << 8) | (isize[2] << 16) | (std::uint32_t{isize[3]} << 24));
}

}  // namespace

// -----------------------------------------------------------------------------------------------

struct CarmenReader::Impl {
  Impl(const std::string& path, CarmenReaderOptions opts)
      : reader(path), options(opts), total_bytes(uncompressed_size(path)) {
    validate_options(options);
  }

  std::optional<SensorMessage> parse_line(const Fields& fields);
  void parse_param(const Fields& fields);
  LaserMessage parse_old_laser(const Fields& fields, bool rear);
  void set_old_laser_geometry(LaserMessage& message, std::size_t n, bool rear);
  LaserMessage parse_new_laser(const Fields& fields, bool robot_laser) const;
  std::pair<std::size_t, std::size_t> new_laser_counts(const Fields& fields, std::size_t fixed_tail) const;
  OdometryMessage parse_odometry(const Fields& fields) const;
  TruePoseMessage parse_true_pose(const Fields& fields) const;
  void note_stamp(double stamp, bool is_laser);

  LineReader reader;
  CarmenReaderOptions options;
  CarmenStats stats;
  OldLaserParams front;
  OldLaserParams rear;
  std::string line;
  std::vector<std::string_view> tokens;
  std::optional<double> previous_stamp;
  ReverseOdometryRepair reverse_repair;
  std::optional<double> previous_laser_stamp;
  double total_bytes;      // uncompressed size, negative if unknown
  double bytes_read = 0.0;  // uncompressed bytes of the lines read so far
  // Until a line of a CARMEN type is read, the file may be something else entirely (a binary, a
  // bag given the wrong name, a CSV): check_is_carmen() refuses it by name.
  bool is_carmen = false;
  std::size_t lines_before_carmen = 0;  // non-comment lines of no CARMEN type read so far

  void check_is_carmen(bool comment);
};

namespace {

// How many lines of other types may come before the first CARMEN line.
constexpr std::size_t kLinesBeforeCarmen = 1000;

// What a file that starts with `head` is, when its magic says so.
std::optional<std::string> known_binary_format(std::string_view head) {
  static const std::pair<std::string_view, std::string_view> kMagics[] = {
      {"\x7f" "ELF", "an ELF executable"}, {"\x89PNG", "a PNG image"}, {"PK\x03\x04", "a zip archive"},
      {"%PDF", "a PDF document"}, {"SQLite format 3", "an SQLite database (a rosbag2 .db3 file: give its folder)"},
      {"BZh", "a bzip2 file"}, {"\x28\xb5\x2f\xfd", "a zstd file"}, {"\xfd" "7zXZ", "an xz file"},
      {"#ROSBAG", "a ROS 1 bag"}, {"\x89MCAP", "an MCAP file"}, {"P5", "a PGM image"}};
  for (const auto& [magic, name] : kMagics) {
    if (head.starts_with(magic)) return std::string(name);
  }
  return std::nullopt;
}

// The first byte of `line` that no text log holds (a control character other than tab, CR,
// vertical tab, form feed), if any.
std::optional<unsigned char> binary_byte(std::string_view line) {
  for (const char c : line) {
    const auto byte = static_cast<unsigned char>(c);
    if ((byte < 0x20 && byte != '\t' && byte != '\r' && byte != '\v' && byte != '\f') || byte == 0x7F) return byte;
  }
  return std::nullopt;
}

bool is_carmen_type(std::string_view type) {
  return type == "FLASER" || type == "RLASER" || type == "ROBOTLASER1" || type == "ODOM" || type == "TRUEPOS" ||
         type == "PARAM" || type.starts_with("RAWLASER");
}

}  // namespace

// Called for each line (comments too) until the first CARMEN line: a file that is something else
// is refused at the first sign of it, naming what it is where its magic says so.
void CarmenReader::Impl::check_is_carmen(bool comment) {
  const std::string not_carmen = "not a CARMEN log: ";
  if (reader.line_number() == 1) {
    if (const auto format = known_binary_format(line)) throw ParseError(reader.path(), 1, not_carmen + "it is " + *format);
  }
  if (const auto byte = binary_byte(line)) {
    throw ParseError(reader.path(), reader.line_number(),
                     not_carmen + fmt::format("binary data (byte 0x{:02x}) before any FLASER, RLASER, ROBOTLASER1, "
                                              "RAWLASER, ODOM, TRUEPOS or PARAM line",
                                              *byte));
  }
  if (comment) return;
  if (is_carmen_type(tokens[0])) {
    is_carmen = true;
  } else if (++lines_before_carmen >= kLinesBeforeCarmen) {
    throw ParseError(reader.path(), reader.line_number(),
                     not_carmen + fmt::format("no FLASER, RLASER, ROBOTLASER1, RAWLASER, ODOM, TRUEPOS or PARAM line "
                                              "in the first {} lines",
                                              kLinesBeforeCarmen));
  }
}

std::optional<SensorMessage> CarmenReader::Impl::parse_line(const Fields& fields) {
  const std::string_view type = fields.type();
  if (type == "FLASER" || type == "RLASER") return parse_old_laser(fields, type == "RLASER");
  if (type == "ROBOTLASER1") return parse_new_laser(fields, true);
  if (type.size() == 9 && type.starts_with("RAWLASER") && type[8] >= '1' && type[8] <= '4') {
    return parse_new_laser(fields, false);
  }
  if (type == "ODOM") return parse_odometry(fields);
  if (type == "TRUEPOS") return parse_true_pose(fields);
  if (type == "PARAM") {
    parse_param(fields);
    return std::nullopt;
  }
  ++stats.skipped_lines;
  ++stats.skipped_types[std::string(type)];
  return std::nullopt;
}

// PARAM name value [ipc_timestamp ipc_hostname logger_timestamp]. Some old logs write only
// "name value hostname logger_timestamp", so the stamp fields are not interpreted; a PARAM is
// configuration, not a timestamped message.
void CarmenReader::Impl::parse_param(const Fields& fields) {
  if (fields.size() < 3 || fields.size() > 6) {
    fields.fail("expected name value [ipc_timestamp ipc_hostname logger_timestamp], got " +
                std::to_string(fields.size() - 1) + " tokens");
  }
  ++stats.param_messages;
  for (const ParamBinding& binding : kParamBindings) {
    if (binding.name != fields.token(1)) continue;
    const double value = fields.number(2, std::string(binding.name) + " value");
    apply_param(binding.rear ? rear : front, binding, value, fields, reader.line_number());
  }
}

// FLASER|RLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta ipc_timestamp [host [logger_ts]]
LaserMessage CarmenReader::Impl::parse_old_laser(const Fields& fields, bool is_rear) {
  if (fields.size() < 2) fields.fail("missing num_readings");
  const std::size_t n = fields.beams(1, "num_readings");
  const std::size_t available = fields.size() - 2;
  if (available < n || !tail_fits(available - n, 6)) {
    fields.fail("expected " + std::to_string(n) + " ranges + 9 fields, got " + std::to_string(available) +
                " tokens");
  }
  LaserMessage message;
  message.type = std::string(fields.type());
  message.line = reader.line_number();
  message.scan.ranges = fields.values(2, n, "range", false);
  message.laser_pose = fields.pose(2 + n, "");
  message.odom_pose = fields.pose(5 + n, "odom_");
  message.scan.stamp = fields.stamp_tail(8 + n);
  set_old_laser_geometry(message, n, is_rear);
  return message;
}

// The geometry decided for this laser and beam count (deciding it at its first line), applied.
void CarmenReader::Impl::set_old_laser_geometry(LaserMessage& message, std::size_t n, bool is_rear) {
  OldLaserParams& params = is_rear ? rear : front;
  auto [at, is_new] = params.decided.try_emplace(n, stats.old_laser_geometries.size());
  if (is_new) {
    try {
      stats.old_laser_geometries.push_back(decide_geometry(options, params, is_rear, n, message.line, reader.path()));
    } catch (...) {
      params.decided.erase(at);
      throw;
    }
  }
  OldLaserGeometry& geometry = stats.old_laser_geometries[at->second];
  LaserScan& scan = message.scan;
  message.field_of_view = geometry.field_of_view.value;
  scan.angle_min = geometry.angle_min.value;
  scan.angle_increment = geometry.angle_increment.value;
  scan.range_min = options.range_min;
  scan.range_max = geometry.range_max.value;
  const double yaw = params.offset_theta + (is_rear ? std::numbers::pi : 0.0);
  scan.T_robot_sensor = SE2(params.offset_x, params.offset_y, yaw);
  ++geometry.scans;
  geometry.readings += n;
  geometry.readings_at_range_max += static_cast<std::size_t>(
      std::count_if(scan.ranges.begin(), scan.ranges.end(), [&](double r) { return r >= scan.range_max; }));
}

// ROBOTLASER1|RAWLASERk laser_type start_angle field_of_view angular_resolution maximum_range
//   accuracy remission_mode n r_1 .. r_n m i_1 .. i_m
//   [ROBOTLASER1 only: laser_x laser_y laser_theta robot_x robot_y robot_theta laser_tv laser_rv
//    forward_safety_dist side_safety_dist turn_axis] ipc_timestamp [host [logger_ts]]
LaserMessage CarmenReader::Impl::parse_new_laser(const Fields& fields, bool robot_laser) const {
  constexpr std::size_t kFirstRange = 9;
  const std::size_t fixed_tail = robot_laser ? 11 : 0;
  const auto [n, m] = new_laser_counts(fields, fixed_tail);
  LaserMessage message;
  message.type = std::string(fields.type());
  message.line = reader.line_number();
  LaserScan& scan = message.scan;
  fields.number(1, "laser_type");
  scan.angle_min = fields.number(2, "start_angle");
  message.field_of_view = fields.number(3, "field_of_view");
  scan.angle_increment = fields.number(4, "angular_resolution");
  scan.range_max = fields.number(5, "maximum_range");
  if (!(scan.range_max > 0.0)) fields.fail("maximum_range must be positive, got " + std::string(fields.token(5)));
  fields.number(6, "accuracy");
  fields.number(7, "remission_mode");
  scan.range_min = options.range_min;
  scan.ranges = fields.values(kFirstRange, n, "range", false);
  scan.intensities = fields.values(kFirstRange + n + 1, m, "remission", true);
  std::size_t i = kFirstRange + n + 1 + m;
  if (robot_laser) {
    message.laser_pose = fields.pose(i, "laser_");
    message.odom_pose = fields.pose(i + 3, "robot_");
    constexpr const char* kRest[] = {"laser_tv", "laser_rv", "forward_safety_dist", "side_safety_dist", "turn_axis"};
    for (std::size_t k = 0; k < 5; ++k) fields.number(i + 6 + k, kRest[k]);
    scan.T_robot_sensor = message.odom_pose.between(message.laser_pose);
    i += fixed_tail;
  } else {
    message.has_poses = false;
  }
  scan.stamp = fields.stamp_tail(i);
  return message;
}

// The counts (num_readings, num_remissions) of a ROBOTLASER1/RAWLASER line, checked against its length.
std::pair<std::size_t, std::size_t> CarmenReader::Impl::new_laser_counts(const Fields& fields,
                                                                          std::size_t fixed_tail) const {
  if (fields.size() < 10) {
    fields.fail("expected 7 fields and num_readings, got " + std::to_string(fields.size() - 1) + " tokens");
  }
  const std::size_t n = fields.beams(8, "num_readings");
  const std::size_t available = fields.size() - 9;  // tokens after num_readings
  const bool has_m = available > n;
  const std::size_t m = has_m ? fields.beams(9 + n, "num_remissions") : 0;
  if (!has_m || available - n - 1 < m || !tail_fits(available - n - 1 - m, fixed_tail)) {
    fields.fail("expected " + std::to_string(n) + " ranges + num_remissions + " +
                (has_m ? std::to_string(m) : std::string("?")) + " remissions + " +
                std::to_string(fixed_tail + kMaxTail) + " fields, got " + std::to_string(available) +
                " tokens after num_readings");
  }
  if (m != 0 && m != n) fields.fail(std::to_string(m) + " remissions for " + std::to_string(n) + " ranges");
  return {n, m};
}

// ODOM x y theta tv rv accel ipc_timestamp [host [logger_ts]]
OdometryMessage CarmenReader::Impl::parse_odometry(const Fields& fields) const {
  if (!tail_fits(fields.size() - 1, 6)) {
    fields.fail("expected 9 fields (x y theta tv rv accel ipc_timestamp ipc_hostname logger_timestamp), got " +
                std::to_string(fields.size() - 1) + " tokens");
  }
  OdometryMessage message;
  message.line = reader.line_number();
  message.reading.pose = fields.pose(1, "");
  message.reading.tv = fields.number(4, "tv");
  message.reading.rv = fields.number(5, "rv");
  fields.number(6, "accel");
  message.reading.stamp = fields.stamp_tail(7);
  return message;
}

// TRUEPOS true_x true_y true_theta odom_x odom_y odom_theta ipc_timestamp [host [logger_ts]]
TruePoseMessage CarmenReader::Impl::parse_true_pose(const Fields& fields) const {
  if (!tail_fits(fields.size() - 1, 6)) {
    fields.fail("expected 9 fields (true_x true_y true_theta odom_x odom_y odom_theta ipc_timestamp "
                "ipc_hostname logger_timestamp), got " + std::to_string(fields.size() - 1) + " tokens");
  }
  TruePoseMessage message;
  message.line = reader.line_number();
  message.true_pose = fields.pose(1, "true_");
  message.odom_pose = fields.pose(4, "odom_");
  message.stamp = fields.stamp_tail(7);
  return message;
}

void CarmenReader::Impl::note_stamp(double stamp, bool is_laser) {
  if (previous_stamp && stamp < *previous_stamp) ++stats.backwards_timestamps;
  previous_stamp = stamp;
  if (is_laser) {
    if (previous_laser_stamp && stamp < *previous_laser_stamp) ++stats.backwards_laser_timestamps;
    previous_laser_stamp = stamp;
  }
  if (!stats.first_stamp) stats.first_stamp = stamp;
  stats.last_stamp = stamp;
}

// -----------------------------------------------------------------------------------------------

const char* to_string(GeometrySource source) {
  switch (source) {
    case GeometrySource::kConvention: return "convention";
    case GeometrySource::kParam: return "PARAM";
    case GeometrySource::kParamUnitGuess: return "PARAM (unit guessed)";
    case GeometrySource::kDerived: return "derived";
    case GeometrySource::kOverride: return "override";
  }
  return "unknown";
}

const OldLaserGeometry* CarmenStats::front_geometry() const {
  const OldLaserGeometry* best = nullptr;
  for (const OldLaserGeometry& geometry : old_laser_geometries) {
    if (!geometry.rear && (best == nullptr || geometry.scans > best->scans)) best = &geometry;
  }
  return best;
}

CarmenReader::CarmenReader(const std::string& path, CarmenReaderOptions options)
    : impl_(std::make_unique<Impl>(path, options)) {}

CarmenReader::~CarmenReader() = default;
CarmenReader::CarmenReader(CarmenReader&&) noexcept = default;
CarmenReader& CarmenReader::operator=(CarmenReader&&) noexcept = default;

std::optional<SensorMessage> CarmenReader::next() {
  if (!impl_) throw Error("CarmenReader: used after move");
  Impl& s = *impl_;
  while (s.reader.next(s.line)) {
    ++s.stats.lines;
    s.bytes_read += static_cast<double>(s.line.size() + 1);
    split_fields(s.line, s.tokens);
    const bool comment = s.tokens.empty() || s.tokens[0].front() == '#';
    if (!s.is_carmen) s.check_is_carmen(comment);
    if (comment) {
      ++s.stats.comment_lines;
      continue;
    }
    std::optional<SensorMessage> message = s.parse_line(Fields(s.reader, s.tokens));
    if (!message) continue;
    if (auto* laser = std::get_if<LaserMessage>(&*message)) {
      ++s.stats.laser_messages;
      s.note_stamp(laser->scan.stamp, true);
      if (laser->has_poses && s.options.repair_reverse_odometry) {
        laser->odom_pose = s.reverse_repair.repair(laser->odom_pose);
        s.stats.odometry_steps_reversed = s.reverse_repair.reversed_steps();
        s.stats.odometry_poses_record_reversing = s.reverse_repair.poses_record_reversing();
      }
    } else if (auto* odometry = std::get_if<OdometryMessage>(&*message)) {
      ++s.stats.odometry_messages;
      s.note_stamp(odometry->reading.stamp, false);
      s.reverse_repair.observe(odometry->reading);
    } else {
      ++s.stats.true_pose_messages;
      s.note_stamp(std::get<TruePoseMessage>(*message).stamp, false);
    }
    return message;
  }
  if (!s.is_carmen && s.lines_before_carmen > 0) {
    throw ParseError(s.reader.path(), s.reader.line_number(),
                     "not a CARMEN log: no FLASER, RLASER, ROBOTLASER1, RAWLASER, ODOM, TRUEPOS or PARAM line");
  }
  return std::nullopt;
}

const CarmenStats& CarmenReader::stats() const {
  if (!impl_) throw Error("CarmenReader: used after move");
  return impl_->stats;
}

double CarmenReader::progress() const {
  if (!impl_) throw Error("CarmenReader: used after move");
  if (impl_->total_bytes < 0.0) return -1.0;
  if (impl_->total_bytes == 0.0) return 1.0;
  return std::min(1.0, impl_->bytes_read / impl_->total_bytes);
}

const std::string& CarmenReader::path() const {
  if (!impl_) throw Error("CarmenReader: used after move");
  return impl_->reader.path();
}

}  // namespace slam2d
