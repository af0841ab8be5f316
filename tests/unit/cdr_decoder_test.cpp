// Typed input decodes CDR straight into the tests' values (io::CdrDecoder).
// Oracles: the JSON path on the same messages (verdicts and warnings must be
// equal), cdr_to_json (the decoder must refuse exactly the samples it refuses,
// with the same words) and hand-computed dense times.
#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "io/cdr_codec.hpp"
#include "io/cdr_decoder.hpp"
#include "msg/type_registry.hpp"
#include "runtime/pipeline.hpp"

namespace rvc::io {
namespace {

const char* kAll =
    "bool flag\nbyte b\nchar c\nint8 i8\nuint8 u8\nint16 i16\nuint16 u16\nint32 i32\nuint32 u32\n"
    "int64 i64\nuint64 u64\nfloat32 f32\nfloat64 f64\nstring name\nstring<=5 short_name\n"
    "t_msgs/Inner inner\nt_msgs/Inner[] inners\nfloat64[3] fixed\nint16[<=4] bounded\nbool[] flags\n"
    "string[] names\nfloat64 t\n";
const char* kInner = "float32 x\nbool on\nstring label\nt_msgs/Empty nothing\n";

struct Types {
  msg::TypeRegistry reg;
  const msg::MessageType* all;
  Types() {
    reg.add_definition("t_msgs/msg/Inner", kInner, "test");
    reg.add_definition("t_msgs/msg/Empty", "", "test");
    reg.add_definition("t_msgs/msg/All", kAll, "test");
    all = &reg.resolve("t_msgs/msg/All");
  }
};

std::string encode(const msg::MessageType& type, const std::string& json, bool big_endian = false) {
  std::string sample, error;
  CdrWriteOptions o;
  o.big_endian = big_endian;
  EXPECT_TRUE(json_to_cdr(type, json, sample, error, o)) << error << " in " << json;
  return sample;
}

// A random message of type All, as JSON; `t` is its (increasing) time.
std::string random_all(std::mt19937& rng, double t) {
  auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<unsigned>(n)); };
  auto inner = [&] {
    const char* labels[] = {"\"a\"", "\"b\"", "\"\""};
    return std::string(R"({"x":)") + std::to_string(pick(7) - 3) + ".5,\"on\":" + (pick(2) ? "true" : "false") +
           ",\"label\":" + labels[pick(3)] + ",\"nothing\":{}}";
  };
  std::string j = "{";
  j += std::string("\"flag\":") + (pick(2) ? "true" : "false");
  j += ",\"b\":" + std::to_string(pick(256)) + ",\"c\":" + std::to_string(pick(128));
  j += ",\"i8\":" + std::to_string(pick(256) - 128) + ",\"u8\":" + std::to_string(pick(256));
  j += ",\"i16\":" + std::to_string(pick(2000) - 1000) + ",\"u16\":" + std::to_string(pick(65536));
  j += ",\"i32\":" + std::to_string(pick(200000) - 100000) + ",\"u32\":" + std::to_string(rng());
  j += ",\"i64\":" + std::to_string(static_cast<int64_t>(rng()) * (pick(2) ? -4096 : 4096));
  j += ",\"u64\":" + std::to_string(static_cast<uint64_t>(rng()) << 20);
  j += ",\"f32\":" + std::to_string(pick(100) - 50) + ".25,\"f64\":" + std::to_string(pick(1000)) + ".125";
  const char* names[] = {"\"ab\"", "\"\"", "\"caf\\u00e9\"", "\"x y\""};
  j += std::string(",\"name\":") + names[pick(4)] + ",\"short_name\":" + names[pick(4)];
  j += ",\"inner\":" + inner() + ",\"inners\":[";
  for (int i = pick(3); i > 0; --i) j += inner() + (i > 1 ? "," : "");
  j += "],\"fixed\":[1.5," + std::to_string(pick(9)) + ",-2],\"bounded\":[";
  for (int i = pick(5); i > 0; --i) j += std::to_string(pick(100)) + (i > 1 ? "," : "");
  j += "],\"flags\":[";
  for (int i = pick(4); i > 0; --i) j += std::string(pick(2) ? "true" : "false") + (i > 1 ? "," : "");
  j += "],\"names\":[" + std::string(pick(2) ? "\"n\"" : "") + "],\"t\":" + std::to_string(t) + "}";
  return j;
}

