// SPDX-License-Identifier: BSD-3-Clause
#include "json.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace slam2d::cli {

std::string json_number(double value) {
  if (!std::isfinite(value)) return "null";
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string json_string(std::string_view text) {
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char escaped[8];
          std::snprintf(escaped, sizeof(escaped), "\\u%04x", c);
          out += escaped;
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

JsonObject& JsonObject::add_scalar(std::string_view key, std::string encoded, std::string plain) {
  members_.push_back({std::string(key), std::move(encoded), std::move(plain), nullptr});
  return *this;
}

JsonObject& JsonObject::add(std::string_view key, double value) {
  const std::string encoded = json_number(value);
  return add_scalar(key, encoded, encoded);
}
JsonObject& JsonObject::add(std::string_view key, std::size_t value) {
  return add_scalar(key, std::to_string(value), std::to_string(value));
}
JsonObject& JsonObject::add(std::string_view key, int value) {
  return add_scalar(key, std::to_string(value), std::to_string(value));
}
JsonObject& JsonObject::add(std::string_view key, bool value) {
  return add_scalar(key, value ? "true" : "false", value ? "true" : "false");
}
JsonObject& JsonObject::add(std::string_view key, std::string_view value) {
  return add_scalar(key, json_string(value), std::string(value));
}
JsonObject& JsonObject::add(std::string_view key, const std::optional<double>& value) {
  return value ? add(key, *value) : add_null(key);
}
JsonObject& JsonObject::add(std::string_view key, const std::vector<std::string>& values) {
  std::string encoded = "[";
  std::string plain;
  for (std::size_t i = 0; i < values.size(); ++i) {
    encoded += (i == 0 ? "" : ", ") + json_string(values[i]);
    plain += (i == 0 ? "" : "; ") + values[i];
  }
  return add_scalar(key, encoded + "]", values.empty() ? "none" : plain);
}
JsonObject& JsonObject::add(std::string_view key, const JsonObject& value) {
  members_.push_back({std::string(key), "", "", std::make_shared<const JsonObject>(value)});
  return *this;
}
JsonObject& JsonObject::merge(const JsonObject& other) {
  members_.insert(members_.end(), other.members_.begin(), other.members_.end());
  return *this;
}

JsonObject& JsonObject::add_null(std::string_view key) { return add_scalar(key, "null", "null"); }

std::string JsonObject::dump(int indent) const {
  const std::string inner(2 * (indent + 1), ' ');
  std::string out = "{";
  for (std::size_t i = 0; i < members_.size(); ++i) {
    const Member& member = members_[i];
    out += (i == 0 ? "\n" : ",\n") + inner + json_string(member.key) + ": ";
    out += member.object ? member.object->dump(indent + 1) : member.encoded;
  }
  out += members_.empty() ? "}" : "\n" + std::string(2 * indent, ' ') + "}";
  if (indent == 0) out += "\n";
  return out;
}

std::string JsonObject::text(int indent) const {
  std::string out;
  const std::string pad(2 * indent, ' ');
  for (const Member& member : members_) {
    if (member.object) {
      out += pad + member.key + ":" + (member.object->members_.empty() ? " none\n" : "\n");
      out += member.object->text(indent + 1);
    } else {
      out += pad + member.key + ": " + member.plain + "\n";
    }
  }
  return out;
}

}  // namespace slam2d::cli
