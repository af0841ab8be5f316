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

// Where a document that starts at `from` sits, given that the next one (or
// the end of the parsed text) starts at `to`. JSON Lines means one object
// per line: anything else is handled line by line, as line mode would.
enum class Layout { OwnLine, SharesLine, SpansLines };

Layout layout(const char* buf, size_t from, size_t to) {
  const char* nl = static_cast<const char*>(std::memchr(buf + from, '\n', to - from));
  if (!nl) return Layout::SharesLine;
  for (const char* p = nl + 1; p < buf + to; ++p)
    if (*p != ' ' && *p != '\t' && *p != '\r' && *p != '\n') return Layout::SpansLines;
  return Layout::OwnLine;
}

// A line as Position::text() shows it: from its first non-blank byte, without a final CR.
std::string_view line_text(const char* begin, const char* end) {
  while (begin < end && (*begin == ' ' || *begin == '\t' || *begin == '\r')) ++begin;
  if (end > begin && end[-1] == '\r') --end;
  return std::string_view(begin, static_cast<size_t>(end - begin));
}

class ChunkProcessor {
 public:
  ChunkProcessor(JsonlHandler& handler, size_t max_line) : handler_(handler), max_line_(max_line) {}

  // buf[0, len) holds complete lines (the last ends with '\n' unless at EOF);
  // buf has SIMDJSON_PADDING readable bytes after len. Returns the number of
  // lines if it counted them (reading layouts, it walks every line), else
  // kUncounted.
  static constexpr uint64_t kUncounted = ~uint64_t{0};
  uint64_t process(const char* buf, size_t len, uint64_t first_line) {
    if (!handler_.reads_layouts()) {
      process_stream(buf, len, first_line);
      return kUncounted;
    }
    // Lines the handler reads by layout are read here; each run of other
    // lines goes to simdjson's document stream before the next matched line,
    // so messages keep their order.
    size_t run = 0;  // the first line not read yet
    uint64_t run_line = first_line;
    size_t run_lines = 0;
    uint64_t line = first_line;
    for (size_t pos = 0; pos < len; ++line) {
      // A matched line's end is where its layout ends: no search for the newline.
      const char* matched = handler_.match_line(buf + pos, buf + len);
      const char* nl = matched ? matched : static_cast<const char*>(std::memchr(buf + pos, '\n', len - pos));
      const size_t end = nl ? static_cast<size_t>(nl - buf) : len;
      if (matched && end - pos <= max_line_) {  // (longer lines: the run's reader reports them)
        if (run < pos) {  // the run before it may teach the handler layouts: match again after it
          process_stream(buf + run, pos - run, run_line);
          matched = handler_.match_line(buf + pos, buf + len);
        }
        if (matched) {
          handler_.read_matched(Position(line, line_text(buf + pos, buf + end)));
          run = end + 1;
          run_line = line + 1;
          run_lines = 0;
          run_limit_ = 1;
          pos = end + 1;
          continue;
        }
        run = pos;
        run_line = line;
        run_lines = 0;
      }
      // Lines the handler cannot match yet: read them with simdjson soon, so
      // it learns their layout, but in runs that grow while nothing matches
      // (each run costs a document stream's set-up).
      if (++run_lines >= run_limit_) {
        process_stream(buf + run, end + (end < len) - run, run_line);
        run = end + 1;
        run_line = line + 1;
        run_lines = 0;
        run_limit_ = std::min<size_t>(run_limit_ * 2, 1 << 16);
      }
      pos = end + 1;
    }
    if (run < len) process_stream(buf + run, len - run, run_line);
    return line - first_line;
  }

