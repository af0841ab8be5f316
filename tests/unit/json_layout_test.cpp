// The layout fast path (io/json_layout.hpp): a line laid out like an earlier
// one is read by position. The oracle is simdjson: every run is repeated with
// layouts off (every line parsed by simdjson), and verdicts, robustness
// values (bit for bit), errors and counters must be identical, on hand-made
// lines and on random ones built to sit on the edges of the fast path.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "io/json_layout.hpp"
#include "runtime/pipeline.hpp"
#include "test_util.hpp"

namespace rvc {
namespace {

using io::FieldValue;
using io::JsonLayout;
using io::ValueKind;

// A layout learned from `text`, whose values are the given substrings (in order).
JsonLayout layout_of(const std::string& text, const std::vector<std::string>& values) {
  std::vector<JsonLayout::Range> ranges;
  size_t from = 0;
  for (const std::string& v : values) {
    size_t at = text.find(v, from);
    EXPECT_NE(at, std::string::npos) << v;
    ranges.push_back({at, at + v.size()});
    from = at + v.size();
  }
  return JsonLayout(text, ranges, std::vector<bool>(values.size(), true));
}

// Whether all of `text` is one message of layout `l`.
bool matches(const JsonLayout& l, std::string_view text, FieldValue* out) {
  return l.match(text.data(), text.data() + text.size(), out) == text.data() + text.size();
}

TEST(JsonLayout, ReadsScalarsOfAnyTypeBetweenTheSameBytes) {
  JsonLayout l = layout_of(R"({"t":1,"s":"ab","b":true,"n":null})", {"1", "\"ab\"", "true", "null"});
  ASSERT_EQ(l.slots(), 4u);
  FieldValue v[4];
  ASSERT_TRUE(matches(l, R"({"t":-2.5,"s":"héllo","b":false,"n":3})", v));
  EXPECT_EQ(v[0].kind, ValueKind::Number);
  EXPECT_EQ(v[0].d, -2.5);
  EXPECT_EQ(v[1].kind, ValueKind::String);
  EXPECT_EQ(v[1].s, "héllo");
  EXPECT_EQ(v[2].kind, ValueKind::Bool);
  EXPECT_FALSE(v[2].b);
  EXPECT_EQ(v[3].kind, ValueKind::Number);
  EXPECT_EQ(v[3].d, 3);
  ASSERT_TRUE(matches(l, R"({"t":1e2,"s":"","b":null,"n":"x"})", v));
  EXPECT_EQ(v[0].d, 100);
  EXPECT_EQ(v[2].kind, ValueKind::Null);
  ASSERT_TRUE(matches(l, R"({"t":0.1,"s":"x","b":true,"n":123456789012345678901234567890})", v));
  EXPECT_EQ(v[0].d, 0.1);
  EXPECT_EQ(v[3].d, 123456789012345678901234567890.0);
}

TEST(JsonLayout, LeavesEverythingElseToSimdjson) {
  JsonLayout l = layout_of(R"({"t":1,"s":"ab","b":true})", {"1", "\"ab\"", "true"});
  FieldValue v[3];
  for (const char* line : {
           R"({"t":1,"s":"ab","b":true}})",     // text after the object
           R"({"t":1, "s":"ab","b":true})",     // other spacing
           R"({"t":1,"S":"ab","b":true})",      // another key
           R"({"t":01,"s":"ab","b":true})",     // leading zero
           R"({"t":1.,"s":"ab","b":true})",     // no fraction digits
           R"({"t":-,"s":"ab","b":true})",      // a lone sign
           R"({"t":+1,"s":"ab","b":true})",     // a plus sign
           R"({"t":1e,"s":"ab","b":true})",     // no exponent digits
           R"({"t":1e400,"s":"ab","b":true})",  // out of range
           R"({"t":1e0001,"s":"ab","b":true})",  // a 4-digit exponent
           R"({"t":1,"s":"a\"b","b":true})",    // an escape
           R"({"t":1,"s":"a)" "\t" R"(b","b":true})",  // a control byte in a string
           R"({"t":1,"s":"a)" "\xff" R"(b","b":true})",  // not UTF-8
           R"({"t":1,"s":"ab","b":tru})",       // a broken literal
           R"({"t":1,"s":"ab","b":truex})",     // a literal and more
           R"({"t":{},"s":"ab","b":true})",     // an object where a scalar was
           R"({"t":[1],"s":"ab","b":true})",    // an array
           R"({"t":1,"s":"ab)",                 // cut short
           "",
       })
    EXPECT_FALSE(matches(l, line, v)) << line;
}

TEST(JsonLayout, AMatchEndsWhereTheLayoutEnds) {
  JsonLayout l = layout_of(R"({"a":1})", {"1"});
  FieldValue v[1];
  const std::string text = "{\"a\":22}\n{\"a\":3}";
  EXPECT_EQ(l.match(text.data(), text.data() + text.size(), v), text.data() + 8);
  EXPECT_EQ(v[0].d, 22);
}

