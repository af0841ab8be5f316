#include "io/jsonl_reader.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <vector>

namespace rvc::io {
namespace {

// Newlines in [begin, end): memchr is vectorized, std::count on bytes is not.
uint64_t count_newlines(const char* begin, const char* end) {
  uint64_t n = 0;
  while (begin < end) {
    const char* nl = static_cast<const char*>(std::memchr(begin, '\n', static_cast<size_t>(end - begin)));
    if (!nl) break;
    ++n;
    begin = nl + 1;
  }
  return n;
}


using simdjson::ondemand::json_type;

bool blank(std::string_view s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return c == ' ' || c == '\t' || c == '\r'; });
}

class ChunkProcessor {
 public:
  ChunkProcessor(JsonlHandler& handler, size_t max_line) : handler_(handler), max_line_(max_line) {}

  // buf[0, len) holds complete lines (the last ends with '\n' unless at EOF);
  // buf has SIMDJSON_PADDING readable bytes after len.
  void process(const char* buf, size_t len, uint64_t first_line) {
    if (len == 0) return;
    size_t fast_len = len;  // the fast path reads buf[0, fast_len)
    // With a message-size limit below the chunk size, a long line may sit
    // inside the chunk: the fast path stops before it, line mode reports it.
    if (max_line_ < len) {
      for (size_t start = 0; start < len;) {
        const char* nl = static_cast<const char*>(std::memchr(buf + start, '\n', len - start));
        size_t end = nl ? static_cast<size_t>(nl - buf) : len;
        if (end - start > max_line_) {
          fast_len = start;
          break;
        }
        start = end + 1;
      }
    }
    size_t resume = fast_len;  // where line-by-line mode starts
    simdjson::ondemand::document_stream stream;
    if (fast_len > 0) {
      if (stream_parser_.iterate_many(buf, fast_len, std::max<size_t>(fast_len, 1 << 16)).get(stream)) {
        resume = 0;
      } else {
        cache_at_ = buf;
        cache_line_ = first_line;
        for (auto it = stream.begin(); it != stream.end(); ++it) {
          size_t at = it.current_index();
          simdjson::ondemand::object object;
          auto doc = *it;
          if (it.error() || doc.get_object().get(object)) {
            resume = at;
            break;
          }
          if (!handler_.on_object(Position(buf, at, first_line, &cache_at_, &cache_line_), object)) {
            resume = at;
            break;
          }
        }
        if (resume == fast_len && stream.truncated_bytes() > 0) resume = fast_len - stream.truncated_bytes();
      }
    }
    if (resume >= len) return;
    // Line mode from the start of the line holding `resume`.
    while (resume > 0 && buf[resume - 1] != '\n') --resume;
    uint64_t line = first_line + count_newlines(buf, buf + resume);
    size_t pos = resume;
    while (pos < len) {
      const char* nl = static_cast<const char*>(std::memchr(buf + pos, '\n', len - pos));
      size_t end = nl ? static_cast<size_t>(nl - buf) : len;
      std::string_view text(buf + pos, end - pos);
      if (text.size() > max_line_)
        handler_.on_error(LineError{line, 0, "message longer than " + std::to_string(max_line_) +
                                                 " bytes (--max-message-size); skipped"});
      else if (!blank(text))
        parse_one(line_parser_, text, line, handler_, scratch_);
      pos = end + 1;
      ++line;
    }
  }

 private:
  JsonlHandler& handler_;
  size_t max_line_;
  const char* cache_at_ = nullptr;
  uint64_t cache_line_ = 0;
  simdjson::ondemand::parser stream_parser_, line_parser_;
  std::string scratch_;
};

}  // namespace

uint64_t Position::number() const {
  if (!base_) return number_;
  const char* at = base_ + offset_;
  if (*cache_at_ > at || *cache_at_ < base_) {  // positions only move forward within a chunk
    *cache_at_ = base_;
    *cache_line_ = number_;
  }
  *cache_line_ += count_newlines(*cache_at_, at);
  *cache_at_ = at;
  return *cache_line_;
}

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
    std::string shown(text.substr(0, 40));
    if (text.size() > 40) shown += "...";
    handler.on_error(LineError{line, 1, "expected a JSON object {...}, found: " + shown});
    return;
  }
  simdjson::ondemand::object object;
  if (auto err = doc.get_object().get(object)) {
    fail("invalid JSON", err);
    return;
  }
  if (!handler.on_object(Position(line), object)) handler.on_error(LineError{line, 0, handler.json_error()});
}

bool read_jsonl(int fd, JsonlHandler& handler, const ReaderOptions& options, std::string& error) {
  ChunkProcessor processor(handler, options.max_line_bytes);
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
      line += static_cast<uint64_t>(count_newlines(buf.data(), buf.data() + complete));
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
