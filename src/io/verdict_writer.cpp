#include "io/verdict_writer.hpp"

#include <cmath>

namespace rvc::io {

void append_verdict(std::string& out, double time, bool /*discrete: times print alike*/, std::string_view property, bool value) {
  out += "{\"time\":";
  append_number(out, time);
  out += ",\"property\":";
  append_json_string(out, property);
  out += value ? ",\"value\":true}\n" : ",\"value\":false}\n";
}

void append_robustness(std::string& out, double time, bool /*discrete*/, std::string_view property, double value) {
  out += "{\"time\":";
  append_number(out, time);
  out += ",\"property\":";
  append_json_string(out, property);
  out += ",\"value\":";
  if (std::isinf(value)) out += value > 0 ? "\"inf\"" : "\"-inf\"";
  else append_number(out, value);
  out += "}\n";
}

}  // namespace rvc::io