TEST(JsonLayout, TextIsTheLineWithoutSurroundingWhitespace) {
  EXPECT_EQ(io::layout_text("  {\"a\":1}\r"), "{\"a\":1}");
  EXPECT_EQ(io::layout_text("\t{}\n"), "{}");
}

// ---- differential: layouts on vs off, through the whole pipeline ----

struct Outcome {
  std::vector<std::tuple<std::string, double, bool, uint64_t>> verdicts;  // robustness as its bits
  runtime::PipelineStats stats;
  std::string errors;
};

Outcome run(const std::vector<engine::PropertySpec>& properties, runtime::PipelineOptions options, const std::string& text,
        bool layouts, bool as_payloads) {
  Outcome r;
  options.layouts = layouts;
  options.max_reported = 1 << 30;
  testing::internal::CaptureStderr();
  {
    runtime::Pipeline p(properties, options, [&](const engine::Verdict& v) {
      uint64_t bits;
      std::memcpy(&bits, &v.robustness, sizeof bits);
      r.verdicts.emplace_back(v.property, v.time, v.value, bits);
    });
    if (as_payloads) {  // one payload per line, as `rvc monitor` gets them
      uint64_t seq = 0;
      for (size_t at = 0; at < text.size();) {
        size_t nl = text.find('\n', at);
        p.feed(std::string_view(text).substr(at, nl - at), ++seq);
        at = nl + 1;
      }
    } else {
      test::TempFile f(text);
      int fd = ::open(f.path().c_str(), O_RDONLY);
      io::ReaderOptions ro;
      ro.chunk_bytes = 4096;  // many chunks: runs of parsed lines meet chunk ends
      std::string error;
      EXPECT_TRUE(io::read_jsonl(fd, p, ro, error)) << error;
      ::close(fd);
    }
    r.stats = p.stats();
  }
  r.errors = testing::internal::GetCapturedStderr();
  return r;
}

// A value for the random lines: mostly well-formed, often of the field's
// usual type, sometimes at the edges of what the fast path reads.
std::string random_value(std::mt19937& rng, int usual) {
  static const std::vector<std::string> odd = {
      "-0", "0", "0.0", "-0.0", "1e2", "1E-2", "2.5e+3", "1e308", "1.7976931348623157e308", "1.8e308", "4.9e-324",
      "1e-400", "1e0001", "01", "1.", ".5", "-", "+1", "123456789012345678901", "9007199254740993",
      "0.30000000000000004", "1234567890.123456789", "\"\"", "\"w\"", "\"a b\"", "\"\\u0077\"", "\"\\n\"",
      "\"h\xc3\xa9\"", "\"\xff\"", "\"\t\"", "true", "false", "null", "tru", "nul", "{}", "[]", "{\"k\":1}", "[1,2]"};
  std::uniform_int_distribution<int> pick(0, 39);
  const int k = pick(rng) % 10;
  if (pick(rng) < 2) return odd[std::uniform_int_distribution<size_t>(0, odd.size() - 1)(rng)];
  switch (usual) {
    case 0: return k % 2 ? "true" : "false";
    case 1: {
      std::uniform_int_distribution<int> digits(-300, 300);
      char buf[64];
      if (k < 6) std::snprintf(buf, sizeof buf, "%d", digits(rng));
      else std::snprintf(buf, sizeof buf, "%.*g", k, digits(rng) / 7.0);
      return buf;
    }
    default: return k % 2 ? "\"w\"" : "\"v\"";
  }
}

std::string random_trace(std::mt19937& rng, size_t lines) {
  std::string text;
  std::uniform_int_distribution<int> pick(0, 99);
  double time = 0;
  for (size_t i = 0; i < lines; ++i) {
    time += 0.5;
    const int shape = pick(rng);
    std::string line;
    if (shape < 3) {
      line = "{\"time\":" + std::to_string(time) + ",\"x\":" + random_value(rng, 1) + "}";  // fewer fields
    } else if (shape < 5) {
      line = "{\"time\": " + std::to_string(time) + ", \"y\": " + random_value(rng, 0) + "}";  // other spacing
    } else if (shape < 6) {
      line = "{\"time\":" + std::to_string(time) + ",\"x\":1}} ";  // text after the object
    } else if (shape < 7) {
      line = "not json";
    } else {
      line = "{\"time\":" + (pick(rng) < 3 ? random_value(rng, 1) : std::to_string(time)) +
             ",\"x\":" + random_value(rng, 1) + ",\"y\":" + random_value(rng, 0) + ",\"s\":" + random_value(rng, 2) +
             ",\"u\":{\"v\":" + random_value(rng, 1) + ",\"w\":[" + random_value(rng, 1) + "]}}";
      if (pick(rng) < 5) line += "\r";
    }
    text += line + "\n";
  }
  return text;
}

