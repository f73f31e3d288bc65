// SPDX-License-Identifier: BSD-3-Clause
#include "slam2d/io/config_text.hpp"

#include <algorithm>

namespace slam2d {

namespace {

// "m, >= 0; the doc", leaving out the parts a field does not have.
std::string comment(const FieldRow& row) {
  std::string head = row.unit;
  if (!row.range.empty()) head += (head.empty() ? "" : ", ") + row.range;
  if (head.empty()) return row.doc;
  return row.doc.empty() ? head : head + "; " + row.doc;
}

}  // namespace

std::string config_yaml(const std::vector<FieldRow>& rows, int indent) {
  std::vector<std::string> keys;
  std::size_t width = 0;
  for (const FieldRow& row : rows) {
    const std::string name = row.path.substr(row.path.rfind('.') == std::string::npos ? 0 : row.path.rfind('.') + 1);
    const std::size_t spaces = static_cast<std::size_t>(indent + 2 * row.depth);
    keys.push_back(row.list_item ? std::string(spaces, ' ') + "- " + name + ": " + row.value
                                 : std::string(spaces, ' ') + name + ":" + (row.is_section ? "" : " " + row.value));
    width = std::max(width, keys.back().size());
  }
  std::string text;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::string note = comment(rows[i]);
    text += keys[i];
    if (!note.empty()) text += std::string(width - keys[i].size() + 2, ' ') + "# " + note;
    text += '\n';
  }
  return text;
}

std::string config_markdown(const std::vector<FieldRow>& rows) {
  std::string text = "| field | default | unit | range | meaning |\n| --- | --- | --- | --- | --- |\n";
  for (const FieldRow& row : rows) {
    if (row.is_section && row.range.empty()) continue;  // a section: its fields carry the dotted path
    std::string range = row.range;
    std::replace(range.begin(), range.end(), '|', '/');  // a choice list inside a table cell
    text += "| `" + row.path + "` | " + row.value + " | " + row.unit + " | " + range + " | " + row.doc + " |\n";
  }
  return text;
}

}  // namespace slam2d
