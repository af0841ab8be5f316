// Verdicts as JSON lines: {"time":12,"property":"p1","value":false}.
// Discrete times print as integers (step indices), dense times in the
// shortest form that reads back to the same double.
#pragma once

#include <string>
#include <string_view>

#include "io/json_writer.hpp"

namespace rvc::io {

// Appends one verdict line (with '\n') to `out`.
void append_verdict(std::string& out, double time, bool discrete, std::string_view property, bool value);
// The same with a robustness value: {"time":3,"property":"p1","value":-1.5}
// (infinities as the strings "inf" and "-inf", as JSON has no number for them).
void append_robustness(std::string& out, double time, bool discrete, std::string_view property, double value);
// Bounded future (issue 29): adds "known_at", the instant a delayed verdict
// became known, to the verdict line just appended:
// {"time":3,"property":"p1","value":false,"known_at":5}. Past-only
// properties' lines have no such field (known at "time").
inline void append_known_at(std::string& out, double known_at) {
  out.resize(out.size() - 2);  // "}\n"
  out += ",\"known_at\":";
  append_number(out, known_at);
  out += "}\n";
}

}  // namespace rvc::io
