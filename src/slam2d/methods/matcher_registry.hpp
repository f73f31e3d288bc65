// SPDX-License-Identifier: BSD-3-Clause
#pragma once
// Every matcher by name, with its configuration from defaults or from a YAML preset
// (configs/<name>.yaml): what the CLI, the benchmarks and the all-matchers test suite use.
//
// A preset file holds `matcher: <name>` and the fields of that matcher's config struct under the
// same names, read by the struct's field table (core/config_fields.hpp); unknown keys, wrong
// types and values out of range are ParseErrors naming the file and line.

#include <string>
#include <vector>

#include "slam2d/io/config_file.hpp"
#include "slam2d/io/config_text.hpp"
#include "slam2d/registration/match_result.hpp"

namespace slam2d {

/// The names make_matcher knows, in the order of issue 3's list.
const std::vector<std::string>& matcher_names();

/// The matcher `name` with its default configuration. Throws Error naming the known matchers.
Matcher make_matcher(const std::string& name);
/// The matcher `name` configured by the keys of `config` (a `matcher` key, if present, must
/// name the same matcher).
Matcher make_matcher(const std::string& name, const ConfigNode& config);
/// The fields of matcher `name`'s config with its defaults (`slam2d config dump NAME`).
std::vector<FieldRow> matcher_fields(const std::string& name);
/// The matcher a preset file names in its `matcher` key, configured by the file.
Matcher load_matcher(const std::string& yaml_path);

/// A NAME or a path to a .yaml preset (anything ending in .yaml or .yml).
Matcher matcher_from_argument(const std::string& name_or_path);

}  // namespace slam2d
