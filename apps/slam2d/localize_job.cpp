// SPDX-License-Identifier: BSD-3-Clause
#include "localize_job.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "slam2d/core/error.hpp"
#include "slam2d/localization/ekf.hpp"
#include "slam2d/localization/hybrid.hpp"
#include "slam2d/localization/markov_grid.hpp"
#include "slam2d/localization/mcl.hpp"
#include "slam2d/methods/method_presets.hpp"

namespace slam2d::cli {


std::vector<double> parse_triple(const std::string& text, const std::string& option) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    try {
      std::size_t used = 0;
      values.push_back(std::stod(item, &used));
      check(used == item.size(), "");
    } catch (const std::exception&) {
      throw Error(fmt::format("localize: {} expects three numbers a,b,c, got '{}'", option, text));
    }
  }
  check(values.size() == 3 && std::isfinite(values[0]) && std::isfinite(values[1]) && std::isfinite(values[2]),
        fmt::format("localize: {} expects three finite numbers a,b,c, got '{}'", option, text));
  return values;
}

std::unique_ptr<Localizer> make_localizer(const LocalizeOptions& options, const LocalizationMap& map, JsonObject& settings) {
  const bool has_initial = !options.initial.empty();
  check(has_initial != options.global, "localize: give exactly one of --initial x,y,theta and --global");
  check(!(options.method == "ekf" && options.global),
        "localize: the EKF has no global mode (it tracks a unimodal Gaussian): give --initial, or use mcl, markov or hybrid");
  SE2 initial;
  Covariance3 covariance = Covariance3::Identity();
  if (has_initial) {
    const std::vector<double> pose = parse_triple(options.initial, "--initial");
    const std::vector<double> sigma = parse_triple(options.initial_sigma, "--initial-sigma");
    check(sigma[0] > 0.0 && sigma[1] > 0.0 && sigma[2] > 0.0, "localize: --initial-sigma must be positive");
    initial = SE2(pose[0], pose[1], pose[2]);
    covariance = covariance_from_sigmas(sigma[0], sigma[1], sigma[2]);
  }
  if (options.method == "mcl") {
    MclConfig config = read_method_preset(options.config, options.method, MclConfig{});
    if (options.particles) {
      check(*options.particles >= 10, "localize: --particles must be at least 10");
      config.max_particles = *options.particles;
      config.min_particles = std::min<std::size_t>(config.min_particles, *options.particles);
    }
    if (options.seed) config.seed = *options.seed;
    if (options.sensor) config.sensor = *options.sensor == "beam" ? SensorModelKind::kBeam : SensorModelKind::kLikelihoodField;
    settings.add("particles", config.max_particles).add("sensor", config.sensor == SensorModelKind::kBeam ? "beam" : "likelihood-field");
    auto mcl = std::make_unique<MonteCarloLocalization>(map, config);
    if (has_initial) mcl->initialize(initial, covariance);
    else mcl->initialize_global();
    return mcl;
  }
  check(!options.sensor && !options.particles, "localize: --sensor and --particles apply to --method mcl only");
  if (options.method == "ekf") {
    auto ekf = std::make_unique<EkfLocalization>(map, read_method_preset(options.config, options.method, EkfConfig{}));
    ekf->initialize(initial, covariance);
    return ekf;
  }
  if (options.method == "markov") {
    auto markov = std::make_unique<MarkovGridLocalization>(map, read_method_preset(options.config, options.method, MarkovGridConfig{}));
    if (has_initial) markov->initialize(initial, covariance);
    else markov->initialize_global();
    return markov;
  }
  auto hybrid = std::make_unique<HybridLocalization>(map, read_method_preset(options.config, options.method, HybridConfig{}));
  if (has_initial) hybrid->initialize(initial, covariance);
  else hybrid->initialize_global();
  return hybrid;
}

}  // namespace slam2d::cli
