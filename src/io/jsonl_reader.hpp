// Streams a JSON-lines source (file descriptor) through simdjson in fixed-size
// chunks, so memory stays flat however long the trace is.
//
// Fast path: each chunk of complete lines goes through simdjson's document
// stream (one SIMD pass over many messages). If a chunk holds anything odd (a
// malformed line, a document spanning lines), the rest of that chunk is
// re-read line by line, so a bad line costs only itself: every valid line
// around it is still delivered, and the error names the line and column.
#pragma once

#include <simdjson.h>

#include <cstdint>
#include <string>

namespace rvc::io {

struct LineError {
  uint64_t line;   // 1-based
  uint64_t column; // 1-based, 0 if unknown
  std::string message;
};

class JsonlHandler {
 public:
  virtual ~JsonlHandler() = default;
  virtual void on_object(uint64_t line, simdjson::ondemand::object object) = 0;
  virtual void on_error(const LineError& error) = 0;
};

struct ReaderOptions {
  size_t chunk_bytes = 1 << 20;
  size_t max_line_bytes = 1 << 20;  // longer lines are rejected as oversized
};

// Reads fd to its end. Returns false (with `error`) only on I/O failure.
bool read_jsonl(int fd, JsonlHandler& handler, const ReaderOptions& options, std::string& error);

// Parses one message (one line or one network payload) and hands it over.
// `scratch` keeps a padded copy when the payload lacks simdjson's padding.
void parse_one(simdjson::ondemand::parser& parser, std::string_view text, uint64_t line, JsonlHandler& handler,
               std::string& scratch);

}  // namespace rvc::io