 private:
  void process_stream(const char* buf, size_t len, uint64_t first_line) {
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
        // An object is committed only when the next document starts on a
        // later line: "{...}}" or "{...} {...}" on one line is one bad line.
        bool pending = false;
        size_t pending_at = 0;
        for (auto it = stream.begin(); it != stream.end(); ++it) {
          // simdjson may place the first document at offset 0 when blank lines
          // come first: layouts and line numbers count from its first byte.
          size_t at = it.current_index();
          while (at < fast_len && (buf[at] == ' ' || buf[at] == '\t' || buf[at] == '\r' || buf[at] == '\n')) ++at;
          if (pending) {
            pending = false;
            Layout l = layout(buf, pending_at, at);
            if (l != Layout::OwnLine) {
              handler_.discard();
              resume = pending_at;
              break;
            }
            handler_.commit();
          }
          simdjson::ondemand::object object;
          auto doc = *it;
          if (it.error() || doc.get_object().get(object)) {
            resume = at;
            break;
          }
          ReadResult r = handler_.on_object(Position(buf, at, fast_len, first_line, &cache_at_, &cache_line_), object);
          if (r == ReadResult::Malformed) {
            resume = at;
            break;
          }
          if (r == ReadResult::Pending) {
            pending = true;
            pending_at = at;
          }
        }
        if (pending) {
          const bool truncated = resume == fast_len && stream.truncated_bytes() > 0;
          const size_t end = truncated ? fast_len - stream.truncated_bytes() : fast_len;
          Layout l = layout(buf, pending_at, end);
          if (!truncated && l == Layout::SharesLine) l = Layout::OwnLine;  // the last line may lack its newline
          if (l == Layout::OwnLine) {
            handler_.commit();
            if (truncated) resume = end;
          } else {
            handler_.discard();
            resume = pending_at;
          }
        } else if (resume == fast_len && stream.truncated_bytes() > 0) {
          resume = fast_len - stream.truncated_bytes();
        }
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
      // A blank line is no message, however long (fuzz_jsonl: a line of 26
      // spaces under a 24-byte limit was an error to check, nothing to monitor).
      if (blank(text)) {
      } else if (text.size() > max_line_) {
        handler_.on_error(LineError{line, 0, "message longer than " + std::to_string(max_line_) +
                                                 " bytes (--max-message-size); skipped"});
      } else {
        parse_one(line_parser_, text, line, handler_, scratch_);
      }
      pos = end + 1;
      ++line;
    }
  }

  JsonlHandler& handler_;
  size_t max_line_;
  size_t run_limit_ = 1;  // lines the next run of unmatched lines may hold (process())
  const char* cache_at_ = nullptr;
  uint64_t cache_line_ = 0;
  simdjson::ondemand::parser stream_parser_, line_parser_;
  std::string scratch_;
};

}  // namespace

struct ChunkReader::Impl {
  Impl(JsonlHandler& handler, size_t max_line) : processor(handler, max_line) {}
  ChunkProcessor processor;
  std::string buf;
};

ChunkReader::ChunkReader(JsonlHandler& handler, size_t max_line) : impl_(std::make_unique<Impl>(handler, max_line)) {}
ChunkReader::~ChunkReader() = default;

void ChunkReader::read(std::string_view text, uint64_t first_line) {
  impl_->buf.assign(text.data(), text.size());
  impl_->buf.append(simdjson::SIMDJSON_PADDING, ' ');
  impl_->processor.process(impl_->buf.data(), text.size(), first_line);
}

uint64_t Position::number() const {
  if (!base_) return number_;
  const char* at = base_ + offset_;
  // simdjson may report the first document of a chunk at offset 0 even when
  // blank lines come first: the document starts at the first non-blank byte.
  while (*at == ' ' || *at == '\t' || *at == '\r' || *at == '\n') ++at;
  if (*cache_at_ > at || *cache_at_ < base_) {  // positions only move forward within a chunk
    *cache_at_ = base_;
    *cache_line_ = number_;
  }
  *cache_line_ += count_newlines(*cache_at_, at);
  *cache_at_ = at;
  return *cache_line_;
}

std::string_view Position::text() const {
  if (!base_) return text_;
  const char* at = base_ + offset_;
  const char* end = base_ + end_;
  while (at < end && (*at == ' ' || *at == '\t' || *at == '\r' || *at == '\n')) ++at;
  const void* nl = std::memchr(at, '\n', static_cast<size_t>(end - at));
  const char* stop = nl ? static_cast<const char*>(nl) : end;
  if (stop > at && stop[-1] == '\r') --stop;
  return std::string_view(at, static_cast<size_t>(stop - at));
}

