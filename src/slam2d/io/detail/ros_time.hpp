// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// A stamp in seconds as the whole seconds and nanoseconds of a ROS time (ROS 1 time, ROS 2
// builtin_interfaces/Time, MCAP's nanoseconds): one home for the writers' rounding.

#include <cmath>
#include <cstdint>
#include <string>

#include "slam2d/core/error.hpp"

namespace slam2d::detail {

struct SplitStamp {
  std::int64_t sec = 0;
  std::uint32_t nsec = 0;  // [0, 1e9)
};

/// `stamp` rounded to the nearest ns, as seconds in [min_sec, max_sec] and nanoseconds; Error
/// ("stamp X s does not fit WHAT") when it is not finite or its seconds fall outside.
inline SplitStamp split_stamp(double stamp, double min_sec, double max_sec, const std::string& what) {
  const double whole = std::floor(stamp);
  if (!std::isfinite(stamp) || whole < min_sec || whole > max_sec) {
    throw Error("stamp " + std::to_string(stamp) + " s does not fit " + what);
  }
  SplitStamp out{static_cast<std::int64_t>(whole), 0};
  auto nsec = std::llround((stamp - whole) * 1e9);
  if (nsec >= 1'000'000'000) {  // rounded up to the next second
    nsec -= 1'000'000'000;
    ++out.sec;
    if (static_cast<double>(out.sec) > max_sec) throw Error("stamp " + std::to_string(stamp) + " s does not fit " + what);
  }
  out.nsec = static_cast<std::uint32_t>(nsec);
  return out;
}

}  // namespace slam2d::detail
