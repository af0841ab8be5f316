// Streams a JSON-lines source (file descriptor) through simdjson in fixed-size
// chunks, so memory stays flat however long the trace is.
//
// Fast path: each chunk of complete lines goes through simdjson's document
// stream (one SIMD pass over many messages). If a chunk holds anything odd (a
// malformed line), the rest of that chunk is re-read line by line, so a bad
// line costs only itself: every valid line around it is still delivered, and
// the error names the line and column. Line numbers are counted only when an
// error or warning asks for one. One message is one line in both paths: an
// object broken over lines is reported line by line, and an object with more
// text after it on its line ({...}} or two objects) is one bad line.
#pragma once

#include <simdjson.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

namespace rvc::io {

struct LineError {
  uint64_t line;   // 1-based
  uint64_t column; // 1-based, 0 if unknown
  std::string message;
};

// Where a message came from: a line of a file (counted only when asked) or a
// number given by the transport (a sequence number).
class Position {
 public:
  explicit Position(uint64_t number, std::string_view text = {}) : number_(number), text_(text) {}
  Position(const char* base, size_t offset, size_t end, uint64_t first_line, const char** cache_at,
           uint64_t* cache_line)
      : number_(first_line), base_(base), offset_(offset), end_(end), cache_at_(cache_at), cache_line_(cache_line) {}
  uint64_t number() const;
  // The message's own text (its line, without the line break), for a
  // witness window; valid while the reader's chunk is (until commit()).
  std::string_view text() const;

 private:
  uint64_t number_;
  std::string_view text_;
  const char* base_ = nullptr;
  size_t offset_ = 0;
  size_t end_ = 0;  // of the chunk's text: a line may lack its final newline
  const char** cache_at_ = nullptr;  // last position counted in this chunk
  uint64_t* cache_line_ = nullptr;
};

// What a handler made of an object it read.
enum class ReadResult {
  Pending,    // fine so far: act on it at commit(), once the reader knows it is whole
  Rejected,   // refused (and already reported) by the handler: valid JSON it cannot use
  Malformed,  // the JSON broke while being read: the reader reports it (json_error())
};

class JsonlHandler {
 public:
  virtual ~JsonlHandler() = default;
  // Reads the object, but must not act on it before commit(): simdjson parses
  // lazily, so the reader only knows the message is whole (no broken or
  // trailing text) after the handler has read it. Returns false if the
  // object turned out to be malformed while being read; the reader then
  // re-reads that stretch line by line and reports the error.
  virtual ReadResult on_object(const Position& position, simdjson::ondemand::object object) = 0;
  // The object just read (Pending) is whole: act on it.
  virtual void commit() {}
  // The object just read (Pending) had broken text after it: forget it.
  virtual void discard() {}
  virtual void on_error(const LineError& error) = 0;
  // Something was skipped but no message lost (a byte-order mark at the start).
  virtual void on_warning(const LineError& warning) {}
  // The JSON error behind the last `false` from on_object.
  virtual std::string json_error() const { return "invalid JSON"; }

  // The layout fast path (io/json_layout.hpp). A handler that reads layouts
  // is offered each line first: match_line() says whether the text at
  // [p, end) starts with a line that has a layout it learned from earlier
  // messages, returning that line's end (its newline, or `end`) and acting
  // on nothing yet; read_matched() then reads and commits that line, and
  // simdjson never sees it. Lines that do not match go through on_object()
  // as before, in order.
  virtual bool reads_layouts() const { return false; }
  virtual const char* match_line(const char* /*p*/, const char* /*end*/) { return nullptr; }
  virtual void read_matched(const Position&) {}
};

struct ReaderOptions {
  size_t chunk_bytes = 1 << 20;
  size_t max_line_bytes = 1 << 20;  // longer lines are rejected as oversized
  std::function<void()> after_chunk;  // called after each chunk of lines is handled (may be empty)
};

// Reads fd to its end. Returns false (with `error`) only on I/O failure.
bool read_jsonl(int fd, JsonlHandler& handler, const ReaderOptions& options, std::string& error);

// Reads JSON lines held in memory (a network payload that batches several
// messages, one per line) through the same fast path as files.
class ChunkReader {
 public:
  ChunkReader(JsonlHandler& handler, size_t max_line);
  ~ChunkReader();
  void read(std::string_view text, uint64_t first_line);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The UTF-8 byte-order mark. At the very start of a file it is skipped with a
// warning; anywhere else (a later line, a network payload) the message is
// rejected with an error that names it.
inline constexpr std::string_view kUtf8Bom = "\xEF\xBB\xBF";
inline constexpr const char* kBomStartWarning = "skipped a UTF-8 byte-order mark at the start of the input";

// Parses one message (one line or one network payload) and hands it over.
// `scratch` keeps a padded copy when the payload lacks simdjson's padding.
void parse_one(simdjson::ondemand::parser& parser, std::string_view text, uint64_t line, JsonlHandler& handler,
               std::string& scratch);

}  // namespace rvc::io
