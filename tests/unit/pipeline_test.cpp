// Pipeline: reader + decoder + checker. Bad lines are rejected once each and
// named by line; valid lines around them still step the monitors; dense time
// rejects non-increasing times and keeps going.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "runtime/pipeline.hpp"
#include "spec/spec_error.hpp"
#include "test_util.hpp"

namespace rvc::runtime {
namespace {

using test::TV;
using TVs = std::vector<TV>;

struct Result {
  TVs verdicts;
  PipelineStats stats;
  std::string stderr_text;
};

Result run(const std::vector<engine::PropertySpec>& properties, const PipelineOptions& options,
           const std::string& content, const io::ReaderOptions& reader = {}) {
  Result r;
  test::TempFile f(content);
  testing::internal::CaptureStderr();
  {
    Pipeline pipeline(properties, options, [&](const engine::Verdict& v) { r.verdicts.emplace_back(v.time, v.value); });
    int fd = ::open(f.path().c_str(), O_RDONLY);
    std::string error;
    EXPECT_TRUE(io::read_jsonl(fd, pipeline, reader, error)) << error;
    ::close(fd);
    pipeline.finish_report();
    r.stats = pipeline.stats();
  }
  r.stderr_text = testing::internal::GetCapturedStderr();
  return r;
}

size_t count(const std::string& text, const std::string& part) {
  size_t n = 0;
  for (size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++n;
  return n;
}

PipelineOptions discrete_all() {
  PipelineOptions o;
  o.emit_all = true;
  return o;
}

io::ReaderOptions chunked(size_t chunk, size_t max_line) {
  io::ReaderOptions o;
  o.chunk_bytes = chunk;
  o.max_line_bytes = max_line;
  return o;
}

// ---------------------------------------------------------------- discrete

const std::string kDiscrete =
    "{\"p\":true}\n"   // 1 -> step 0: T
    "garbage\n"        // 2 rejected
    "{\"p\":false}\n"  // 3 -> step 1: F
    "[1]\n"            // 4 rejected
    "\n"               // 5 blank: nothing
    "{\"q\":1}\n"      // 6 -> step 2: p absent, keeps F
    "{\"p\":true}";    // 7 -> step 3: T (no trailing newline)

TEST(Pipeline, DiscreteBadLinesAreSkippedOnce) {
  for (const io::ReaderOptions& ro : {io::ReaderOptions{}, chunked(16, 15)}) {
    Result r = run({{"p1", "{p}"}}, discrete_all(), kDiscrete, ro);
    // Verdict times are step indices of accepted messages, not line numbers.
    EXPECT_EQ(r.verdicts, (TVs{{0, true}, {1, false}, {2, false}, {3, true}})) << ro.chunk_bytes;
    EXPECT_EQ(r.stats.accepted, 4u);
    EXPECT_EQ(r.stats.rejected, 2u);
    EXPECT_EQ(r.stats.warnings, 0u);
    EXPECT_EQ(count(r.stderr_text, "rvc: line 2, column 1: "), 1u) << r.stderr_text;
    EXPECT_EQ(count(r.stderr_text, "rvc: line 4, column 1: "), 1u) << r.stderr_text;
    EXPECT_EQ(count(r.stderr_text, "(message skipped)"), 2u) << r.stderr_text;
  }
}

TEST(Pipeline, MalformedObjectsAreRejectedOnce) {
  // {"p" true} and {"p":} look like objects to the fast path; the decoder
  // finds the error while reading p. Each must be one rejection, and the
  // valid lines around them each one step.
  const std::string content =
      "{\"p\":true}\n"   // step 0: T
      "{\"p\" true}\n"   // 2 rejected
      "{\"p\":false}\n"  // step 1: F
      "{\"p\":}\n"       // 4 rejected
      "{\"p\":true}\n";  // step 2: T
  for (const io::ReaderOptions& ro : {io::ReaderOptions{}, chunked(16, 15)}) {
    Result r = run({{"p1", "{p}"}}, discrete_all(), content, ro);
    EXPECT_EQ(r.verdicts, (TVs{{0, true}, {1, false}, {2, true}})) << ro.chunk_bytes;
    EXPECT_EQ(r.stats.accepted, 3u);
    EXPECT_EQ(r.stats.rejected, 2u);
    EXPECT_EQ(count(r.stderr_text, "rvc: line 2"), 1u) << r.stderr_text;
    EXPECT_EQ(count(r.stderr_text, "rvc: line 4"), 1u) << r.stderr_text;
  }
}

TEST(Pipeline, ObjectWithTrailingBraceIsOneRejectionNotTwoSteps) {
  // Was a bug (fixed): {"p":true}} is delivered by the fast path (one step), then the
  // stream errors on the extra '}', the line is re-read in line mode and
  // delivered again (a second step), and no error is reported. See
  // JsonlReader.TrailingContentAfterAnObjectIsOneError.
  const std::string content = "{\"p\":false}\n{\"p\":true}}\n{\"p\":false}\n";
  Result r = run({{"p1", "{p}"}}, discrete_all(), content);
  EXPECT_EQ(r.verdicts, (TVs{{0, false}, {1, false}}));
  EXPECT_EQ(r.stats.accepted, 2u);
  EXPECT_EQ(r.stats.rejected, 1u);
}

// Was a bug (fixed; found by comparing the layout path with simdjson): a
// payload refused at one field (dense time given as a string) was reported as
// "unexpected text after the JSON object", because the decoder stopped
// reading there and line mode took the rest for trailing text.
TEST(Pipeline, APayloadRefusedAtAFieldIsReportedForThatField) {
  PipelineOptions o;
  o.model = engine::TimeModel::Dense;
  o.position_name = "seq";
  testing::internal::CaptureStderr();
  {
    Pipeline p({{"p1", "{p}"}}, o, [](const engine::Verdict&) {});
    p.feed("{\"time\":\"soon\",\"p\":true}", 7);
    EXPECT_EQ(p.stats().rejected, 1u);
  }
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("rvc: seq 7: time field \"time\" must be a number of seconds or a Time {sec, nanosec}, not a "
                     "string (message skipped)"),
            std::string::npos)
      << err;
  EXPECT_EQ(err.find("unexpected text"), std::string::npos) << err;
}

// Was a bug (fixed): junk after an object on its line was reported without
// its column when the line fell in a document stream, with it in line mode.
// Now it is re-read in line mode wherever it falls: column 11 is the second '}'.
TEST(Pipeline, TextAfterAnObjectIsReportedWithItsColumn) {
  Result r = run({{"p1", "{p}"}}, discrete_all(), "{\"p\":true}\n{\"p\":true}}\n{\"p\":false}\n");
  EXPECT_EQ(r.stats.rejected, 1u);
  EXPECT_NE(r.stderr_text.find("rvc: line 2, column 11: unexpected text after the JSON object"), std::string::npos)
      << r.stderr_text;
}

TEST(Pipeline, WarningsNameTheLine) {
  Result r = run({{"p1", "{x > 2}"}}, discrete_all(), "{\"x\":5}\n{\"x\":\"abc\"}\n{\"x\":1}\n");
  EXPECT_EQ(r.verdicts, (TVs{{0, true}, {1, true}, {2, false}}));  // line 2 keeps x > 2 true
  EXPECT_EQ(r.stats.accepted, 3u);
  EXPECT_EQ(r.stats.rejected, 0u);
  EXPECT_EQ(r.stats.warnings, 1u);
  EXPECT_NE(r.stderr_text.find("rvc: warning: line 2: field \"x\" is a string"), std::string::npos) << r.stderr_text;
}

TEST(Pipeline, StrictModeRejectsNamingTheField) {
  PipelineOptions o = discrete_all();
  o.strict = true;
  Result r = run({{"p1", "{p} and {speed > 3}"}}, o,
                 "{\"p\":true,\"speed\":5}\n{\"p\":true}\n{\"p\":true,\"speed\":\"x\"}\n{\"p\":true,\"speed\":1}\n");
  EXPECT_EQ(r.verdicts, (TVs{{0, true}, {1, false}}));
  EXPECT_EQ(r.stats.accepted, 2u);
  EXPECT_EQ(r.stats.rejected, 2u);
  EXPECT_NE(r.stderr_text.find("rvc: line 2: missing field \"speed\""), std::string::npos) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("rvc: line 3: field \"speed\" is a string"), std::string::npos) << r.stderr_text;
}

TEST(Pipeline, OversizedLineRejected) {
  std::string content = "{\"p\":true}\n{\"p\":false,\"pad\":\"" + std::string(60, 'x') + "\"}\n{\"p\":false}\n";
  for (const io::ReaderOptions& ro : {chunked(1 << 16, 32), chunked(33, 32)}) {
    Result r = run({{"p1", "{p}"}}, discrete_all(), content, ro);
    EXPECT_EQ(r.verdicts, (TVs{{0, true}, {1, false}})) << ro.chunk_bytes;
    EXPECT_EQ(r.stats.rejected, 1u);
    EXPECT_NE(r.stderr_text.find("rvc: line 2: message longer than 32 bytes"), std::string::npos) << r.stderr_text;
  }
}

TEST(Pipeline, ErrorsBeyondTheLimitAreCountedNotPrinted) {
  PipelineOptions o = discrete_all();
  o.max_reported = 1;
  Result r = run({{"p1", "{p}"}}, o, "[1]\n[2]\n{\"p\":true}\n[3]\n");
  EXPECT_EQ(r.stats.rejected, 3u);
  EXPECT_EQ(count(r.stderr_text, "(message skipped)"), 1u) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("rvc: line 1, column 1"), std::string::npos) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("2 more errors/warnings were not shown"), std::string::npos) << r.stderr_text;
}

