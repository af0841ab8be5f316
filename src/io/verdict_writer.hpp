// Verdicts as JSON lines: {"time":12,"property":"p1","value":false}.
// Discrete times print as integers (step indices), dense times in the
// shortest form that reads back to the same double.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "io/json_writer.hpp"

namespace rvc::io {

// Appends one verdict line (with '\n') to `out`. The *_at forms take the
// time's JSON text: dense time prints exact decimal seconds (at most 9
// decimals, never an exponent: spec::append_seconds).
void append_verdict_at(std::string& out, std::string_view time, std::string_view property, bool value);
void append_robustness_at(std::string& out, std::string_view time, std::string_view property, double value);
void append_verdict(std::string& out, double time, bool discrete, std::string_view property, bool value);
// The same with a robustness value: {"time":3,"property":"p1","value":-1.5}
// (infinities as the strings "inf" and "-inf", as JSON has no number for them).
void append_robustness(std::string& out, double time, bool discrete, std::string_view property, double value);
// Bounded future (issue 29): adds "known_at", the instant a delayed verdict
// became known, to the verdict line just appended:
// {"time":3,"property":"p1","value":false,"known_at":5}. Past-only
// properties' lines have no such field (known at "time").
inline void append_known_at_text(std::string& out, std::string_view known_at) {
  out.resize(out.size() - 2);  // "}\n"
  out += ",\"known_at\":";
  out += known_at;
  out += "}\n";
}
inline void append_known_at(std::string& out, double known_at) {
  std::string t;
  append_number(t, known_at);
  append_known_at_text(out, t);
}

// Appends one verdict as a CDR sample of rvc_msgs/msg/Verdict (src/msg/definitions;
// little-endian, with its 4-byte encapsulation header): time, property, value,
// stamp (from `stamp_ns`), robustness (NaN for a Boolean verdict), explanation.
void append_verdict_cdr(std::string& out, double time, std::string_view property, bool value, uint64_t stamp_ns,
                        double robustness, const std::vector<std::string>* explanation);

}  // namespace rvc::io
