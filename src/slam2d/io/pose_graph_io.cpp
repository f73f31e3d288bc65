// SPDX-License-Identifier: BSD-3-Clause
// 2D pose graph files: g2o (Kuemmerle et al. 2011, "g2o: A general framework for graph optimization")
// and TORO (Grisetti et al. 2007, "A tree parameterization for efficiently computing maximum
// likelihood maps using gradient descent"), which HOG-Man also reads.
#include "slam2d/io/pose_graph_io.hpp"

#include <array>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string_view>
#include <unordered_map>
#include <utility>

#include "slam2d/core/error.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/detail/number_format.hpp"
#include "slam2d/io/detail/text_input.hpp"
#include "slam2d/io/input_limits.hpp"

namespace slam2d {

namespace {

enum class Tag { kVertex, kEdge, kFix, kOther };

// How one format spells its lines. FIX (g2o, also read by HOG-Man) belongs to neither format.
struct FormatSpec {
  PoseGraphFormat format;
  std::string_view name;
  std::string_view vertex_tag;
  std::string_view edge_tag;
  // Information entries (row, column) in file order, and their names for messages.
  std::array<std::pair<int, int>, 6> information_order;
  std::array<std::string_view, 6> information_names;
};

constexpr FormatSpec kG2o = {PoseGraphFormat::kG2o, "g2o", "VERTEX_SE2", "EDGE_SE2",
                             {{{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}}},
                             {"I11", "I12", "I13", "I22", "I23", "I33"}};
constexpr FormatSpec kToro = {PoseGraphFormat::kToro, "TORO", "VERTEX2", "EDGE2",
                              {{{0, 0}, {0, 1}, {1, 1}, {2, 2}, {0, 2}, {1, 2}}},
                              {"I11", "I12", "I22", "I33", "I13", "I23"}};

const FormatSpec& spec_of(PoseGraphFormat format) { return format == PoseGraphFormat::kToro ? kToro : kG2o; }

// The tag's kind and, for vertices and edges, the format it belongs to.
std::pair<Tag, const FormatSpec*> classify(std::string_view tag) {
  for (const FormatSpec* spec : {&kG2o, &kToro}) {
    if (tag == spec->vertex_tag) return {Tag::kVertex, spec};
    if (tag == spec->edge_tag) return {Tag::kEdge, spec};
  }
  return {tag == "FIX" ? Tag::kFix : Tag::kOther, nullptr};
}

void expect_field_count(const LineReader& reader, const std::vector<std::string_view>& fields, std::size_t count,
                        std::string_view layout) {
  if (fields.size() != count) {
    reader.fail(std::string(fields[0]) + ": expected " + std::to_string(count - 1) + " values (" +
                std::string(layout) + "), got " + std::to_string(fields.size() - 1));
  }
}

GraphVertex parse_vertex(const LineReader& reader, const std::vector<std::string_view>& fields) {
  expect_field_count(reader, fields, 5, "id x y theta");
  // One statement per field, so the first bad field is the one reported.
  const int id = parse_int_field(reader, fields[1], "vertex id");
  const double x = parse_finite_field(reader, fields[2], "x");
  const double y = parse_finite_field(reader, fields[3], "y");
  const double theta = parse_finite_field(reader, fields[4], "theta");
  return GraphVertex{.id = id, .pose = SE2(x, y, theta)};
}

GraphEdge parse_edge(const LineReader& reader, const std::vector<std::string_view>& fields, const FormatSpec& spec) {
  if (fields.size() != 12) {
    std::string layout = "from to dx dy dtheta";
    for (std::string_view name : spec.information_names) layout.append(" ").append(name);
    expect_field_count(reader, fields, 12, layout);
  }
  GraphEdge edge;
  edge.from = parse_int_field(reader, fields[1], "from id");
  edge.to = parse_int_field(reader, fields[2], "to id");
  const double dx = parse_finite_field(reader, fields[3], "dx");
  const double dy = parse_finite_field(reader, fields[4], "dy");
  edge.T_from_to = SE2(dx, dy, parse_finite_field(reader, fields[5], "dtheta"));
  for (std::size_t k = 0; k < 6; ++k) {
    const auto [row, col] = spec.information_order[k];
    const double value = parse_finite_field(reader, fields[6 + k], spec.information_names[k]);
    edge.information(row, col) = value;  // symmetric by construction
    edge.information(col, row) = value;
  }
  return edge;
}

// Reads a pose graph line by line, tracking which format the file is in and which ids are taken.
class GraphFileReader {
 public:
  explicit GraphFileReader(const std::string& path) : reader_(path) {}

  PoseGraphFile read() {
    std::string line;
    while (reader_.next(line)) {
      if (is_blank_or_comment(line)) continue;
      read_line(split_fields(line));
    }
    return std::move(graph_);
  }