TEST(Pipeline, SpecErrorNamesTheProperty) {
  try {
    Pipeline p({{"ok", "{p}"}, {"speedy", "{speed >}"}}, PipelineOptions{}, nullptr);
    ADD_FAILURE() << "accepted a bad spec";
  } catch (const spec::SpecError& e) {
    EXPECT_EQ(e.message().rfind("in property 'speedy': ", 0), 0u) << e.message();
    EXPECT_NE(e.message().find("expected a value"), std::string::npos) << e.message();
    EXPECT_EQ(e.column(), 9);  // the '}' where the value belongs
    EXPECT_EQ(e.source(), "{speed >}");
  }
}

TEST(Pipeline, FeedNamesMessagesBySequenceNumber) {
  PipelineOptions o = discrete_all();
  o.position_name = "seq";
  TVs verdicts;
  testing::internal::CaptureStderr();
  {
    Pipeline p({{"p1", "pre {p}"}}, o, [&](const engine::Verdict& v) { verdicts.emplace_back(v.time, v.value); });
    p.feed("{\"p\":true}", 10);
    p.feed("nope", 11);
    p.feed("{\"p\":false}", 12);
    p.feed("{\"p\":false}", 13);
    EXPECT_EQ(p.stats().accepted, 3u);
    EXPECT_EQ(p.stats().rejected, 1u);
    EXPECT_TRUE(p.violated());
  }
  std::string err = testing::internal::GetCapturedStderr();
  // pre p over T, F, F: F (first step), T, F.
  EXPECT_EQ(verdicts, (TVs{{0, false}, {1, true}, {2, false}}));
  EXPECT_NE(err.find("rvc: seq 11, column 1: "), std::string::npos) << err;
}

