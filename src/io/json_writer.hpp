// The one JSON writer of rvc: verdicts, counters, summaries of replay, perf
// and bridge all go through it, so every string is escaped the same way
// (RFC 8259: quotes, backslashes and every control character) and numbers
// print in one form (integers without ".0", other doubles in the shortest
// form that reads back exactly, non-finite values as null).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <type_traits>

namespace rvc::io {

// Appends `s` as a JSON string literal.
void append_json_string(std::string& out, std::string_view s);
// Appends a number in the shortest round-trip form; NaN and infinities as null.
void append_number(std::string& out, double v);
// NaN, Infinity, -Infinity: how a message's non-finite float is written (as
// Python's json module writes them; rvc's JSON readers accept them back).
inline const char* non_finite_word(double v) { return v != v ? "NaN" : v < 0 ? "-Infinity" : "Infinity"; }
// Appends a number with a fixed count of decimals (wall-clock seconds, rates).
void append_fixed(std::string& out, double v, int decimals);

// Builds one JSON object, key by key:
//   JsonObject().add("sent", 12).add("to", uri).str()  ->  {"sent":12,"to":"..."}
class JsonObject {
 public:
  JsonObject& add(std::string_view key, std::string_view value);
  JsonObject& add(std::string_view key, const char* value) { return add(key, std::string_view(value)); }
  JsonObject& add(std::string_view key, const std::string& value) { return add(key, std::string_view(value)); }
  JsonObject& add(std::string_view key, bool value);
  JsonObject& add(std::string_view key, double value);
  template <typename T, typename = std::enable_if_t<std::is_integral_v<T> && !std::is_same_v<T, bool>>>
  JsonObject& add(std::string_view key, T value) {
    if constexpr (std::is_signed_v<T>) return add_int(key, static_cast<int64_t>(value));
    else return add_uint(key, static_cast<uint64_t>(value));
  }
  JsonObject& add_fixed(std::string_view key, double value, int decimals);
  JsonObject& add(std::string_view key, const JsonObject& nested);
  // `json` must already be valid JSON (an array built elsewhere, a payload).
  JsonObject& add_raw(std::string_view key, std::string_view json);

  // The object, closed: "{...}". The builder stays usable.
  std::string str() const { return body_.empty() ? "{}" : body_ + "}"; }

 private:
  JsonObject& add_int(std::string_view key, int64_t value);
  JsonObject& add_uint(std::string_view key, uint64_t value);
  void key(std::string_view k);
  std::string body_;  // "{" + members so far, without the closing brace
};

// A JSON array of already-built values: JsonArray().add(obj).add(obj).str().
class JsonArray {
 public:
  JsonArray& add(const JsonObject& value);
  JsonArray& add_raw(std::string_view json);
  std::string str() const { return body_.empty() ? "[]" : body_ + "]"; }

 private:
  std::string body_;
};

}  // namespace rvc::io
