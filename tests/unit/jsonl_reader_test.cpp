// jsonl_reader: every valid line is delivered once, with its line number;
// every bad line yields exactly one error naming its line (and column where
// one is given), whatever the chunk size, and from files or pipes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <simdjson.h>
#include <unistd.h>

#include <map>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "io/jsonl_reader.hpp"
#include "test_util.hpp"

namespace rvc::io {
namespace {

using simdjson::ondemand::json_type;

// Reads a whole value, so malformed JSON inside it shows up now (simdjson
// parses lazily). Returns false on any JSON error.
bool read_fully(simdjson::ondemand::value v) {
  json_type type;
  if (v.type().get(type)) return false;
  switch (type) {
    case json_type::object: {
      simdjson::ondemand::object o;
      if (v.get_object().get(o)) return false;
      for (auto field : o) {
        std::string_view key;
        simdjson::ondemand::value inner;
        if (field.unescaped_key().get(key) || field.value().get(inner) || !read_fully(inner)) return false;
      }
      return true;
    }
    case json_type::array: {
      simdjson::ondemand::array a;
      if (v.get_array().get(a)) return false;
      for (auto item : a) {
        simdjson::ondemand::value inner;
        if (item.get(inner) || !read_fully(inner)) return false;
      }
      return true;
    }
    case json_type::string: {
      std::string_view s;
      return !v.get_string().get(s);
    }
    case json_type::number: {
      double d;
      return !v.get_double().get(d);
    }
    case json_type::boolean: {
      bool b;
      return !v.get_bool().get(b);
    }
    case json_type::null: {
      bool n = false;
      return !v.is_null().get(n) && n;
    }
  }
  return false;
}

// Records (line, id) for each committed object (id = its "id" field, -1 if
// none) and each error. Reads every object fully and reports malformed ones
// as the handler contract says (Malformed: the reader re-reads and reports);
// an object counts only once the reader commits it.
struct Recorder : JsonlHandler {
  std::vector<std::pair<uint64_t, int64_t>> objects;
  std::vector<LineError> errors;
  std::pair<uint64_t, int64_t> pending{0, 0};

  ReadResult on_object(const Position& position, simdjson::ondemand::object object) override {
    int64_t id = -1;
    for (auto field : object) {
      std::string_view key;
      simdjson::ondemand::value value;
      if (field.unescaped_key().get(key) || field.value().get(value)) return ReadResult::Malformed;
      if (key == "id") {
        if (value.get_int64().get(id)) return ReadResult::Malformed;
      } else if (!read_fully(value)) {
        return ReadResult::Malformed;
      }
    }
    pending = {position.number(), id};
    return ReadResult::Pending;
  }
  void commit() override { objects.push_back(pending); }
  void on_error(const LineError& error) override { errors.push_back(error); }

