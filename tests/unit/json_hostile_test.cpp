// Hostile JSON: every malformed message is rejected whatever the properties
// read (so one property's verdicts never depend on another property being
// there), keys ending in an escaped backslash, byte-order marks.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <random>
#include <string>
#include <vector>

#include "runtime/pipeline.hpp"
#include "test_util.hpp"

namespace rvc::runtime {
namespace {

struct Result {
  std::vector<std::pair<double, bool>> verdicts;  // of property "a" only
  PipelineStats stats;
  std::string stderr_text;
};

// Runs `lines` through the chunked file reader (or, with `payloads`, one
// network payload per line, as `rvc monitor` feeds them).
Result run(const std::vector<engine::PropertySpec>& props, const std::string& content, bool payloads = false,
           PipelineOptions o = {}, size_t chunk = 256) {
  Result r;
  o.emit_all = true;
  testing::internal::CaptureStderr();
  {
    Pipeline p(props, o, [&](const engine::Verdict& v) {
      if (v.property == "a") r.verdicts.emplace_back(v.time, v.value);
    });
    if (payloads) {
      uint64_t n = 0;
      for (size_t at = 0; at < content.size();) {
        size_t nl = content.find('\n', at);
        std::string line = content.substr(at, nl - at);
        at = nl == std::string::npos ? content.size() : nl + 1;
        ++n;
        if (!line.empty()) p.feed(line, n);
      }
    } else {
      test::TempFile f(content);
      int fd = ::open(f.path().c_str(), O_RDONLY);
      std::string error;
      io::ReaderOptions ro;
      ro.chunk_bytes = chunk;  // many chunks: the fast path and its fallback both run
      ro.max_line_bytes = o.max_message_size;
      EXPECT_TRUE(io::read_jsonl(fd, p, ro, error)) << error;
      ::close(fd);
    }
    r.stats = p.stats();
  }
  r.stderr_text = testing::internal::GetCapturedStderr();
  return r;
}

const std::vector<engine::PropertySpec> kAlone = {{"a", "{x > 0} since {y}"}};
const std::vector<engine::PropertySpec> kWithOther = {{"a", "{x > 0} since {y}"}, {"b", "{u.v == \"w\"} or {z}"}};

TEST(JsonHostile, MalformedUntestedFieldsAreRejected) {
  for (const char* bad : {R"({"x":1,"z":tru})", R"({"x":1,"z":01})", R"({"x":1,"z":[1,,2]})", R"({"x":1,"z":"\q"})",
                          R"({"x":1,"u":{"v":nul}})", R"({"x":1,"z":-})", R"({"x":[1,,2]})", R"({"x":1,"z":nulx})"}) {
    for (bool payloads : {false, true}) {
      Result r = run(kAlone, std::string(R"({"x":1,"y":true})") + "\n" + bad + "\n" + R"({"x":2})" + "\n", payloads);
      EXPECT_EQ(r.stats.accepted, 2u) << bad;
      EXPECT_EQ(r.stats.rejected, 1u) << bad << r.stderr_text;
      EXPECT_NE(r.stderr_text.find("line 2"), std::string::npos) << r.stderr_text;
    }
  }
}

TEST(JsonHostile, KeyEndingInEscapedBackslash) {
  // {"a\\":1}: the key is a + backslash; its closing quote follows an escaped
  // backslash. The key scan used to run past the end of the buffer.
  for (bool payloads : {false, true}) {
    Result r = run({{"a", "{x > 0}"}, {"b", R"({"q\\" > 0})"}},
                R"({"x":1,"a\\":1})" "\n" R"({"a\\":2,"x":0})" "\n" R"({"q\\":1,"x":3})" "\n", payloads);
    EXPECT_EQ(r.stats.accepted, 3u) << r.stderr_text;
    EXPECT_EQ(r.verdicts, (std::vector<std::pair<double, bool>>{{0, true}, {1, false}, {2, true}}));
  }
}

TEST(JsonHostile, ByteOrderMarkAtTheStartIsSkippedWithAWarning) {
  Result r = run(kAlone, "\xEF\xBB\xBF{\"x\":1,\"y\":true}\n\xEF\xBB\xBF{\"x\":1}\n{\"x\":1}\n");
  EXPECT_EQ(r.stats.accepted, 2u);  // line 1 kept, line 3 kept
  EXPECT_EQ(r.stats.rejected, 1u);  // a mark at the start of line 2 is not the file's
  EXPECT_EQ(r.stats.warnings, 1u);
  EXPECT_NE(r.stderr_text.find("line 1: skipped a UTF-8 byte-order mark"), std::string::npos) << r.stderr_text;
  EXPECT_NE(r.stderr_text.find("line 2, column 1: UTF-8 byte-order mark"), std::string::npos) << r.stderr_text;
  Result p = run(kAlone, "\xEF\xBB\xBF{\"x\":1}\n", true);  // a network payload: an error naming it
  EXPECT_EQ(p.stats.rejected, 1u);
  EXPECT_NE(p.stderr_text.find("byte-order mark"), std::string::npos) << p.stderr_text;
}

// Found by fuzz_jsonl: small chunks and a small size limit; the file reader
// and one payload per line must accept and reject the same messages.
TEST(JsonHostile, FuzzFoundChunkedReaderCase) {
  const std::string content = std::string("\n{\"x\":1} {\"x\":2}\0{\"x\":\n{\" {\"x\":2}\0{\"x\":\n{\"x\":2tr}", 50);
  PipelineOptions o;
  o.model = engine::TimeModel::Dense;
  o.max_message_size = 24;
  Result file = run(kAlone, content, false, o, 16), payloads = run(kAlone, content, true, o);
  EXPECT_EQ(file.stats.accepted, payloads.stats.accepted);
  EXPECT_EQ(file.stats.rejected, payloads.stats.rejected) << file.stderr_text << "\n---\n" << payloads.stderr_text;
}

// Random messages, some malformed in tested or untested fields: property a's
// verdicts and the rejected count must not change when property b (reading
// other fields) is added, in the file path and in the payload path.
TEST(JsonHostile, VerdictsDoNotDependOnOtherProperties) {
  std::mt19937 rng(20261123);
  const std::vector<std::string> good = {"1", "-2.5", "0", "true", "false", "null", "\"w\"", "\"\\u0077\"",
                                         "[1,2,{\"k\":[]}]", "{\"v\":\"w\"}", "{}", "1e3"};
  const std::vector<std::string> bad = {"tru", "01", "[1,,2]", "\"\\q\"", "nul", "-", "{\"v\":}", "[1 2]", "+1"};
  for (int round = 0; round < 40; ++round) {
    std::string content;
    for (int i = 0; i < 60; ++i) {
      std::string line = "{";
      const char* keys[] = {"x", "y", "z", "u", "pad"};
      for (int k = 0; k < 5; ++k) {
        if (rng() % 4 == 0) continue;
        std::string value = rng() % 12 == 0 ? bad[rng() % bad.size()] : good[rng() % good.size()];
        if (k == 0 && rng() % 2) value = std::to_string(static_cast<int>(rng() % 5) - 2);
        line += std::string(line.size() > 1 ? "," : "") + "\"" + keys[k] + "\":" + value;
      }
      content += line + "}\n";
    }
    for (bool payloads : {false, true}) {
      Result alone = run(kAlone, content, payloads), both = run(kWithOther, content, payloads);
      ASSERT_EQ(alone.verdicts, both.verdicts) << content;
      ASSERT_EQ(alone.stats.rejected, both.stats.rejected) << content;
      ASSERT_EQ(alone.stats.accepted, both.stats.accepted) << content;
    }
  }
}

}  // namespace
}  // namespace rvc::runtime
