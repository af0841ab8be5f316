#include "msg/msg_values.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace rvc::msg {

namespace {

bool py_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }

std::string_view strip(std::string_view s) {
  while (!s.empty() && py_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && py_space(s.back())) s.remove_suffix(1);
  return s;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return out;
}

int digit_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'z') return c - 'a' + 10;
  if (c >= 'A' && c <= 'Z') return c - 'A' + 10;
  return 99;
}

// Digits of `base` with single '_' between them (Python's integer and float
// literals); `leading_underscore`: one '_' may come first (after 0x, 0o, 0b).
// The digits without underscores, or false. Stops at nothing: all of s.
bool py_digits(std::string_view s, int base, bool leading_underscore, std::string& digits) {
  digits.clear();
  bool after_digit = false;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '_') {
      if (!(after_digit || (i == 0 && leading_underscore)) || i + 1 == s.size()) return false;
      after_digit = false;
      continue;
    }
    if (digit_value(s[i]) >= base) return false;
    digits.push_back(s[i]);
    after_digit = true;
  }
  return !digits.empty();
}

// Python's int(text), else int(text, 0): the magnitude and sign. False when
// neither reads it or it does not fit in 64 bits (then no type can hold it).
bool py_int(std::string_view text, bool& negative, uint64_t& magnitude, bool& too_big) {
  too_big = false;
  std::string_view s = strip(text);
  negative = false;
  if (!s.empty() && (s[0] == '+' || s[0] == '-')) negative = s[0] == '-', s.remove_prefix(1);
  int base = 10;
  std::string digits;
  if (!py_digits(s, 10, false, digits)) {  // int(text) fails: int(text, 0)
    if (s.size() > 2 && s[0] == '0') {
      const char p = static_cast<char>(s[1] | 0x20);
      base = p == 'x' ? 16 : p == 'o' ? 8 : p == 'b' ? 2 : 0;
    }
    if (base == 10 || base == 0 || !py_digits(s.substr(2), base, true, digits)) return false;
  }
  auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), magnitude, base);
  if (ec == std::errc::result_out_of_range) return too_big = true, false;
  return ec == std::errc() && end == digits.data() + digits.size();
}

// Python's float(text): false when it does not read it. Out-of-range
// magnitudes are +-inf and 0, as in Python.
bool py_float(std::string_view text, double& value) {
  std::string_view s = strip(text);
  bool negative = false;
  if (!s.empty() && (s[0] == '+' || s[0] == '-')) negative = s[0] == '-', s.remove_prefix(1);
  const std::string word = lower(s);
  if (word == "nan") return value = std::nan(""), true;  // Python keeps no NaN sign
  if (word == "inf" || word == "infinity") return value = negative ? -HUGE_VAL : HUGE_VAL, true;
  // [digits][.[digits]][(e|E)[sign]digits], digits somewhere before the exponent.
  size_t e = s.find_first_of("eE");
  std::string_view mantissa = s.substr(0, e), exponent = e == std::string_view::npos ? "" : s.substr(e + 1);
  const size_t dot = mantissa.find('.');
  std::string_view whole = mantissa.substr(0, dot), fraction = dot == std::string_view::npos ? "" : mantissa.substr(dot + 1);
  std::string clean = negative ? "-" : "", digits;
  if (!whole.empty()) {
    if (!py_digits(whole, 10, false, digits)) return false;
    clean += digits;
  }
  if (dot != std::string_view::npos) {
    clean += '.';
    if (!fraction.empty()) {
      if (!py_digits(fraction, 10, false, digits)) return false;
      clean += digits;
    }
  }
  if (whole.empty() && fraction.empty()) return false;
  if (e != std::string_view::npos) {
    clean += 'e';
    if (!exponent.empty() && (exponent[0] == '+' || exponent[0] == '-')) clean += exponent[0], exponent.remove_prefix(1);
    if (!py_digits(exponent, 10, false, digits)) return false;
    clean += digits;
  }
  errno = 0;
  value = std::strtod(clean.c_str(), nullptr);  // the text is plain decimal here; ERANGE gives +-inf or 0, as Python
  return true;
}

