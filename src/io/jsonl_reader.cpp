#include "io/jsonl_reader.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <vector>

namespace rvc::io {
namespace {

using simdjson::ondemand::json_type;

bool blank(std::string_view s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return c == ' ' || c == '\t' || c == '\r'; });
}

class ChunkProcessor {
 public:
  ChunkProcessor(JsonlHandler& handler) : handler_(handler) {}

  // buf[0, len) holds complete lines (the last ends with '\n' unless at EOF);
  // buf has SIMDJSON_PADDING readable bytes after len.
  void process(const char* buf, size_t len, uint64_t first_line) {
    if (len == 0) return;
    size_t resume = 0;  // where line-by-line mode starts, if needed
    bool fallback = false;
    simdjson::ondemand::document_stream stream;
    if (stream_parser_.iterate_many(buf, len, std::max<size_t>(len, 1 << 16)).get(stream)) {
      fallback = true;
    } else {
      uint64_t line = first_line;
      size_t scanned = 0;  // newlines counted up to here
      for (auto it = stream.begin(); it != stream.end(); ++it) {
        size_t at = it.current_index();
        std::string_view src = it.source();
        // One JSON-lines record per line: a document that spans a newline, or
        // anything the stream reports as an error, sends us to line mode.
        if (it.error() || std::memchr(src.data(), '\n', src.size()) != nullptr) {
          resume = at;
          fallback = true;
          break;
        }
        line += static_cast<uint64_t>(std::count(buf + scanned, buf + at, '\n'));
        scanned = at;
        simdjson::ondemand::object object;
        auto doc = *it;
        if (doc.get_object().get(object)) {
          resume = at;
          fallback = true;
          break;
        }
        handler_.on_object(line, object);
      }
      if (!fallback && stream.truncated_bytes() > 0) {
        resume = len - stream.truncated_bytes();
        fallback = true;
      }
    }
    if (!fallback) return;
    // Line mode from the start of the line holding `resume`.
    while (resume > 0 && buf[resume - 1] != '\n') --resume;
    uint64_t line = first_line + static_cast<uint64_t>(std::count(buf, buf + resume, '\n'));
    size_t pos = resume;
    while (pos < len) {
      const char* nl = static_cast<const char*>(std::memchr(buf + pos, '\n', len - pos));
      size_t end = nl ? static_cast<size_t>(nl - buf) : len;
      std::string_view text(buf + pos, end - pos);
      if (!blank(text)) parse_one(line_parser_, text, line, handler_, scratch_);
      pos = end + 1;
      ++line;
    }
  }

 private:
  JsonlHandler& handler_;
  simdjson::ondemand::parser stream_parser_, line_parser_;
  std::string scratch_;
};

}  // namespace

void parse_one(simdjson::ondemand::parser& parser, std::string_view text, uint64_t line, JsonlHandler& handler,
               std::string& scratch) {
  // Copy into a padded buffer: simdjson reads up to SIMDJSON_PADDING bytes past the end.
  scratch.assign(text.data(), text.size());
  scratch.append(simdjson::SIMDJSON_PADDING, '\0');
  simdjson::ondemand::document doc;
  auto fail = [&](const char* what, simdjson::error_code err) {
    uint64_t column = 0;
    const char* loc = nullptr;
    if (!doc.current_location().get(loc) && loc >= scratch.data() && loc <= scratch.data() + text.size())
      column = static_cast<uint64_t>(loc - scratch.data()) + 1;
    std::string msg = std::string(what);
    if (err) msg += std::string(": ") + simdjson::error_message(err);
    handler.on_error(LineError{line, column, msg});
  };
  if (auto err = parser.iterate(scratch.data(), text.size(), scratch.size()).get(doc)) {
    fail("invalid JSON", err);
    return;
  }
  json_type type;
  if (auto err = doc.type().get(type)) {
    fail("invalid JSON", err);
    return;
  }
  if (type != json_type::object) {
    handler.on_error(LineError{line, 1, "expected a JSON object, got a JSON " +
                                            std::string(type == json_type::array ? "array" : "scalar")});
    return;
  }
  simdjson::ondemand::object object;
  if (auto err = doc.get_object().get(object)) {
    fail("invalid JSON", err);
    return;
  }
  handler.on_object(line, object);
}

bool read_jsonl(int fd, JsonlHandler& handler, const ReaderOptions& options, std::string& error) {
  ChunkProcessor processor(handler);
  const size_t cap = std::max(options.chunk_bytes, options.max_line_bytes + 1);
  // simdjson may read SIMDJSON_PADDING bytes past what it parses; the slack
  // keeps that inside our buffer (its content does not matter).
  std::vector<char> buf(cap + simdjson::SIMDJSON_PADDING, ' ');
  size_t have = 0;        // bytes in buf
  uint64_t line = 1;      // line number of buf[0]
  bool skipping = false;  // inside an oversized line, dropping bytes until '\n'
  for (;;) {
    ssize_t n = ::read(fd, buf.data() + have, cap - have);
    if (n < 0) {
      if (errno == EINTR) continue;
      error = std::string("read error: ") + std::strerror(errno);
      return false;
    }
    const bool eof = n == 0;
    have += static_cast<size_t>(n);
    if (skipping) {
      const char* nl = static_cast<const char*>(std::memchr(buf.data(), '\n', have));
      if (!nl && !eof) { have = 0; continue; }
      handler.on_error(LineError{line, 0, "message longer than " + std::to_string(options.max_line_bytes) +
                                              " bytes (--max-message-size); skipped"});
      skipping = false;
      size_t drop = nl ? static_cast<size_t>(nl - buf.data()) + 1 : have;
      std::memmove(buf.data(), buf.data() + drop, have - drop);
      have -= drop;
      ++line;
    }
    // Complete lines end at the last newline; at EOF everything is complete.
    size_t complete = have;
    if (!eof) {
      complete = 0;
      for (size_t i = have; i > 0; --i)
        if (buf[i - 1] == '\n') { complete = i; break; }
    }
    if (complete > 0) {
      processor.process(buf.data(), complete, line);
      line += static_cast<uint64_t>(std::count(buf.data(), buf.data() + complete, '\n'));
      std::memmove(buf.data(), buf.data() + complete, have - complete);
      have -= complete;
    }
    if (eof) return true;
    if (have > options.max_line_bytes) {  // a line without its newline is already too long
      skipping = true;
      have = 0;
    }
  }
}

}  // namespace rvc::io
