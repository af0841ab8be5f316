// Opening a file that rvc writes (verdicts, diagnostics, traces, configs).
//
// rvc never writes over a file it did not create. Every regular file it
// writes carries the extended attribute `user.rvc.output`; a later run may
// write over such a file (re-running a command with the same -o), but an
// existing, non-empty file without the mark (a trace, a config, another
// tool's output) is refused before a byte of it changes. Devices and pipes
// (/dev/null, a FIFO) are written as they are: they hold nothing to lose.
#pragma once

#include <cstdio>
#include <string>

namespace rvc::transport {

// The mark rvc puts on the files it writes.
inline constexpr const char* kOutputMark = "user.rvc.output";

// Opens `path` for writing (truncating a file rvc wrote earlier) and marks it.
// Throws std::invalid_argument naming the file and the reason when rvc may not
// write it or cannot open it. `what` names the option in the message
// ("--output", "--diagnostics", ...).
std::FILE* open_output_file(const std::string& path, const std::string& what = "output");

// Why rvc may not write over `path`, or "" when it may (it does not exist, is
// empty, is not a regular file, or carries the mark).
std::string output_file_refusal(const std::string& path);

}  // namespace rvc::transport