void parse_one(simdjson::ondemand::parser& parser, std::string_view text, uint64_t line, JsonlHandler& handler,
               std::string& scratch) {
  if (text.substr(0, kUtf8Bom.size()) == kUtf8Bom) {
    handler.on_error(LineError{line, 1, "UTF-8 byte-order mark (EF BB BF) before the message; "
                                        "save the data as UTF-8 without BOM"});
    return;
  }
  // Copy into a padded buffer: simdjson reads up to SIMDJSON_PADDING bytes past the end.
  scratch.assign(text.data(), text.size());
  scratch.append(simdjson::SIMDJSON_PADDING, '\0');
  simdjson::ondemand::document doc;
  bool started = false;  // the document exists: its location can be asked for
  auto fail = [&](const char* what, simdjson::error_code err) {
    uint64_t column = 0;
    const char* loc = nullptr;
    if (started && !doc.current_location().get(loc) && loc >= scratch.data() && loc <= scratch.data() + text.size())
      column = static_cast<uint64_t>(loc - scratch.data()) + 1;
    std::string msg = std::string(what);
    if (err) msg += std::string(": ") + simdjson::error_message(err);
    handler.on_error(LineError{line, column, msg});
  };
  if (auto err = parser.iterate(scratch.data(), text.size(), scratch.size()).get(doc)) {
    fail("invalid JSON", err);
    return;
  }
  started = true;
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
  ReadResult r = handler.on_object(Position(line, text), object);
  if (r == ReadResult::Malformed) {
    handler.on_error(LineError{line, 0, handler.json_error()});
    return;
  }
  if (r == ReadResult::Rejected) return;
  // Anything left is text after the object, unless the handler stopped
  // early, at a field it refuses (a time that is not a number): then the
  // rest of the object is skipped first, so that the error is that refusal,
  // as when the line is read in a document stream.
  // current_location() succeeds only while text remains (simdjson 3.0 has no at_end()).
  const char* rest = nullptr;
  if (!doc.current_location().get(rest)) {
    doc.rewind();
    simdjson::ondemand::object whole;
    simdjson::error_code err = doc.get_object().get(whole);
    for (auto field = whole.begin(); !err && field != whole.end(); ++field) err = (*field).error();
    if (err) {
      handler.discard();
      fail("invalid JSON", err);
      return;
    }
  }
  if (!doc.current_location().get(rest)) {
    handler.discard();
    uint64_t column = 0;
    if (rest >= scratch.data() && rest <= scratch.data() + text.size())
      column = static_cast<uint64_t>(rest - scratch.data()) + 1;
    handler.on_error(LineError{line, column, "unexpected text after the JSON object"});
    return;
  }
  handler.commit();
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
  bool skipped_blank = true;  // what was dropped of that line so far was blank (then it is no message)
  bool at_start = true;   // nothing read yet: a byte-order mark may come first
  for (;;) {
    ssize_t n = ::read(fd, buf.data() + have, cap - have);
    if (n < 0) {
      if (errno == EINTR) continue;
      error = std::string("read error: ") + std::strerror(errno);
      return false;
    }
    const bool eof = n == 0;
    have += static_cast<size_t>(n);
    if (at_start && (have >= kUtf8Bom.size() || eof)) {
      at_start = false;
      if (std::string_view(buf.data(), std::min(have, kUtf8Bom.size())) == kUtf8Bom) {
        handler.on_warning(LineError{1, 1, kBomStartWarning});
        std::memmove(buf.data(), buf.data() + kUtf8Bom.size(), have - kUtf8Bom.size());
        have -= kUtf8Bom.size();
      }
    } else if (at_start) {
      continue;  // fewer than 3 bytes so far: read on before looking
    }
    if (skipping) {
      const char* nl = static_cast<const char*>(std::memchr(buf.data(), '\n', have));
      const size_t part = nl ? static_cast<size_t>(nl - buf.data()) : have;
      skipped_blank = skipped_blank && blank(std::string_view(buf.data(), part));
      if (!nl && !eof) { have = 0; continue; }
      if (!skipped_blank)
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
      const uint64_t lines = processor.process(buf.data(), complete, line);
      if (options.after_chunk) options.after_chunk();
      line += lines != ChunkProcessor::kUncounted ? lines : count_newlines(buf.data(), buf.data() + complete);
      std::memmove(buf.data(), buf.data() + complete, have - complete);
      have -= complete;
    }
    if (eof) return true;
    if (have > options.max_line_bytes) {  // a line without its newline is already too long
      skipping = true;
      skipped_blank = blank(std::string_view(buf.data(), have));
      have = 0;
    }
  }
}

}  // namespace rvc::io