  std::vector<uint64_t> error_lines() const {
    std::vector<uint64_t> out;
    for (const LineError& e : errors) out.push_back(e.line);
    return out;
  }
};

using Objects = std::vector<std::pair<uint64_t, int64_t>>;
using Lines = std::vector<uint64_t>;

ReaderOptions chunked(size_t chunk, size_t max_line) {
  ReaderOptions o;
  o.chunk_bytes = chunk;
  o.max_line_bytes = max_line;
  return o;
}

Recorder read_file(const std::string& content, const ReaderOptions& options = {}) {
  test::TempFile f(content);
  Recorder r;
  int fd = ::open(f.path().c_str(), O_RDONLY);
  EXPECT_GE(fd, 0);
  std::string error;
  EXPECT_TRUE(read_jsonl(fd, r, options, error)) << error;
  ::close(fd);
  return r;
}

// The same through a pipe, written `piece` bytes at a time, so reads return
// short counts at arbitrary places.
Recorder read_pipe(const std::string& content, const ReaderOptions& options, size_t piece) {
  int fds[2];
  EXPECT_EQ(::pipe(fds), 0);
  std::thread writer([&] {
    for (size_t off = 0; off < content.size(); off += piece) {
      size_t n = std::min(piece, content.size() - off);
      EXPECT_EQ(::write(fds[1], content.data() + off, n), static_cast<ssize_t>(n));
    }
    ::close(fds[1]);
  });
  Recorder r;
  std::string error;
  EXPECT_TRUE(read_jsonl(fds[0], r, options, error)) << error;
  writer.join();
  ::close(fds[0]);
  return r;
}

// ---------------------------------------------------------------- a mixed file

const std::string kMixed =
    "{\"id\":1}\n"      // 1  ok
    "not json\n"        // 2  error (not an object)
    "\n"                // 3  blank: skipped silently
    "[1,2]\n"           // 4  error: an array
    "{\"id\":5}\n"      // 5  ok
    "\"str\"\n"         // 6  error: a string
    "{\"id\":7}\r\n"    // 7  ok (CRLF)
    "   \t \n"          // 8  whitespace only: skipped
    "42\n"              // 9  error: a number
    "}\n"               // 10 error: a stray brace
    "{\"id\":11, \"a\": [1, {\"b\": null}]}\n"  // 11 ok
    "null\n"            // 12 error
    "{\"id\":13}";      // 13 ok, no trailing newline

void expect_mixed(const Recorder& r, const std::string& how) {
  EXPECT_EQ(r.objects, (Objects{{1, 1}, {5, 5}, {7, 7}, {11, 11}, {13, 13}})) << how;
  EXPECT_EQ(r.error_lines(), (Lines{2, 4, 6, 9, 10, 12})) << how;
  for (const LineError& e : r.errors) {
    if (e.line == 10) {
      EXPECT_LE(e.column, 1u) << how;  // unknown (0) or the brace's column
    } else {
      EXPECT_EQ(e.column, 1u) << how << " line " << e.line;  // the value that is not an object
      EXPECT_NE(e.message.find("expected a JSON object"), std::string::npos) << how << ": " << e.message;
    }
  }
}

TEST(JsonlReader, MixedFileDefaultChunks) { expect_mixed(read_file(kMixed), "default"); }
TEST(JsonlReader, MixedFile64ByteChunks) { expect_mixed(read_file(kMixed, chunked(64, 63)), "64-byte chunks"); }
TEST(JsonlReader, MixedFileTinyChunks) { expect_mixed(read_file(kMixed, chunked(40, 39)), "40-byte chunks"); }
TEST(JsonlReader, MixedFileThroughAPipe) {
  expect_mixed(read_pipe(kMixed, {}, 3), "pipe, default chunks");
  expect_mixed(read_pipe(kMixed, chunked(64, 63), 5), "pipe, 64-byte chunks");
}

TEST(JsonlReader, EmptyAndBlankInputs) {
  Recorder empty = read_file("");
  EXPECT_TRUE(empty.objects.empty());
  EXPECT_TRUE(empty.errors.empty());
  Recorder blank = read_file("\n\n  \n\r\n");
  EXPECT_TRUE(blank.objects.empty());
  EXPECT_TRUE(blank.errors.empty());
  Recorder one = read_file("{}");
  EXPECT_EQ(one.objects, (Objects{{1, -1}}));
}

TEST(JsonlReader, LineNumbersAcrossBlankLines) {
  Recorder r = read_file("{\"id\":1}\n\n\n{\"id\":4}\n\n{\"id\":6}\n");
  EXPECT_EQ(r.objects, (Objects{{1, 1}, {4, 4}, {6, 6}}));
  EXPECT_TRUE(r.errors.empty());
}

TEST(JsonlReader, LineNumbersAfterLeadingBlankLines) {
  // Was a bug (fixed): when a chunk starts with blank lines, its first document is given
  // the chunk's first line number. simdjson's document_stream reports
  // current_index() == batch start (0) for the first document, not the
  // offset of its first byte; the reader counts newlines up to that index.
  // Fix: skip whitespace from current_index() before counting (or count up
  // to it.source().data()).
  Recorder r = read_file("\n\n{\"id\":3}\n\n\n{\"id\":6}\n");
  EXPECT_EQ(r.objects, (Objects{{3, 3}, {6, 6}}));
  // The same inside a file: line 1 is exactly one 10-byte chunk, so the
  // second chunk starts with the blank line 2 and {"id":3} is numbered 2.
  Recorder c = read_file("{\"id\":10}\n\n{\"id\":3}\n", chunked(10, 9));
  EXPECT_EQ(c.objects, (Objects{{1, 10}, {3, 3}}));
}

// 300 lines of varying length, every 7th an array (error), every 11th blank:
// with 64-byte chunks almost every line straddles a chunk boundary somewhere.
TEST(JsonlReader, ManyLinesAcrossChunkBoundaries) {
  std::string content;
  Objects expected_objects;
  Lines expected_errors;
  for (int i = 1; i <= 300; ++i) {
    if (i % 11 == 0) {
      content += "\n";
    } else if (i % 7 == 0) {
      content += "[" + std::to_string(i) + "]\n";
      expected_errors.push_back(i);
    } else {
      content += "{\"id\":" + std::to_string(i) + ",\"pad\":\"" + std::string(i % 23, 'x') + "\"}\n";
      expected_objects.emplace_back(i, i);
    }
  }
  for (const ReaderOptions& o : {ReaderOptions{}, chunked(64, 63), chunked(100, 45)}) {
    Recorder r = read_file(content, o);
    EXPECT_EQ(r.objects, expected_objects) << o.chunk_bytes;
    EXPECT_EQ(r.error_lines(), expected_errors) << o.chunk_bytes;
  }
  Recorder p = read_pipe(content, chunked(64, 63), 7);
  EXPECT_EQ(p.objects, expected_objects);
  EXPECT_EQ(p.error_lines(), expected_errors);
}

// ---------------------------------------------------------------- oversized lines

TEST(JsonlReader, LineLongerThanTheLimitIsOneError) {
  const std::string longline = "{\"id\":2,\"pad\":\"" + std::string(40, 'x') + "\"}";  // 57 bytes
  const std::string content = "{\"id\":1}\n" + longline + "\n{\"id\":3}\n";
  // The limit below the chunk size (the long line sits inside one chunk), at
  // the chunk size, and with the default 1 MiB chunks.
  for (const ReaderOptions& o : {chunked(64, 20), chunked(21, 20), chunked(1 << 20, 20)}) {
    Recorder r = read_file(content, o);
    EXPECT_EQ(r.objects, (Objects{{1, 1}, {3, 3}})) << o.chunk_bytes;
    ASSERT_EQ(r.error_lines(), (Lines{2})) << o.chunk_bytes;
    EXPECT_NE(r.errors[0].message.find("longer than 20 bytes"), std::string::npos) << r.errors[0].message;
  }
}

TEST(JsonlReader, LimitIsInclusive) {
  // {"id":1,"p":"xxxxx"} is exactly 20 bytes: accepted with a limit of 20,
  // rejected with 19.
  const std::string line = "{\"id\":1,\"p\":\"xxxxx\"}";
  ASSERT_EQ(line.size(), 20u);
  Recorder ok = read_file(line + "\n{\"id\":2}\n", chunked(64, 20));
  EXPECT_EQ(ok.objects, (Objects{{1, 1}, {2, 2}}));
  EXPECT_TRUE(ok.errors.empty());
  Recorder too_long = read_file(line + "\n{\"id\":2}\n", chunked(64, 19));
  EXPECT_EQ(too_long.objects, (Objects{{2, 2}}));
  EXPECT_EQ(too_long.error_lines(), (Lines{1}));
}

TEST(JsonlReader, OversizedLastLineWithoutNewline) {
  std::string content = "{\"id\":1}\n{\"id\":2,\"pad\":\"" + std::string(100, 'y') + "\"}";
  for (const ReaderOptions& o : {chunked(32, 31), chunked(256, 31)}) {
    Recorder r = read_file(content, o);
    EXPECT_EQ(r.objects, (Objects{{1, 1}})) << o.chunk_bytes;
    EXPECT_EQ(r.error_lines(), (Lines{2})) << o.chunk_bytes;
  }
}

TEST(JsonlReader, SeveralOversizedLinesInARow) {
  std::string big(50, 'z');
  std::string content = "{\"id\":1}\n\"" + big + "\"\n\"" + big + "\"\n{\"id\":4}\n\"" + big + "\"\n{\"id\":6}\n";
  Recorder r = read_file(content, chunked(17, 16));
  EXPECT_EQ(r.objects, (Objects{{1, 1}, {4, 4}, {6, 6}}));
  EXPECT_EQ(r.error_lines(), (Lines{2, 3, 5}));
}

// ---------------------------------------------------------------- truncated / malformed

TEST(JsonlReader, TruncatedLastLine) {
  Recorder r = read_file("{\"id\":1}\n{\"id\":2,");
  EXPECT_EQ(r.objects, (Objects{{1, 1}}));
  EXPECT_EQ(r.error_lines(), (Lines{2}));
}

TEST(JsonlReader, MalformedObjectsFoundWhileReading) {
  // Each of these starts like an object, so simdjson hands it over lazily;
  // the error appears while it is read. Each must cost exactly one error.
  const std::string content =
      "{\"id\":1}\n"
      "{\"id\" 2}\n"     // 2: missing colon
      "{\"id\":3}\n"
      "{\"id\":}\n"      // 4: missing value
      "{\"id\":5}\n"
      "{,}\n"            // 6: stray comma
      "{\"id\":7}\n"
      "{\"id\":8,\"x\":[1,}\n"  // 8: bad array
      "{\"id\":9}\n";
  for (const ReaderOptions& o : {ReaderOptions{}, chunked(32, 31)}) {
    Recorder r = read_file(content, o);
    EXPECT_EQ(r.objects, (Objects{{1, 1}, {3, 3}, {5, 5}, {7, 7}, {9, 9}})) << o.chunk_bytes;
    EXPECT_EQ(r.error_lines(), (Lines{2, 4, 6, 8})) << o.chunk_bytes;
  }
}

TEST(JsonlReader, TrailingContentAfterAnObjectIsOneError) {
  // Was a bug (fixed): a line holding an object followed by junk is delivered from the
  // fast path, and then, when the stream trips over the junk, the same line
  // is re-read in line mode, where parse_one accepts the object again
  // (ondemand never checks for trailing content): {"id":2}} reaches the
  // handler twice (two monitor steps for one message), {"id":2} xyz is
  // delivered once *and* reported as an error.
  const std::string content =
      "{\"id\":1}\n"
      "{\"id\":2}}\n"
      "{\"id\":3}\n"
      "{\"id\":4} xyz\n"
      "{\"id\":5}\n";
  for (const ReaderOptions& o : {ReaderOptions{}, chunked(32, 31)}) {
    Recorder r = read_file(content, o);
    EXPECT_EQ(r.objects, (Objects{{1, 1}, {3, 3}, {5, 5}})) << o.chunk_bytes;
    EXPECT_EQ(r.error_lines(), (Lines{2, 4})) << o.chunk_bytes;
  }
}

TEST(JsonlReader, UnterminatedStringIsOneErrorNotACrash) {
  // Regression: parse_one's error path once called doc.current_location()
  // on a document whose iterate() had failed (here UNCLOSED_STRING), which
  // dereferenced a null parser (SIGSEGV in `rvc check`).
  Recorder r = read_file("{\"id\":1}\n{\"id\":\"abc\n{\"id\":3}\n");
  EXPECT_EQ(r.objects, (Objects{{1, 1}, {3, 3}}));
  EXPECT_EQ(r.error_lines(), (Lines{2}));
}

TEST(JsonlReader, DocumentSpanningTwoLinesIsTwoBadLines) {
  // JSON Lines: one object per line. An object broken over two lines is two
  // bad lines (each alone is not JSON), in the fast path as in line mode.
  Recorder r = read_file("{\"id\":1}\n{\"id\":\n2}\n{\"id\":4}\n");
  EXPECT_EQ(r.objects, (Objects{{1, 1}, {4, 4}}));
  EXPECT_EQ(r.error_lines(), (Lines{2, 3}));
}

TEST(JsonlReader, DocumentSpanningLinesDoesNotDependOnItsNeighbours) {
  // Whether the chunk is read fast or (after an earlier bad line) line by
  // line, the same two lines give the same two errors.
  const std::string spanning = "{\"id\":\n2}\n{\"id\":4}\n";
  Recorder after_good = read_file("{\"id\":1}\n" + spanning);
  Recorder after_bad = read_file("[1]\n" + spanning);
  EXPECT_EQ(after_good.error_lines(), (Lines{2, 3}));
  EXPECT_EQ(after_bad.error_lines(), (Lines{1, 2, 3}));
  Objects good_tail(after_good.objects.begin() + 1, after_good.objects.end());
  EXPECT_EQ(after_bad.objects, good_tail);
}

}  // namespace
}  // namespace rvc::io