// Tests on every field and of every kind, including tests of the wrong type
// (a string compared with a number, a truthiness test on an array), which
// keep their previous value and are reported as warnings.
const std::vector<engine::PropertySpec> kProps = {
    {"flag", "{flag} && {b > 100} || {c == 65}"},
    {"ints", "{i8 < 0} && {u8 >= 128} || {i16 != -3} && {u16 <= 30000}"},
    {"wide", "once[0:3]({i32 > 0} && {u32 > 2000000000}) || {i64 < 0} && {u64 > 1000000}"},
    {"floats", "historically[0:2]({f32 >= 0.25} || {f64 == 5.125})"},
    {"names", "{name == \"ab\"} || {short_name == \"caf\u00e9\"} || {name != \"\"} && {short_name: *}"},
    {"inner", "{inner.x > 0} && {inner.on} || {inner.label == \"a\"} && {inner: *}"},
    {"arrays", "{inners: *} && {fixed: *} || {bounded} || {flags == true}"},
    {"wrong", "{name > 3} || {inner.on == 1} || {u8 == \"a\"} || {inner}"},
    // 0/1 flags in integer fields, Booleans read as numbers (Reelay's rule, io::evaluate_test)
    {"flags01", "{u8: true} && {i8: false} || {flag > 0} && {inner.on == 1} || {c: false}"},
    {"nothing", "{inner.nothing: *} && once[0:1]{inner.nothing}"},
};

struct RunResult {
  std::vector<std::string> verdicts;
  runtime::PipelineStats stats;
};

RunResult run(const std::vector<std::string>& jsons, const msg::MessageType* typed, engine::TimeModel model,
        bool big_endian = false) {
  runtime::PipelineOptions o;
  o.emit_all = true;
  o.model = model;
  o.time_field = "t";
  o.type = typed;
  o.max_reported = 0;
  RunResult r;
  runtime::Pipeline p(kProps, o, [&](const engine::Verdict& v) {
    r.verdicts.push_back(v.property + "@" + std::to_string(v.time) + (v.value ? "T" : "F"));
  });
  uint64_t seq = 0;
  for (const auto& j : jsons) p.feed(typed ? encode(*typed, j, big_endian) : j, ++seq);
  r.stats = p.stats();
  return r;
}

TEST(CdrDecoder, VerdictsAndWarningsEqualTheJsonPath) {
  Types types;
  std::mt19937 rng(20261123);
  std::vector<std::string> jsons;
  for (int i = 0; i < 400; ++i) jsons.push_back(random_all(rng, 0.5 * (i + 1)));
  for (auto model : {engine::TimeModel::Discrete, engine::TimeModel::Dense}) {
    const RunResult from_json = run(jsons, nullptr, model);
    ASSERT_EQ(from_json.stats.rejected, 0u);
    ASSERT_EQ(from_json.stats.accepted, jsons.size());
    EXPECT_GT(from_json.stats.warnings, 0u);  // the "wrong" property's tests
    ASSERT_GT(from_json.verdicts.size(), 0u);
    for (bool big : {false, true}) {
      const RunResult typed = run(jsons, types.all, model, big);
      EXPECT_EQ(typed.stats.rejected, 0u);
      EXPECT_EQ(typed.stats.accepted, from_json.stats.accepted);
      EXPECT_EQ(typed.stats.warnings, from_json.stats.warnings);
      EXPECT_EQ(typed.verdicts, from_json.verdicts) << (big ? "big" : "little") << " endian";
    }
  }
}