 private:
  void read_line(const std::vector<std::string_view>& fields) {
    const auto [tag, spec] = classify(fields[0]);
    if ((tag == Tag::kVertex || tag == Tag::kEdge) &&
        graph_.vertices.size() + graph_.edges.size() >= input_limits().max_graph_elements) {
      reader_.fail("more than " + std::to_string(input_limits().max_graph_elements) +
                   " vertices and edges (max_graph_elements; " + limit_hint("max_graph_elements") + ")");
    }
    switch (tag) {
      case Tag::kVertex:
        settle_format(*spec, fields[0]);
        add_vertex(parse_vertex(reader_, fields));
        break;
      case Tag::kEdge:
        settle_format(*spec, fields[0]);
        graph_.edges.push_back(parse_edge(reader_, fields, *spec));
        break;
      case Tag::kFix:
        if (fields.size() < 2) reader_.fail("FIX: expected at least one vertex id");
        for (std::size_t i = 1; i < fields.size(); ++i) graph_.fixed.push_back(parse_int_field(reader_, fields[i], "FIX id"));
        break;
      case Tag::kOther:
        ++graph_.skipped_lines;
        break;
    }
  }

  // The first vertex or edge line fixes the format; a line of the other format is an error.
  void settle_format(const FormatSpec& spec, std::string_view tag) {
    if (!format_line_) {
      graph_.format = spec.format;
      format_line_ = reader_.line_number();
    } else if (graph_.format != spec.format) {
      const std::string file_format(spec_of(graph_.format).name);
      reader_.fail("mixed formats: " + std::string(spec.name) + " tag " + std::string(tag) + " in a " + file_format +
                   " file (" + file_format + " since line " + std::to_string(*format_line_) + ")");
    }
  }

  void add_vertex(const GraphVertex& vertex) {
    const auto [it, inserted] = vertex_lines_.emplace(vertex.id, reader_.line_number());
    if (!inserted) {
      reader_.fail("duplicate vertex id " + std::to_string(vertex.id) + " (first on line " +
                   std::to_string(it->second) + ")");
    }
    graph_.vertices.push_back(vertex);
  }

  LineReader reader_;
  PoseGraphFile graph_;
  std::optional<std::size_t> format_line_;             // line of the first vertex or edge
  std::unordered_map<int, std::size_t> vertex_lines_;  // id -> line
};

void append_numbers(std::string& text, std::initializer_list<double> values) {
  for (double value : values) {
    text += ' ';
    append_number(text, value);
  }
}

// Writes `graph` in the format `spec`: vertices, FIX, then edges. The information matrix's upper
// triangle is written (in the format's order), as g2o and TORO do.
void write_pose_graph(const std::string& path, const PoseGraphFile& graph, const FormatSpec& spec) {
  AtomicFile file(path, has_gzip_extension(path));
  std::string text;
  for (const GraphVertex& v : graph.vertices) {
    if (!v.pose.vector().allFinite()) {
      throw Error(path + ": vertex " + std::to_string(v.id) + " has a non-finite pose");
    }
    text.assign(spec.vertex_tag).append(" ").append(std::to_string(v.id));
    append_numbers(text, {v.pose.x(), v.pose.y(), v.pose.theta()});
    file.stream() << text << '\n';
  }
  if (!graph.fixed.empty()) {
    text = "FIX";
    for (int id : graph.fixed) text.append(" ").append(std::to_string(id));
    file.stream() << text << '\n';
  }
  for (const GraphEdge& e : graph.edges) {
    if (!e.T_from_to.vector().allFinite() || !e.information.allFinite()) {
      throw Error(path + ": edge " + std::to_string(e.from) + " -> " + std::to_string(e.to) +
                  " has a non-finite value");
    }
    text.assign(spec.edge_tag).append(" ").append(std::to_string(e.from)).append(" ").append(std::to_string(e.to));
    append_numbers(text, {e.T_from_to.x(), e.T_from_to.y(), e.T_from_to.theta()});
    for (const auto& [row, col] : spec.information_order) append_numbers(text, {e.information(row, col)});
    file.stream() << text << '\n';
  }
  file.commit();
}

}  // namespace

PoseGraphFile read_pose_graph(const std::string& path) { return GraphFileReader(path).read(); }

void write_g2o(const std::string& path, const PoseGraphFile& graph) { write_pose_graph(path, graph, kG2o); }

void write_toro(const std::string& path, const PoseGraphFile& graph) { write_pose_graph(path, graph, kToro); }

PoseGraphFormat pose_graph_format_of(const std::string& path) {
  std::filesystem::path name(path);
  if (name.extension() == ".gz") name = name.stem();  // the compression, not the format
  if (name.extension() == ".g2o") return PoseGraphFormat::kG2o;
  if (name.extension() == ".graph") return PoseGraphFormat::kToro;
  throw Error(path + ": the extension must be .g2o (g2o) or .graph (TORO), optionally + .gz");
}

void write_pose_graph(const std::string& path, const PoseGraphFile& graph) {
  write_pose_graph(path, graph, pose_graph_format_of(path) == PoseGraphFormat::kToro ? kToro : kG2o);
}

}  // namespace slam2d
