#include "io/json_writer.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace rvc::io {

void append_json_string(std::string& out, std::string_view s) {
  static constexpr char kHex[] = "0123456789abcdef";
  out.push_back('"');
  for (char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      case '\b': out += "\\b"; break;
      case '\f': out += "\\f"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          const char esc[] = {'\\', 'u', '0', '0', kHex[(c >> 4) & 0xf], kHex[c & 0xf]};
          out.append(esc, sizeof esc);
        } else {
          out.push_back(c);
        }
    }
  }
  out.push_back('"');
}

void append_number(std::string& out, double v) {
  char buf[64];
  if (!std::isfinite(v)) {
    out += "null";
    return;
  }
  if (v == std::floor(v) && std::fabs(v) < 9e15) {
    auto [p, ec] = std::to_chars(buf, buf + sizeof buf, static_cast<int64_t>(v));
    out.append(buf, p);
    return;
  }
  // Integral values from 9e15 up in scientific form: the shortest form of 2^69
  // is 21 plain digits, an integer too big for simdjson's DOM (rvc msg encode
  // refused what rvc msg decode wrote, found by fuzz_cdr).
  const auto format = v == std::floor(v) ? std::chars_format::scientific : std::chars_format::general;
  auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v, format);
  out.append(buf, p);
}

void append_fixed(std::string& out, double v, int decimals) {
  if (!std::isfinite(v)) {
    out += "null";
    return;
  }
  char buf[64];
  auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::fixed, decimals);
  if (ec != std::errc()) {  // too long for the buffer: shortest form instead
    append_number(out, v);
    return;
  }
  out.append(buf, p);
}

void JsonObject::key(std::string_view k) {
  body_.push_back(body_.empty() ? '{' : ',');
  append_json_string(body_, k);
  body_.push_back(':');
}

JsonObject& JsonObject::add(std::string_view k, std::string_view value) {
  key(k);
  append_json_string(body_, value);
  return *this;
}

JsonObject& JsonObject::add(std::string_view k, bool value) {
  key(k);
  body_ += value ? "true" : "false";
  return *this;
}

JsonObject& JsonObject::add(std::string_view k, double value) {
  key(k);
  append_number(body_, value);
  return *this;
}

JsonObject& JsonObject::add_int(std::string_view k, int64_t value) {
  key(k);
  body_ += std::to_string(value);
  return *this;
}

JsonObject& JsonObject::add_uint(std::string_view k, uint64_t value) {
  key(k);
  body_ += std::to_string(value);
  return *this;
}

JsonObject& JsonObject::add_fixed(std::string_view k, double value, int decimals) {
  key(k);
  append_fixed(body_, value, decimals);
  return *this;
}

JsonObject& JsonObject::add(std::string_view k, const JsonObject& nested) { return add_raw(k, nested.str()); }

JsonObject& JsonObject::add_raw(std::string_view k, std::string_view json) {
  key(k);
  body_ += json;
  return *this;
}

JsonArray& JsonArray::add(const JsonObject& value) { return add_raw(value.str()); }

JsonArray& JsonArray::add_raw(std::string_view json) {
  body_.push_back(body_.empty() ? '[' : ',');
  body_ += json;
  return *this;
}

}  // namespace rvc::io