// ---------------------------------------------------------------- dense

TEST(Pipeline, DenseNonIncreasingTimeRejectedAndLaterLinesProcessed) {
  PipelineOptions o;
  o.model = engine::TimeModel::Dense;
  const std::string content =
      "{\"time\":0,\"p\":true}\n"    // 1: closes [0,0): nothing
      "{\"time\":1,\"p\":false}\n"   // 2: [0,1) p=T
      "{\"time\":1,\"p\":true}\n"    // 3: rejected (not after 1); its p=T is dropped
      "{\"time\":0.5}\n"             // 4: rejected (before 1)
      "{\"time\":3,\"p\":true}\n"    // 5: [1,3) p=F
      "{\"p\":false}\n"              // 6: rejected (no time)
      "{\"time\":4}\n";              // 7: [3,4) p=T
  for (const io::ReaderOptions& ro : {io::ReaderOptions{}, chunked(24, 23)}) {
    Result r = run({{"p1", "{p}"}}, o, content, ro);
    EXPECT_EQ(r.verdicts, (TVs{{0, true}, {1, false}, {3, true}})) << ro.chunk_bytes;
    EXPECT_EQ(r.stats.accepted, 4u);
    EXPECT_EQ(r.stats.rejected, 3u);
    EXPECT_NE(r.stderr_text.find("rvc: line 3: time 1 is not after the previous message's time 1"), std::string::npos)
        << r.stderr_text;
    EXPECT_NE(r.stderr_text.find("rvc: line 4: time 0.5 is not after the previous message's time 1"),
              std::string::npos)
        << r.stderr_text;
    EXPECT_NE(r.stderr_text.find("rvc: line 6: missing time field \"time\""), std::string::npos) << r.stderr_text;
  }
}

