// Verdicts as JSON lines: {"time":12,"property":"p1","value":false}.
// Discrete times print as integers (step indices), dense times in the
// shortest form that reads back to the same double.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

#include "io/json_writer.hpp"

namespace rvc::io {

// Appends one verdict line (with '\n') to `out`.
void append_verdict(std::string& out, double time, bool discrete, std::string_view property, bool value);

// Buffered writer to a FILE*: verdicts are small and frequent.
class VerdictWriter {
 public:
  explicit VerdictWriter(std::FILE* out, bool discrete, bool line_buffered)
      : out_(out), discrete_(discrete), line_buffered_(line_buffered) {}
  ~VerdictWriter() { flush(); }
  void write(double time, std::string_view property, bool value) {
    append_verdict(buf_, time, discrete_, property, value);
    if (line_buffered_ || buf_.size() > (1 << 16)) flush();
  }
  void flush() {
    if (!buf_.empty()) std::fwrite(buf_.data(), 1, buf_.size(), out_);
    buf_.clear();
    std::fflush(out_);
  }

 private:
  std::FILE* out_;
  bool discrete_, line_buffered_;
  std::string buf_;
};

}  // namespace rvc::io
