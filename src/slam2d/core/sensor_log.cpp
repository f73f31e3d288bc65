// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/core/sensor_log.hpp"

namespace slam2d {

double stamp_of(const SensorMessage& message) {
  struct Stamp {
    double operator()(const LaserMessage& m) const { return m.scan.stamp; }
    double operator()(const OdometryMessage& m) const { return m.reading.stamp; }
    double operator()(const TruePoseMessage& m) const { return m.stamp; }
    double operator()(const ImuMessage& m) const { return m.reading.stamp; }
  };
  return std::visit(Stamp{}, message);
}

}  // namespace slam2d
