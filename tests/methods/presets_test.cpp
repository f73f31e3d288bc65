// SPDX-License-Identifier: BSD-3-Clause
// Presets and the field tables behind them: every file in configs/ is read and valid, the method
// presets hold exactly the library defaults, a dump reads back to the same fields, a value in a
// preset reaches the config, bad presets are refused at their line, and docs/configuration.md is
// what the tables give.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "slam2d/core/error.hpp"
#include "slam2d/methods/matcher_registry.hpp"
#include "slam2d/methods/method_presets.hpp"
#include "slam2d/slam/graph/graph_slam.hpp"
#include "support/test_support.hpp"

namespace slam2d {
namespace {

using test::TempDir;

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string write_text(const TempDir& dir, const std::string& name, const std::string& text) {
  const std::string path = dir.file(name);
  std::ofstream(path) << text;
  return path;
}

const FieldRow* find_row(const std::vector<FieldRow>& rows, const std::string& path) {
  for (const FieldRow& row : rows) {
    if (row.path == path) return &row;
  }
  return nullptr;
}

TEST(Presets, EveryFileInConfigsIsReadAndValid) {
  int matchers = 0;
  std::set<std::string> methods;  // a method may have more than one preset (graph, graph-keep-all)
  for (const auto& entry : std::filesystem::directory_iterator("configs")) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string path = entry.path().string();
    const ConfigNode root = ConfigNode::load(path);
    if (root.has("method")) {  // a method's config may have a section named `matcher`
      EXPECT_NO_THROW(method_fields(root.at("method").as_string(), path)) << path;
      methods.insert(root.at("method").as_string());
    } else {
      ASSERT_TRUE(root.has("matcher")) << path << ": neither a matcher nor a method preset";
      EXPECT_NO_THROW(load_matcher(path)) << path;
      ++matchers;
    }
  }
  EXPECT_GE(matchers, 12);
  EXPECT_EQ(methods.size(), method_names().size());
}

TEST(Presets, EachMethodsPresetHoldsExactlyTheLibraryDefaults) {
  for (const std::string& name : method_names()) {
    const std::string path = "configs/" + name + ".yaml";
    ASSERT_TRUE(std::filesystem::exists(path)) << path;
    const std::vector<FieldRow> defaults = method_fields(name);
    EXPECT_GT(defaults.size(), 5u) << name;
    EXPECT_EQ(method_fields(name, path), defaults) << path << " differs from `slam2d config dump " << name << "`";
  }
}

TEST(Presets, ADumpReadsBackToTheSameFieldsForEveryMethodAndMatcher) {
  TempDir dir;
  for (const std::string& name : configurable_names()) {
    const std::string path = write_text(dir, name + ".yaml", default_preset(name));
    if (ConfigNode::load(path).has("method")) {
      EXPECT_EQ(method_fields(name, path), method_fields(name)) << name;
    } else {
      EXPECT_NO_THROW(load_matcher(path)) << name;
    }
  }
}

TEST(Presets, AValueInAPresetReachesTheConfigAndSectionsNest) {
  TempDir dir;
  const std::string path = write_text(dir, "graph.yaml", "method: graph\nmap_resolution: 0.1\n");
  const GraphSlamConfig config = read_method_preset(path, "graph", GraphSlamConfig{});
  EXPECT_EQ(config.map_resolution, 0.1);
  const std::vector<FieldRow> rows = method_fields("graph", path);
  ASSERT_NE(find_row(rows, "map_resolution"), nullptr);
  EXPECT_EQ(find_row(rows, "map_resolution")->value, "0.1");
  // A nested section: Hector's matcher iterations.
  const std::string hector = write_text(dir, "hector.yaml", "method: hector\nmatcher:\n  fine_iterations: 9\n");
  const std::vector<FieldRow> hector_rows = method_fields("hector", hector);  // kept: `fine` points into it
  const FieldRow* fine = find_row(hector_rows, "matcher.fine_iterations");
  ASSERT_NE(fine, nullptr);
  EXPECT_EQ(fine->value, "9");
}

// The ParseError of `text` read as a graph preset, or "" when it is accepted.
std::string preset_error(const std::string& text) {
  TempDir dir;
  const std::string path = write_text(dir, "p.yaml", text);
  try {
    method_fields("graph", path);
  } catch (const ParseError& e) {
    const std::string message = e.what();
    return message.substr(message.find("p.yaml"));
  }
  return "";
}

TEST(Presets, BadPresetsAreRefusedAtTheirLine) {
  EXPECT_EQ(preset_error("method: graph\nmap_resolution: 0.1\n"), "");
  EXPECT_NE(preset_error("method: graph\nmap_resolutoin: 0.1\n").find("p.yaml:2"), std::string::npos);  // typo
  EXPECT_NE(preset_error("method: graph\nmap_resolution: -1\n").find("p.yaml:2"), std::string::npos);   // range
  EXPECT_NE(preset_error("method: graph\nmap_resolution: fine\n").find("p.yaml:2"), std::string::npos);  // type
  EXPECT_NE(preset_error("method: hector\n").find("p.yaml:1"), std::string::npos);  // another method's preset
  EXPECT_NE(preset_error("map_resolution: 0.1\n").find("method"), std::string::npos);  // no method key
  EXPECT_THROW(method_fields("teleport"), Error);
  EXPECT_THROW(default_preset("teleport"), Error);
}

TEST(ConfigurationDocs, ThePageIsWhatTheFieldTablesGive) {
  EXPECT_EQ(read_text("docs/configuration.md"), configuration_docs())
      << "regenerate with: build/release/bin/slam2d config docs > docs/configuration.md";
}

}  // namespace
}  // namespace slam2d