void append_float(std::string& json, double v) {
  if (std::isnan(v)) return void(json += "NaN");
  if (std::isinf(v)) return void(json += v < 0 ? "-Infinity" : "Infinity");
  if (v == 0) return void(json += std::signbit(v) ? "-0.0" : "0.0");
  char buf[64];
  // Shortest form, a float as a float ("5.0"); large integral values with an
  // exponent: 21 plain digits would be an integer too big for a JSON reader.
  const bool integral = v == std::floor(v);
  const auto format = integral && std::fabs(v) >= 1e15 ? std::chars_format::scientific : std::chars_format::general;
  auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v, format);
  json.append(buf, p);
  if (integral && format == std::chars_format::general && json.find_first_of(".e", json.size() - (p - buf)) == std::string::npos)
    json += ".0";
}

void append_string(std::string& json, std::string_view s) {
  static constexpr char kHex[] = "0123456789abcdef";
  json += '"';
  for (char c : s) {
    if (c == '"' || c == '\\') {
      json += '\\';
      json += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      json += "\\u00";
      json += kHex[(c >> 4) & 0xf];
      json += kHex[c & 0xf];
    } else {
      json += c;
    }
  }
  json += '"';
}

bool integer_range(Prim prim, bool negative, uint64_t magnitude) {
  uint64_t max = 0, min_magnitude = 0;  // [-min_magnitude, max]
  switch (prim) {
    case Prim::Int8: max = 127, min_magnitude = 128; break;
    case Prim::UInt8: case Prim::Byte: case Prim::Char: max = 255; break;
    case Prim::Int16: max = 32767, min_magnitude = 32768; break;
    case Prim::UInt16: max = 65535; break;
    case Prim::Int32: max = 2147483647, min_magnitude = 2147483648u; break;
    case Prim::UInt32: max = 4294967295u; break;
    case Prim::Int64: max = 9223372036854775807u, min_magnitude = 9223372036854775808u; break;
    default: max = ~uint64_t{0}; break;
  }
  return negative ? magnitude <= min_magnitude : magnitude <= max;
}

// Well-formed UTF-8 (rosidl reads definitions as UTF-8; CDR strings must be).
bool utf8(std::string_view s) {
  for (size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      ++i;
      continue;
    }
    size_t n = 0;  // continuation bytes
    uint32_t cp = 0;
    if ((c >> 5) == 6) n = 1, cp = c & 0x1f;
    else if ((c >> 4) == 14) n = 2, cp = c & 0x0f;
    else if ((c >> 3) == 30) n = 3, cp = c & 0x07;
    else return false;
    if (i + n >= s.size()) return false;
    for (size_t k = 1; k <= n; ++k) {
      const auto d = static_cast<unsigned char>(s[i + k]);
      if ((d >> 6) != 2) return false;
      cp = cp << 6 | (d & 0x3f);
    }
    // Overlong forms, surrogates and code points past U+10FFFF are not UTF-8.
    if ((n == 1 && cp < 0x80) || (n == 2 && (cp < 0x800 || (cp >= 0xd800 && cp <= 0xdfff))) ||
        (n == 3 && (cp < 0x10000 || cp > 0x10ffff)))
      return false;
    i += n + 1;
  }
  return true;
}

// One primitive value (rosidl's parse_primitive_value_string).
bool scalar(Prim prim, uint32_t string_bound, std::string_view text, std::string& json, std::string& error) {
  const std::string shown(text);
  if (prim == Prim::Bool) {
    const std::string v = lower(strip(text));
    if (v == "true" || v == "1") return json += "true", true;
    if (v == "false" || v == "0") return json += "false", true;
    error = "a bool value is true, false, 1 or 0 (any case), not '" + shown + "'";
    return false;
  }
  if (prim_is_integer(prim) || prim == Prim::Byte || prim == Prim::Char) {
    bool negative = false, too_big = false;
    uint64_t magnitude = 0;
    if (!py_int(text, negative, magnitude, too_big) && !too_big) {
      error = "not an integer for " + std::string(prim_name(prim)) + ": '" + shown + "'";
      return false;
    }
    if (too_big || !integer_range(prim, negative, magnitude)) {
      error = shown + " does not fit in " + prim_name(prim);
      return false;
    }
    if (negative && magnitude) json += '-';
    json += std::to_string(magnitude);
    return true;
  }
  if (prim_is_float(prim)) {
    double v = 0;
    if (!py_float(text, v)) {
      error = "not a " + std::string(prim_name(prim)) + " value: '" + shown + "'";
      return false;
    }
    append_float(json, v);
    return true;
  }
  if (prim == Prim::String || prim == Prim::WString) {
    std::string_view s = strip(text);
    std::string value(s);
    for (char quote : {'"', '\''}) {
      if (s.empty() || s.front() != quote || s.back() != quote) continue;
      std::string_view inner = s.size() >= 2 ? s.substr(1, s.size() - 2) : std::string_view();
      value.clear();
      for (size_t i = 0; i < inner.size(); ++i) {
        if (inner[i] == quote && (i == 0 || inner[i - 1] != '\\')) {
          error = "a quote inside the string is not escaped: '" + shown + "'";
          return false;
        }
        if (inner[i] == '\\' && i + 1 < inner.size() && inner[i + 1] == quote) continue;  // \" is "
        value += inner[i];
      }
      break;
    }
    if (!utf8(value) || value.find('\0') != std::string::npos) {
      error = "a string value must be UTF-8 text without NUL bytes";
      return false;
    }
    if (string_bound && value.size() > string_bound) {
      error = "a string of " + std::to_string(value.size()) + " bytes over its bound " + std::to_string(string_bound);
      return false;
    }
    append_string(json, value);
    return true;
  }
  error = "no value of type " + std::string(prim_name(prim));
  return false;
}