// --robustness on typed samples: each test's margin as on the same message
// as JSON (io::test_margin on both paths), so every robustness value equals
// the JSON path's, discrete and dense, in both endiannesses. The properties
// read every kind of field (integers of each width, floats, strings,
// Booleans, nested and indexed fields, presence, wrong types) under every
// operator, since with and without bounds included.
TEST(CdrDecoder, RobustnessEqualsTheJsonPath) {
  Types types;
  const std::vector<engine::PropertySpec> props = {
      {"numbers", "({i8 < 0} && {u16 <= 30000}) || {i32 > 0} && not {u64 > 1000000} || {f32 >= 0.25}"},
      {"since", "({f64 > 500} since[1:3] {inner.x > 0}) || ({i16 > 0} since {b < 100})"},
      {"half", "historically[0:2]({u8 >= 128} since[1:] {inners[0].x < 1}) || once[1:2]{fixed[1] != 4}"},
      {"kinds", "({flag} && {name == \"ab\"}) || {inner.on} && {short_name: *} || {bounded[1]} -> {i64 < 0}"},
      {"wrong", "{name > 3} || {inner.on == 1} || {u8 == \"a\"}"},
      {"flags01", "({u8: true} && {i8: false}) || {flag >= 1} && {inner.on != 0} || {c: false}"},
  };
  const auto run_robust = [&](const std::vector<std::string>& jsons, const msg::MessageType* typed,
                              engine::TimeModel model, bool big_endian) {
    runtime::PipelineOptions o;
    o.emit_all = true;
    o.model = model;
    o.time_field = "t";
    o.type = typed;
    o.robustness = true;
    o.max_reported = 0;
    std::vector<std::string> out;
    runtime::Pipeline p(props, o, [&](const engine::Verdict& v) {
      EXPECT_TRUE(v.robust);
      char value[64];
      std::snprintf(value, sizeof value, "@%.17g=%.17g", v.time, v.robustness);
      out.push_back(v.property + value);
    });
    uint64_t seq = 0;
    for (const auto& j : jsons) p.feed(typed ? encode(*typed, j, big_endian) : j, ++seq);
    EXPECT_EQ(p.stats().rejected, 0u);
    EXPECT_EQ(p.stats().accepted, jsons.size());
    return out;
  };
  std::mt19937 rng(515);
  std::vector<std::string> jsons;
  for (int i = 0; i < 300; ++i) jsons.push_back(random_all(rng, 0.5 * (i + 1)));
  for (auto model : {engine::TimeModel::Discrete, engine::TimeModel::Dense}) {
    const std::vector<std::string> from_json = run_robust(jsons, nullptr, model, false);
    ASSERT_GT(from_json.size(), 100u);
    // Margins, not only infinities and 0/1: many different values.
    std::set<std::string> values;
    for (const std::string& v : from_json) values.insert(v.substr(v.find('=')));
    EXPECT_GT(values.size(), 20u);
    for (bool big : {false, true})
      EXPECT_EQ(run_robust(jsons, types.all, model, big), from_json) << (big ? "big" : "little") << " endian";
  }
}

// Every corruption cdr_to_json refuses, the decoder refuses with the same
// words and offset, whatever the properties read; and nothing else.
TEST(CdrDecoder, RefusesExactlyWhatCdrToJsonRefuses) {
  Types types;
  // One field read (the rest only checked), and array elements read.
  for (const char* spec : {"{f64 > 1}", "{inners[1].x > 0} || {bounded[2] > 3} || {names[0] == \"n\"} || {flags[1]}"}) {
    engine::Checker checker(engine::TimeModel::Discrete, false, [](const engine::Verdict&) {});
    checker.add_property({"p", spec});
    CdrDecoder decoder(checker.atoms(), *types.all, DecoderOptions{});
    std::mt19937 rng(7);
    int refused = 0;
    for (int i = 0; i < 3000; ++i) {
      std::string sample = encode(*types.all, random_all(rng, i), i % 2);
      const int how = static_cast<int>(rng() % 3);
      if (how == 0) sample.resize(rng() % sample.size());
      if (how >= 1) sample[4 + rng() % (sample.size() - 4)] = static_cast<char>(rng());
      if (how == 2) sample += std::string(rng() % 9, '\0');
      std::string json, error;
      CdrError expected;
      const bool ok = cdr_to_json(*types.all, sample, json, expected);
      const bool decoded = decoder.decode(sample, error);
      ASSERT_EQ(decoded, ok) << spec << (ok ? ": refused: " + error : ": accepted: " + expected.to_string());
      if (!ok) {
        ++refused;
        EXPECT_TRUE(decoder.malformed());
        EXPECT_EQ(error, "bad t_msgs/msg/All sample: " + expected.to_string());
      }
    }
    EXPECT_GT(refused, 1000);
  }
}

