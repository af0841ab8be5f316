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

}  // namespace rvc::io