// The elements of a string array's text (rosidl's parse_string_array_value_string):
// quoted elements up to their closing quote, others up to the next comma.
bool string_elements(std::string_view s, std::vector<std::string>& out, std::string& error) {
  while (!s.empty()) {
    while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
    if (s.empty()) break;
    if (s.front() == ',') return error = "an element is missing before a ','", false;
    if (s.front() == '"' || s.front() == '\'') {
      const char quote = s.front();
      size_t i = 1;
      std::string value;
      for (; i < s.size(); ++i) {
        if (s[i] == '\\' && i + 1 < s.size() && s[i + 1] == quote) {
          value += quote;
          ++i;
        } else if (s[i] == quote) {
          break;
        } else {
          value += s[i];
        }
      }
      if (i >= s.size()) return error = "a string element's quote is not closed", false;
      out.push_back(value);
      s.remove_prefix(i + 1);
    } else {
      const size_t comma = s.find(',');
      out.emplace_back(s.substr(0, comma));
      s.remove_prefix(comma == std::string_view::npos ? s.size() : comma);
    }
    while (!s.empty() && s.front() == ' ') s.remove_prefix(1);
    if (!s.empty() && s.front() == ',') s.remove_prefix(1);
  }
  return true;
}

}  // namespace

bool rosidl_value(const FieldType& type, std::string_view text, std::string& json, std::string& error) {
  json.clear();
  if (type.prim == Prim::Message) {
    error = "a field of a message type has no default value";
    return false;
  }
  if (type.array == ArrayKind::None) return scalar(type.prim, type.string_bound, text, json, error);
  const std::string_view s = strip(text);
  if (s.size() < 2 || s.front() != '[' || s.back() != ']') {
    error = "an array value is written [a, b, ...], not '" + std::string(text) + "'";
    return false;
  }
  const std::string_view inside = s.substr(1, s.size() - 2);
  std::vector<std::string> elements;
  if (type.prim == Prim::String || type.prim == Prim::WString) {
    if (!string_elements(inside, elements, error)) return false;
  } else if (!inside.empty()) {
    for (size_t start = 0;;) {
      const size_t comma = inside.find(',', start);
      elements.emplace_back(inside.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
      if (comma == std::string_view::npos) break;
      start = comma + 1;
    }
  }
  if (type.array == ArrayKind::Fixed && elements.size() != type.array_size) {
    error = "the array needs exactly " + std::to_string(type.array_size) + " elements, not " +
            std::to_string(elements.size());
    return false;
  }
  if (type.array == ArrayKind::Bounded && elements.size() > type.array_size) {
    error = "the array has at most " + std::to_string(type.array_size) + " elements, not " +
            std::to_string(elements.size());
    return false;
  }
  json += '[';
  for (size_t i = 0; i < elements.size(); ++i) {
    if (i) json += ',';
    std::string element_error;
    if (!scalar(type.prim, type.string_bound, strip(elements[i]), json, element_error)) {
      error = "element " + std::to_string(i) + ": " + element_error;
      return false;
    }
  }
  json += ']';
  return true;
}

}  // namespace rvc::msg
