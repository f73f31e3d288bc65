// SPDX-License-Identifier: BSD-3-Clause
#include "support/simulated_office.hpp"

#include <map>
#include <utility>

namespace slam2d::test {

const SimulatedRun& simulated_office(double duration, std::uint64_t seed) {
  static std::map<std::pair<double, std::uint64_t>, SimulatedRun> runs;
  const auto key = std::make_pair(duration, seed);
  auto it = runs.find(key);
  if (it == runs.end()) {
    SimulationConfig config;
    config.duration = duration;
    config.seed = seed;
    it = runs.emplace(key, simulate(config)).first;
  }
  return it->second;
}

}  // namespace slam2d::test
