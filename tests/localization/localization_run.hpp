// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// One localizer driven over a simulated run by a LocalizationSession, with the error of every
// step against the simulator's truth (shared by the localization tests).

#include <optional>
#include <vector>

#include "slam2d/localization/localizer.hpp"
#include "slam2d/localization/session.hpp"
#include "slam2d/sim/simulator.hpp"

namespace slam2d::test {

struct LocalizationRun {
  LocalizationRunSummary summary;
  std::vector<double> errors;  // m, per scan
  std::vector<bool> localized;
};

inline LocalizationRun run_localization(Localizer& localizer, const SimulatedRun& sim,
                                        std::optional<Kidnap> kidnap = std::nullopt) {
  LocalizationSession session(localizer, kidnap);
  LocalizationRun result;
  const auto lasers = laser_messages(sim);
  for (std::size_t i = 0; i < lasers.size(); ++i) {
    const LocalizationEstimate& estimate = session.add(lasers[i]->odom_pose, lasers[i]->scan);
    result.errors.push_back((estimate.pose.translation() - sim.truth[i].pose.translation()).norm());
  }
  result.summary = session.summary();
  result.localized = session.localized();
  return result;
}

}  // namespace slam2d::test
