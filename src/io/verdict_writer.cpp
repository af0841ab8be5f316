#include "io/verdict_writer.hpp"

#include <cmath>
#include <cstring>

namespace rvc::io {

void append_verdict(std::string& out, double time, bool /*discrete: times print alike*/, std::string_view property, bool value) {
  std::string t;
  append_number(t, time);
  append_verdict_at(out, t, property, value);
}

void append_verdict_at(std::string& out, std::string_view time, std::string_view property, bool value) {
  out += "{\"time\":";
  out += time;
  out += ",\"property\":";
  append_json_string(out, property);
  out += value ? ",\"value\":true}\n" : ",\"value\":false}\n";
}

void append_robustness(std::string& out, double time, bool /*discrete*/, std::string_view property, double value) {
  std::string t;
  append_number(t, time);
  append_robustness_at(out, t, property, value);
}

void append_robustness_at(std::string& out, std::string_view time, std::string_view property, double value) {
  out += "{\"time\":";
  out += time;
  out += ",\"property\":";
  append_json_string(out, property);
  out += ",\"value\":";
  if (std::isinf(value)) out += value > 0 ? "\"inf\"" : "\"-inf\"";
  else append_number(out, value);
  out += "}\n";
}

namespace {

// XCDR1 little-endian: each primitive aligned to its size, counted from the
// end of the encapsulation header (`base`).
struct CdrOut {
  std::string& out;
  size_t base;
  void align(size_t n) {
    while ((out.size() - base) % n) out.push_back('\0');
  }
  template <typename T>
  void put(T v) {
    align(sizeof(T));
    char bytes[sizeof(T)];
    std::memcpy(bytes, &v, sizeof(T));  // little-endian hosts only (x86-64, aarch64), as the CDR decoder
    out.append(bytes, sizeof(T));
  }
  void put_string(std::string_view s) {
    put<uint32_t>(static_cast<uint32_t>(s.size() + 1));
    out.append(s);
    out.push_back('\0');
  }
};

}  // namespace

void append_verdict_cdr(std::string& out, double time, std::string_view property, bool value, uint64_t stamp_ns,
                        double robustness, const std::vector<std::string>* explanation) {
  out.append("\x00\x01\x00\x00", 4);  // CDR_LE
  CdrOut c{out, out.size()};
  c.put<double>(time);
  c.put_string(property);
  c.put<uint8_t>(value ? 1 : 0);
  c.put<int32_t>(static_cast<int32_t>(stamp_ns / 1000000000u));
  c.put<uint32_t>(static_cast<uint32_t>(stamp_ns % 1000000000u));
  c.put<double>(robustness);
  c.put<uint32_t>(explanation ? static_cast<uint32_t>(explanation->size()) : 0u);
  if (explanation)
    for (const auto& line : *explanation) c.put_string(line);
}

}  // namespace rvc::io
