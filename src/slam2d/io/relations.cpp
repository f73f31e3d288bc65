// SPDX-License-Identifier: BSD-3-Clause
// Relations files of Kuemmerle et al. 2009, "On measuring the accuracy of SLAM algorithms".
#include "slam2d/io/relations.hpp"

#include <array>
#include <cmath>
#include <string_view>

#include "slam2d/core/error.hpp"
#include "slam2d/io/atomic_file.hpp"
#include "slam2d/io/detail/number_format.hpp"
#include "slam2d/io/detail/text_input.hpp"

namespace slam2d {

namespace {

constexpr std::array<std::string_view, 8> kFieldNames = {"t1", "t2", "x", "y", "z", "roll", "pitch", "yaw"};

Relation parse_relation(const LineReader& reader, const std::vector<std::string_view>& fields) {
  if (fields.size() != kFieldNames.size()) {
    reader.fail("expected 8 numbers (t1 t2 x y z roll pitch yaw), got " + std::to_string(fields.size()));
  }
  std::array<double, kFieldNames.size()> v{};
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = parse_finite_field(reader, fields[i], kFieldNames[i]);
  // z, roll and pitch are checked (no NaN slips through) but have no place in 2D.
  return Relation{.stamp_from = v[0], .stamp_to = v[1], .T_from_to = SE2(v[2], v[3], v[7]),
                  .line = reader.line_number()};
}

}  // namespace

std::vector<Relation> read_relations(const std::string& path) {
  LineReader reader(path);
  std::vector<Relation> relations;
  std::string line;
  while (reader.next(line)) {
    if (is_blank_or_comment(line)) continue;
    relations.push_back(parse_relation(reader, split_fields(line)));
  }
  return relations;
}

void write_relations(const std::string& path, const std::vector<Relation>& relations) {
  AtomicFile file(path, has_gzip_extension(path));
  std::string text;
  for (std::size_t i = 0; i < relations.size(); ++i) {
    const Relation& r = relations[i];
    const std::array<double, 5> values = {r.stamp_from, r.stamp_to, r.T_from_to.x(), r.T_from_to.y(),
                                          r.T_from_to.theta()};
    for (double value : values) {
      if (!std::isfinite(value)) throw Error(path + ": relation " + std::to_string(i) + " has a non-finite value");
    }
    text.clear();
    for (std::size_t k = 0; k < 4; ++k) {
      append_number(text, values[k]);
      text += ' ';
    }
    text += "0 0 0 ";  // z roll pitch
    append_number(text, values[4]);
    text += '\n';
    file.stream() << text;
  }
  file.commit();
}

}  // namespace slam2d
