#include "io/verdict_writer.hpp"


namespace rvc::io {

void append_verdict(std::string& out, double time, bool /*discrete: times print alike*/, std::string_view property, bool value) {
  out += "{\"time\":";
  append_number(out, time);
  out += ",\"property\":";
  append_json_string(out, property);
  out += value ? ",\"value\":true}\n" : ",\"value\":false}\n";
}

}  // namespace rvc::io