TEST(Pipeline, DenseNegativeTimeAndLateStart) {
  PipelineOptions o;
  o.model = engine::TimeModel::Dense;
  const std::string trace = "{\"time\":-1,\"p\":true}\n{\"time\":2,\"p\":true}\n{\"time\":3}\n";
  // The timeline starts at the first valid message (issue 36): nothing is said before 2.
  Result r = run({{"p1", "{p}"}}, o, trace);
  EXPECT_EQ(r.verdicts, (TVs{{2, true}}));
  EXPECT_EQ(r.stats.rejected, 1u);
  EXPECT_NE(r.stderr_text.find("rvc: line 1: time -1 is negative"), std::string::npos) << r.stderr_text;
  // --origin zero (Reelay's rule): the first message at 2 closes [0,2) with the initial (false) values.
  o.origin = runtime::Origin::Zero;
  Result z = run({{"p1", "{p}"}}, o, trace);
  EXPECT_EQ(z.verdicts, (TVs{{0, false}, {2, true}}));
}

TEST(Pipeline, DenseBoundedOperatorOverAFile) {
  PipelineOptions o;
  o.model = engine::TimeModel::Dense;
  // p true on [0,1): once[1:2] p true on [1,3); reported inside the last segment.
  Result r = run({{"late", "once[1:2] {p}"}}, o, "{\"time\":0,\"p\":true}\n{\"time\":1,\"p\":false}\n{\"time\":5}\n");
  EXPECT_EQ(r.verdicts, (TVs{{0, false}, {1, true}, {3, false}}));
  EXPECT_EQ(r.stats.accepted, 3u);
}

}  // namespace
}  // namespace rvc::runtime

namespace rvc::runtime {
namespace {

// Found by fuzz_jsonl (file vs topic oracle): the same lines read in chunks
// of any size give the same messages, verdicts and rejections.
TEST(Pipeline, FuzzFoundChunkSizeDoesNotChangeResults) {
  const std::string text = std::string("\n{\"time\":2-\"x\"20}\n{\"time\":1,\"x\":0}\n{\"time") +
                           std::string("\x01\0\0\0\0\0\0\x01", 8) + ":q2,\"}";
  PipelineOptions o = discrete_all();
  o.model = engine::TimeModel::Dense;
  o.max_message_size = 24;
  const std::vector<engine::PropertySpec> props = {{"a", "{x > 0} since ({y} or {s == \"w\"})"}};
  Result big = run(props, o, text, chunked(1 << 20, 24));
  for (size_t chunk : {1, 2, 5, 16, 17, 40}) {
    Result r = run(props, o, text, chunked(chunk, 24));
    EXPECT_EQ(r.verdicts, big.verdicts) << chunk << "\n" << r.stderr_text << "\n--- big:\n" << big.stderr_text;
    EXPECT_EQ(r.stats.accepted, big.stats.accepted) << chunk;
    EXPECT_EQ(r.stats.rejected, big.stats.rejected) << chunk << "\n" << r.stderr_text << "\n--- big:\n" << big.stderr_text;
  }
}

// Found by the 1-hour fuzz_jsonl run: a whitespace-only line longer than
// --max-message-size was a rejected message to `rvc check` but, being blank, no
// message at all to `rvc monitor --input file:`. Blank lines are no messages,
// whatever their length, whatever the chunking.
TEST(Pipeline, FuzzFoundLongBlankLineIsNoMessage) {
  const std::string text = std::string("{\"x\":1}\n") + std::string(40, ' ') + "\n \t\r" +
                           std::string(30, ' ') + "\r\n{\"x\":2}\n" + std::string(50, ' ');
  PipelineOptions o = discrete_all();
  o.max_message_size = 24;
  const std::vector<engine::PropertySpec> props = {{"a", "{x > 1}"}};
  for (size_t chunk : {1, 2, 5, 16, 17, 40, 1 << 20}) {
    Result r = run(props, o, text, chunked(chunk, 24));
    EXPECT_EQ(r.stats.accepted, 2u) << chunk;
    EXPECT_EQ(r.stats.rejected, 0u) << chunk << "\n" << r.stderr_text;
  }
}

}  // namespace
}  // namespace rvc::runtime
