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

namespace {

// The length of the well-formed UTF-8 sequence at text[i] (RFC 3629: no overlong forms, no
// surrogates, nothing above U+10FFFF), or 0 when the bytes there are not one.
std::size_t utf8_sequence_length(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char lead = byte(i);
  std::size_t length = 0;
  unsigned char low = 0x80;
  unsigned char high = 0xBF;  // the range of the second byte
  if (lead >= 0xC2 && lead <= 0xDF) length = 2;
  else if (lead >= 0xE0 && lead <= 0xEF) {
    length = 3;
    if (lead == 0xE0) low = 0xA0;
    if (lead == 0xED) high = 0x9F;
  } else if (lead >= 0xF0 && lead <= 0xF4) {
    length = 4;
    if (lead == 0xF0) low = 0x90;
    if (lead == 0xF4) high = 0x8F;
  } else {
    return 0;
  }
  if (i + length > text.size()) return 0;
  if (byte(i + 1) < low || byte(i + 1) > high) return 0;
  for (std::size_t k = 2; k < length; ++k) {
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  }
  return length;
}

}  // namespace

std::string json_string(std::string_view text) {
  // Valid JSON text is Unicode: a byte that is not part of well-formed UTF-8 (a binary file's
  // junk in a skipped line's type) is written as U+FFFD, the replacement character.
  std::string out = "\"";
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x80) {
      const std::size_t length = utf8_sequence_length(text, i);
      if (length == 0) {
        out += "\\ufffd";
      } else {
        out.append(text.substr(i, length));
        i += length - 1;
      }
      continue;
    }
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (byte < 0x20 || byte == 0x7F) {
          char escaped[8];
          std::snprintf(escaped, sizeof(escaped), "\\u%04x", byte);
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
JsonObject& JsonObject::add(std::string_view key, const std::vector<double>& values) {
  std::string encoded = "[";
  for (std::size_t i = 0; i < values.size(); ++i) encoded += (i == 0 ? "" : ", ") + json_number(values[i]);
  return add_scalar(key, encoded + "]", std::to_string(values.size()) + " numbers");
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