void expect_same(const std::vector<engine::PropertySpec>& props, const runtime::PipelineOptions& o,
                 const std::string& text, bool payloads) {
  Outcome fast = run(props, o, text, true, payloads);
  Outcome slow = run(props, o, text, false, payloads);
  EXPECT_EQ(fast.verdicts, slow.verdicts);
  if (fast.errors != slow.errors) {  // the first line that differs, not pages of both
    size_t at = 0;
    while (at < fast.errors.size() && at < slow.errors.size() && fast.errors[at] == slow.errors[at]) ++at;
    at = fast.errors.rfind('\n', at) + 1;
    ADD_FAILURE() << "errors differ:\n layouts: " << fast.errors.substr(at, fast.errors.find('\n', at) - at)
                  << "\n simdjson: " << slow.errors.substr(at, slow.errors.find('\n', at) - at);
  }
  EXPECT_EQ(fast.stats.accepted, slow.stats.accepted);
  EXPECT_EQ(fast.stats.rejected, slow.stats.rejected);
  EXPECT_EQ(fast.stats.warnings, slow.stats.warnings);
  EXPECT_EQ(slow.stats.by_layout, 0u);
  // The fast path must have been taken, or this test proves nothing.
  EXPECT_GT(fast.stats.by_layout, fast.stats.accepted / 3) << "layouts read too few lines";
}

const std::vector<engine::PropertySpec> kProps = {
    {"a", "{x > 0} since ({y} or {s == \"w\"})"},
    {"b", "once[1:3] ({u.v >= 2.5} or {x == 0.30000000000000004} or {u.k: *})"},
    {"c", "historically(exists[z].({s: *z} and once {s: *z}))"},
};

TEST(JsonLayoutDifferential, DiscreteFileAndPayloadsMatchSimdjson) {
  std::mt19937 rng(7);
  for (int round = 0; round < 4; ++round) {
    const std::string text = random_trace(rng, 3000);
    runtime::PipelineOptions o;
    o.emit_all = true;
    expect_same(kProps, o, text, false);
    expect_same(kProps, o, text, true);
  }
}

TEST(JsonLayoutDifferential, RobustnessValuesAreBitForBitTheSame) {
  std::mt19937 rng(11);
  const std::vector<engine::PropertySpec> props = {
      {"q", "{x >= 1.5} since {y}"}, {"v", "once[0:2] {u.v <= -1}"}, {"w", "historically {x < 100}"}};
  for (int round = 0; round < 3; ++round) {
    const std::string text = random_trace(rng, 3000);
    runtime::PipelineOptions o;
    o.emit_all = true;
    o.robustness = true;
    expect_same(props, o, text, false);
  }
}

TEST(JsonLayoutDifferential, DenseTimeMatchesSimdjson) {
  std::mt19937 rng(5);
  for (int round = 0; round < 3; ++round) {
    const std::string text = random_trace(rng, 3000);
    runtime::PipelineOptions o;
    o.model = engine::TimeModel::Dense;
    expect_same({{"a", "{x > 0} since[0:2] ({y} or {s == \"w\"})"}, {"b", "once[1:3] {u.v >= 2.5}"}}, o, text, false);
    expect_same({{"a", "{x > 0} since[0:2] ({y} or {s == \"w\"})"}}, o, text, true);
  }
}

}  // namespace
}  // namespace rvc

namespace rvc {
namespace {

// A stretch where messages keep changing shape makes layouts rest (they would
// cost more than they save); once the shape settles, they are back.
TEST(JsonLayoutDifferential, LayoutsRestWhileShapesChurnAndComeBack) {
  std::mt19937 rng(3);
  std::string churn;
  const char* keys[] = {"\"x\":", "\"y\":", "\"s\":", "\"time\":"};
  for (int i = 0; i < 1000; ++i) {  // keys in a random order: 24 shapes
    std::vector<int> order = {0, 1, 2, 3};
    std::shuffle(order.begin(), order.end(), rng);
    std::string line = "{";
    for (int k : order) {
      if (line.size() > 1) line += ",";
      line += std::string(keys[k]) + (k == 1 ? (i % 3 ? "true" : "false") : k == 2 ? "\"w\"" : std::to_string(i % 7));
    }
    churn += line + "}\n";
  }
  std::string text = churn;
  for (int i = 0; i < 5000; ++i)
    text += "{\"time\":" + std::to_string(i) + ",\"x\":" + std::to_string(i % 5) + ",\"y\":" + (i % 4 ? "true" : "false") +
            ",\"s\":\"v\"}\n";
  runtime::PipelineOptions o;
  o.emit_all = true;
  const std::vector<engine::PropertySpec> props = {{"a", "{x > 2} since {y}"}};
  Outcome fast = run(props, o, text, true, false);
  Outcome slow = run(props, o, text, false, false);
  EXPECT_EQ(fast.verdicts, slow.verdicts);
  EXPECT_EQ(fast.stats.accepted, 6000u);
  EXPECT_GT(fast.stats.by_layout, 3500u) << "layouts should be back once the shape settles";
  // Tried on every line, 4 kept layouts of 24 shapes would match about 1 line in 6.
  Outcome churning = run(props, o, churn, true, false);
  EXPECT_LT(churning.stats.by_layout, 80u) << "layouts should rest while shapes churn";
  EXPECT_EQ(churning.verdicts, run(props, o, churn, false, false).verdicts);
}

}  // namespace
}  // namespace rvc