TEST(CdrDecoder, DenseTimeIsTheStampByDefault) {
  msg::TypeRegistry reg;
  const auto& steer = reg.resolve("autoware_auto_vehicle_msgs/msg/SteeringReport");
  runtime::PipelineOptions o;
  o.emit_all = true;
  o.model = engine::TimeModel::Dense;
  o.type = &steer;
  std::vector<std::pair<double, bool>> out;
  runtime::Pipeline p({{"p", "{steering_tire_angle < 0.5}"}}, o,
                      [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  // stamps 10.25 s, 11.5 s, 12 s: each message closes the interval since the previous one
  p.feed(encode(steer, R"({"stamp":{"sec":10,"nanosec":250000000},"steering_tire_angle":0.1})"), 1);
  p.feed(encode(steer, R"({"stamp":{"sec":11,"nanosec":500000000},"steering_tire_angle":0.9})"), 2);
  p.feed(encode(steer, R"({"stamp":{"sec":12,"nanosec":0},"steering_tire_angle":0.2})"), 3);
  EXPECT_EQ(p.stats().accepted, 3u);
  ASSERT_GE(out.size(), 2u);
  EXPECT_DOUBLE_EQ(out.front().first, 10.25);  // the timeline starts at the first stamp (issue 36)
  bool saw_violation_at_11_5 = false;
  for (auto [t, v] : out) saw_violation_at_11_5 = saw_violation_at_11_5 || (t == 11.5 && !v);
  EXPECT_TRUE(saw_violation_at_11_5);
  // A stamp that goes back is refused like a JSON time that goes back.
  p.feed(encode(steer, R"({"stamp":{"sec":11,"nanosec":0},"steering_tire_angle":0.2})"), 4);
  EXPECT_EQ(p.stats().rejected, 1u);
}

TEST(CdrDecoder, ATimeFieldTheTypeLacksIsNamed) {
  Types types;
  engine::Checker checker(engine::TimeModel::Dense, false, [](const engine::Verdict&) {});
  DecoderOptions o;
  o.need_time = true;
  o.time_field = "inner.when";
  try {
    CdrDecoder d(checker.atoms(), *types.all, o);
    FAIL() << "a missing time field was accepted";
  } catch (const msg::MsgError& e) {
    EXPECT_NE(std::string(e.what()).find("'inner.when' (--time-field)"), std::string::npos) << e.what();
  }
  o.time_field = "name";  // a string is no time
  EXPECT_THROW(CdrDecoder(checker.atoms(), *types.all, o), msg::MsgError);
  o.time_field = "inner.x";  // a nested number is
  EXPECT_NO_THROW(CdrDecoder(checker.atoms(), *types.all, o));
}

TEST(CdrDecoder, StrictModeRefusesAWrongTypeInsteadOfWarning) {
  Types types;
  engine::Checker checker(engine::TimeModel::Discrete, false, [](const engine::Verdict&) {});
  checker.add_property({"p", "{name > 3}"});
  DecoderOptions o;
  o.strict = true;
  CdrDecoder d(checker.atoms(), *types.all, o);
  std::mt19937 rng(1);
  std::string error;
  EXPECT_FALSE(d.decode(encode(*types.all, random_all(rng, 1)), error));
  EXPECT_FALSE(d.malformed());
  EXPECT_EQ(error, "field \"name\" is a string, but {name > 3} needs a number");
}

}  // namespace
}  // namespace rvc::io

namespace rvc::io {
namespace {

// A property with no field test at all has no atom values to copy: found by
// fuzz_cdr under UBSan (memcpy from the null data of an empty vector), in the
// JSON decoder as much as in the CDR one.
TEST(CdrDecoder, APropertyWithoutFieldTests) {
  Types types;
  std::mt19937 rng(2);
  for (bool typed : {false, true}) {
    runtime::PipelineOptions o;
    o.emit_all = true;
    o.type = typed ? types.all : nullptr;
    int verdicts = 0;
    runtime::Pipeline p({{"p", "true"}}, o, [&](const engine::Verdict& v) { verdicts += v.value; });
    const std::string json = random_all(rng, 1);
    p.feed(typed ? encode(*types.all, json) : json, 1);
    EXPECT_EQ(p.stats().accepted, 1u);
    EXPECT_EQ(verdicts, 1);
  }
}

}  // namespace
}  // namespace rvc::io
