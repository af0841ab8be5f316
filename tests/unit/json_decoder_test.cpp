// JsonDecoder: Reelay's missing-field semantics (an absent field keeps its
// value, false before first seen; presence tests are re-evaluated on every
// message; null reads as false for {p}), wrong types (kept, with a warning),
// strict mode, nested fields, and the dense time field.
#include <gtest/gtest.h>
#include <simdjson.h>

#include <memory>
#include <string>
#include <vector>

#include "engine/checker.hpp"
#include "io/json_decoder.hpp"
#include "test_util.hpp"

namespace rvc::io {
namespace {

class Decoder {
 public:
  explicit Decoder(const std::vector<std::string>& specs, DecoderOptions options = {},
                   engine::TimeModel model = engine::TimeModel::Discrete)
      : checker_(model, false, nullptr) {
    for (size_t i = 0; i < specs.size(); ++i) checker_.add_property({"p" + std::to_string(i), specs[i]});
    decoder_ = std::make_unique<JsonDecoder>(checker_.atoms(), options);
  }
  // Decodes one message; commits it when accepted, like the pipeline.
  bool feed(const std::string& json) {
    error.clear();
    warnings.clear();
    simdjson::padded_string padded(json);
    simdjson::ondemand::document doc;
    EXPECT_EQ(parser_.iterate(padded).get(doc), simdjson::SUCCESS) << json;
    simdjson::ondemand::object object;
    EXPECT_EQ(doc.get_object().get(object), simdjson::SUCCESS) << json;
    bool ok = decoder_->decode(object, error, &warnings);
    if (ok) decoder_->commit();
    return ok;
  }
  // The committed value of the test with canonical text `canonical`.
  int operator[](const std::string& canonical) {
    return decoder_->values()[test::atom_index(checker_, canonical)];
  }
  double time() const { return decoder_->time(); }

  std::string error;
  std::vector<std::string> warnings;

 private:
  engine::Checker checker_;
  std::unique_ptr<JsonDecoder> decoder_;
  simdjson::ondemand::parser parser_;
};

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// ---------------------------------------------------------------- missing fields

TEST(JsonDecoder, AbsentFieldKeepsPreviousValueFalseInitially) {
  Decoder d({"{p}"});
  EXPECT_EQ(d["p"], 0);  // before any message
  ASSERT_TRUE(d.feed(R"({"q": true})"));
  EXPECT_EQ(d["p"], 0);  // never seen: false
  ASSERT_TRUE(d.feed(R"({"p": true})"));
  EXPECT_EQ(d["p"], 1);
  ASSERT_TRUE(d.feed(R"({})"));
  EXPECT_EQ(d["p"], 1);  // absent: keeps true
  ASSERT_TRUE(d.feed(R"({"other": false})"));
  EXPECT_EQ(d["p"], 1);
  ASSERT_TRUE(d.feed(R"({"p": false})"));
  EXPECT_EQ(d["p"], 0);
  ASSERT_TRUE(d.feed(R"({})"));
  EXPECT_EQ(d["p"], 0);  // absent: keeps false
  EXPECT_TRUE(d.warnings.empty());
}

TEST(JsonDecoder, PresenceIsReEvaluatedEveryMessage) {
  Decoder d({"{k: *}"});
  ASSERT_TRUE(d.feed(R"({"k": 1})"));
  EXPECT_EQ(d["k: *"], 1);
  ASSERT_TRUE(d.feed(R"({})"));
  EXPECT_EQ(d["k: *"], 0);  // unlike other tests, absence makes it false at once
  ASSERT_TRUE(d.feed(R"({"k": "text"})"));
  EXPECT_EQ(d["k: *"], 1);  // any type counts
  ASSERT_TRUE(d.feed(R"({"j": 1})"));
  EXPECT_EQ(d["k: *"], 0);
  ASSERT_TRUE(d.feed(R"({"k": null})"));
  EXPECT_EQ(d["k: *"], 1);  // present, with a null value (as Reelay)
  ASSERT_TRUE(d.feed(R"({"k": {"x": [1, 2]}})"));
  EXPECT_EQ(d["k: *"], 1);
  ASSERT_TRUE(d.feed(R"({"k": [true]})"));
  EXPECT_EQ(d["k: *"], 1);
  EXPECT_TRUE(d.warnings.empty());
}

TEST(JsonDecoder, TruthyReadsBooleansNumbersAndNull) {
  Decoder d({"{p}"});
  ASSERT_TRUE(d.feed(R"({"p": true})"));
  EXPECT_EQ(d["p"], 1);
  ASSERT_TRUE(d.feed(R"({"p": null})"));
  EXPECT_EQ(d["p"], 0);  // null reads as false
  ASSERT_TRUE(d.feed(R"({"p": 2.5})"));
  EXPECT_EQ(d["p"], 1);  // non-zero number
  ASSERT_TRUE(d.feed(R"({"p": 0})"));
  EXPECT_EQ(d["p"], 0);
  ASSERT_TRUE(d.feed(R"({"p": -1})"));
  EXPECT_EQ(d["p"], 1);
  EXPECT_TRUE(d.warnings.empty());
}

// ---------------------------------------------------------------- comparisons

TEST(JsonDecoder, NumberComparisons) {
  Decoder d({"{x < 2}", "{x <= 2}", "{x > 2}", "{x >= 2}", "{x == 2}", "{x != 2}"});
  ASSERT_TRUE(d.feed(R"({"x": 1})"));
  EXPECT_EQ(d["x < 2"], 1);
  EXPECT_EQ(d["x <= 2"], 1);
  EXPECT_EQ(d["x > 2"], 0);
  EXPECT_EQ(d["x >= 2"], 0);
  EXPECT_EQ(d["x == 2"], 0);
  EXPECT_EQ(d["x != 2"], 1);
  ASSERT_TRUE(d.feed(R"({"x": 2.0})"));
  EXPECT_EQ(d["x < 2"], 0);
  EXPECT_EQ(d["x <= 2"], 1);
  EXPECT_EQ(d["x > 2"], 0);
  EXPECT_EQ(d["x >= 2"], 1);
  EXPECT_EQ(d["x == 2"], 1);  // 2.0 == 2
  EXPECT_EQ(d["x != 2"], 0);
  ASSERT_TRUE(d.feed(R"({"x": 2.5e0})"));
  EXPECT_EQ(d["x > 2"], 1);
  EXPECT_EQ(d["x == 2"], 0);
}

TEST(JsonDecoder, StringAndBooleanEquality) {
  Decoder d({"{mode: sport}", "{mode != \"eco\"}", "{p: false}", "{q: true}"});
  ASSERT_TRUE(d.feed(R"({"mode": "sport", "p": false, "q": true})"));
  EXPECT_EQ(d["mode == \"sport\""], 1);
  EXPECT_EQ(d["mode != \"eco\""], 1);
  EXPECT_EQ(d["p == false"], 1);
  EXPECT_EQ(d["q == true"], 1);
  ASSERT_TRUE(d.feed(R"({"mode": "eco", "p": true, "q": false})"));
  EXPECT_EQ(d["mode == \"sport\""], 0);
  EXPECT_EQ(d["mode != \"eco\""], 0);
  EXPECT_EQ(d["p == false"], 0);
  EXPECT_EQ(d["q == true"], 0);
  ASSERT_TRUE(d.feed(R"({"mode": "Sport"})"));  // case matters
  EXPECT_EQ(d["mode == \"sport\""], 0);
  EXPECT_EQ(d["mode != \"eco\""], 1);
}

TEST(JsonDecoder, WrongTypeKeepsValueWithWarning) {
  Decoder d({"{x > 2}"});
  ASSERT_TRUE(d.feed(R"({"x": 5})"));
  EXPECT_EQ(d["x > 2"], 1);
  ASSERT_TRUE(d.feed(R"({"x": "abc"})"));  // accepted, not rejected
  EXPECT_EQ(d["x > 2"], 1);                // kept
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_TRUE(contains(d.warnings[0], "field \"x\" is a string")) << d.warnings[0];
  EXPECT_TRUE(contains(d.warnings[0], "{x > 2} needs a number")) << d.warnings[0];
  EXPECT_TRUE(contains(d.warnings[0], "keeps its previous value")) << d.warnings[0];
  ASSERT_TRUE(d.feed(R"({"x": [3]})"));
  EXPECT_EQ(d["x > 2"], 1);
  ASSERT_EQ(d.warnings.size(), 1u);
  EXPECT_TRUE(contains(d.warnings[0], "is an array")) << d.warnings[0];
  ASSERT_TRUE(d.feed(R"({"x": 1})"));
  EXPECT_EQ(d["x > 2"], 0);
  EXPECT_TRUE(d.warnings.empty());
}

// Reelay 25's rule, measured (tests/python/test_reelay_types.py): a Boolean
// counts 1 or 0 where a number is tested, and a Boolean test reads a number
// as true unless 0 and null as false, so a 0/1 flag sent as a number (a ROS 2
// uint8) reads as one sent as a Boolean.
TEST(JsonDecoder, BooleansAndNumbersReadEachOtherAsReelayDoes) {
  Decoder d({"{p: true}", "{p: false}", "{p}", "{p > 0}", "{p == 1}", "{p < 0.5}", "{p != 0}"});
  struct Row { const char* value; int t, f, truthy, gt0, eq1, lt_half, ne0; };
  const Row rows[] = {
      {"0", 0, 1, 0, 0, 0, 1, 0},     {"1", 1, 0, 1, 1, 1, 0, 1},      {"2", 1, 0, 1, 1, 0, 0, 1},
      {"-1", 1, 0, 1, 0, 0, 1, 1},    {"0.5", 1, 0, 1, 1, 0, 0, 1},    {"true", 1, 0, 1, 1, 1, 0, 1},
      {"false", 0, 1, 0, 0, 0, 1, 0}, {"1", 1, 0, 1, 1, 1, 0, 1},      {"0.0", 0, 1, 0, 0, 0, 1, 0},
  };
  for (const Row& r : rows) {
    ASSERT_TRUE(d.feed(std::string(R"({"p": )") + r.value + "}"));
    EXPECT_TRUE(d.warnings.empty()) << r.value << ": " << d.warnings[0];
    EXPECT_EQ(d["p == true"], r.t) << r.value;
    EXPECT_EQ(d["p == false"], r.f) << r.value;
    EXPECT_EQ(d["p"], r.truthy) << r.value;
    EXPECT_EQ(d["p > 0"], r.gt0) << r.value;
    EXPECT_EQ(d["p == 1"], r.eq1) << r.value;
    EXPECT_EQ(d["p < 0.5"], r.lt_half) << r.value;
    EXPECT_EQ(d["p != 0"], r.ne0) << r.value;
  }
  ASSERT_TRUE(d.feed(R"({"p": null})"));  // Boolean tests: false; comparisons: no value (kept)
  EXPECT_EQ(d["p == true"], 0);
  EXPECT_EQ(d["p == false"], 1);
  EXPECT_EQ(d["p"], 0);
  EXPECT_EQ(d["p > 0"], 0);  // kept from 0.0
  EXPECT_TRUE(d.warnings.empty());
}

TEST(JsonDecoder, WrongTypeForStringBooleanAndTruthyTests) {
  Decoder d({"{mode: sport}", "{p: false}", "{t}"});
  ASSERT_TRUE(d.feed(R"({"mode": "sport", "p": false, "t": true})"));
  ASSERT_TRUE(d.feed(R"({"mode": 3, "p": "no", "t": "yes"})"));
  EXPECT_EQ(d["mode == \"sport\""], 1);
  EXPECT_EQ(d["p == false"], 1);
  EXPECT_EQ(d["t"], 1);
  ASSERT_EQ(d.warnings.size(), 3u);
  EXPECT_TRUE(contains(d.warnings[0], "field \"mode\" is a number")) << d.warnings[0];
  EXPECT_TRUE(contains(d.warnings[0], "needs a string")) << d.warnings[0];
  EXPECT_TRUE(contains(d.warnings[1], "field \"p\" is a string")) << d.warnings[1];
  EXPECT_TRUE(contains(d.warnings[1], "needs a Boolean or number")) << d.warnings[1];
  EXPECT_TRUE(contains(d.warnings[2], "field \"t\" is a string")) << d.warnings[2];
  EXPECT_TRUE(contains(d.warnings[2], "needs a Boolean or number")) << d.warnings[2];
}

TEST(JsonDecoder, NullForAComparisonIsLikeAMissingField) {
  Decoder d({"{x > 2}"});
  ASSERT_TRUE(d.feed(R"({"x": 5})"));
  ASSERT_TRUE(d.feed(R"({"x": null})"));
  EXPECT_EQ(d["x > 2"], 1);  // kept
  EXPECT_TRUE(d.warnings.empty());
}

TEST(JsonDecoder, OneFieldManyTests) {
  // One field read once, five tests of two kinds on it.
  Decoder d({"{v}", "{v > 0.5}", "{v: *}", "{v == 0}", "{v: true}"});
  ASSERT_TRUE(d.feed(R"({"v": 1})"));
  EXPECT_EQ(d["v"], 1);
  EXPECT_EQ(d["v > 0.5"], 1);
  EXPECT_EQ(d["v: *"], 1);
  EXPECT_EQ(d["v == 0"], 0);
  EXPECT_EQ(d["v == true"], 1);  // a number other than 0 reads true (Reelay's rule)
  EXPECT_TRUE(d.warnings.empty());
  ASSERT_TRUE(d.feed(R"({"v": false})"));
  EXPECT_EQ(d["v"], 0);
  EXPECT_EQ(d["v > 0.5"], 0);  // false counts 0
  EXPECT_EQ(d["v: *"], 1);
  EXPECT_EQ(d["v == 0"], 1);
  EXPECT_EQ(d["v == true"], 0);
  EXPECT_TRUE(d.warnings.empty());
}

TEST(JsonDecoder, PresenceAndComparisonOnOneField) {
  Decoder d({"{x: *}", "{x > 2}"});
  ASSERT_TRUE(d.feed(R"({"x": 3})"));
  EXPECT_EQ(d["x: *"], 1);
  EXPECT_EQ(d["x > 2"], 1);
  ASSERT_TRUE(d.feed(R"({"x": "high"})"));
  EXPECT_EQ(d["x: *"], 1);   // present
  EXPECT_EQ(d["x > 2"], 1);  // wrong type: kept
  EXPECT_EQ(d.warnings.size(), 1u);
  ASSERT_TRUE(d.feed(R"({})"));
  EXPECT_EQ(d["x: *"], 0);
  EXPECT_EQ(d["x > 2"], 1);  // absent: kept
  ASSERT_TRUE(d.feed(R"({"x": 1})"));
  EXPECT_EQ(d["x: *"], 1);
  EXPECT_EQ(d["x > 2"], 0);
}

TEST(JsonDecoder, TruthyAndPresenceOnOneField) {
  Decoder d({"{p}", "{p: *}"});
  ASSERT_TRUE(d.feed(R"({"p": 7})"));
  EXPECT_EQ(d["p"], 1);
  EXPECT_EQ(d["p: *"], 1);
  ASSERT_TRUE(d.feed(R"({"p": false})"));
  EXPECT_EQ(d["p"], 0);
  EXPECT_EQ(d["p: *"], 1);
  ASSERT_TRUE(d.feed(R"({"q": true})"));
  EXPECT_EQ(d["p"], 0);
  EXPECT_EQ(d["p: *"], 0);
}

TEST(JsonDecoder, FieldOrderDoesNotMatter) {
  Decoder d({"{a > 0}", "{b > 0}", "{c}"});
  ASSERT_TRUE(d.feed(R"({"a": 1, "b": 1, "c": true})"));
  EXPECT_EQ(d["a > 0"], 1);
  EXPECT_EQ(d["b > 0"], 1);
  EXPECT_EQ(d["c"], 1);
  ASSERT_TRUE(d.feed(R"({"c": false, "b": 0, "zz": 1, "a": 0})"));
  EXPECT_EQ(d["a > 0"], 0);
  EXPECT_EQ(d["b > 0"], 0);
  EXPECT_EQ(d["c"], 0);
  ASSERT_TRUE(d.feed(R"({"x": 1, "a": 3})"));
  EXPECT_EQ(d["a > 0"], 1);
  EXPECT_EQ(d["b > 0"], 0);
  ASSERT_TRUE(d.feed(R"({"b": 2, "a": 0, "c": true})"));
  EXPECT_EQ(d["a > 0"], 0);
  EXPECT_EQ(d["b > 0"], 1);
  EXPECT_EQ(d["c"], 1);
  ASSERT_TRUE(d.feed(R"({"aa": 1, "b": 0, "a ": 5})"));  // keys that merely start with a test's key
  EXPECT_EQ(d["a > 0"], 0);
  EXPECT_EQ(d["b > 0"], 0);
}

TEST(JsonDecoder, EscapedKeys) {
  Decoder d({"{\"q\\\"uote\"}", "{\"sp ace\" > 1}"});
  ASSERT_TRUE(d.feed(R"({"q\"uote": true, "sp ace": 2})"));
  EXPECT_EQ(d["\"q\\\"uote\""], 1);
  EXPECT_EQ(d["\"sp ace\" > 1"], 1);
}

TEST(JsonDecoder, KeyWrittenWithUnicodeEscapeMatches) {
  // Regression: {"\u0070": true} has the key "p" in JSON; the raw-key fast
  // path once compared raw bytes only and ignored the field. Keys written
  // with escapes are compared unescaped.
  Decoder d({"{p}"});
  ASSERT_TRUE(d.feed(R"({"\u0070": true})"));
  EXPECT_EQ(d["p"], 1);
}

TEST(JsonDecoder, ManyFieldsAndTheTestedOneLate) {
  // 80 untested fields before the tested one, twice, then moved to the front.
  std::string filler;
  for (int i = 0; i < 80; ++i) filler += "\"f" + std::to_string(i) + "\": " + std::to_string(i) + ", ";
  Decoder d({"{late > 1}"});
  ASSERT_TRUE(d.feed("{" + filler + "\"late\": 2}"));
  EXPECT_EQ(d["late > 1"], 1);
  ASSERT_TRUE(d.feed("{" + filler + "\"late\": 0}"));
  EXPECT_EQ(d["late > 1"], 0);
  ASSERT_TRUE(d.feed("{\"late\": 5, " + filler + "\"x\": 1}"));
  EXPECT_EQ(d["late > 1"], 1);
}

TEST(JsonDecoder, EmptyKeyAfterManyFields) {
  // Regression: the per-position key cache was once resized before its
  // "position > 64" guard, so positions past 64 held a default entry {key "",
  // no target} and a field with the empty key "" there was skipped.
  std::string filler;
  for (int i = 0; i < 70; ++i) filler += "\"f" + std::to_string(i) + "\": 0, ";
  Decoder d({"{\"\"}"});
  ASSERT_TRUE(d.feed("{" + filler + "\"\": true}"));
  EXPECT_EQ(d["\"\""], 1);
  ASSERT_TRUE(d.feed("{" + filler + "\"\": false}"));
  EXPECT_EQ(d["\"\""], 0);
}

// ---------------------------------------------------------------- nested

TEST(JsonDecoder, NestedFields) {
  Decoder d({"{a.b > 1}", "{a.c.d}"});
  ASSERT_TRUE(d.feed(R"({"a": {"b": 2, "c": {"d": true}}})"));
  EXPECT_EQ(d["a.b > 1"], 1);
  EXPECT_EQ(d["a.c.d"], 1);
  ASSERT_TRUE(d.feed(R"({"a": {"b": 0}})"));
  EXPECT_EQ(d["a.b > 1"], 0);
  EXPECT_EQ(d["a.c.d"], 1);  // a.c absent: kept
  ASSERT_TRUE(d.feed(R"({"b": 5, "d": false, "a": {"x": 9}})"));
  EXPECT_EQ(d["a.b > 1"], 0);  // top-level b is a different field
  EXPECT_EQ(d["a.c.d"], 1);
  ASSERT_TRUE(d.feed(R"({"a": {"c": {"d": false}, "b": 7}})"));
  EXPECT_EQ(d["a.b > 1"], 1);
  EXPECT_EQ(d["a.c.d"], 0);
}

TEST(JsonDecoder, NestedPresence) {
  Decoder d({"{a.b: *}"});
  ASSERT_TRUE(d.feed(R"({"a": {"b": null}})"));
  EXPECT_EQ(d["a.b: *"], 1);
  ASSERT_TRUE(d.feed(R"({"a": {}})"));
  EXPECT_EQ(d["a.b: *"], 0);
  ASSERT_TRUE(d.feed(R"({"a": {"b": [1]}})"));
  EXPECT_EQ(d["a.b: *"], 1);
  ASSERT_TRUE(d.feed(R"({"a": 3})"));
  EXPECT_EQ(d["a.b: *"], 0);  // a is not an object: no a.b
  ASSERT_TRUE(d.feed(R"({"b": 1})"));
  EXPECT_EQ(d["a.b: *"], 0);
}

TEST(JsonDecoder, QuotedDottedKeyIsTopLevel) {
  Decoder d({"{\"a.b\"}", "{a.b}"});
  ASSERT_TRUE(d.feed(R"({"a.b": true})"));
  EXPECT_EQ(d["\"a.b\""], 1);
  EXPECT_EQ(d["a.b"], 0);
  ASSERT_TRUE(d.feed(R"({"a": {"b": true}, "a.b": false})"));
  EXPECT_EQ(d["\"a.b\""], 0);
  EXPECT_EQ(d["a.b"], 1);
}

// ---------------------------------------------------------------- strict

TEST(JsonDecoderStrict, MissingFieldRejected) {
  DecoderOptions o;
  o.strict = true;
  Decoder d({"{p}", "{speed > 3}"}, o);
  ASSERT_TRUE(d.feed(R"({"p": true, "speed": 5})"));
  EXPECT_FALSE(d.feed(R"({"p": false})"));
  EXPECT_TRUE(contains(d.error, "missing field \"speed\"")) << d.error;
  EXPECT_TRUE(contains(d.error, "strict")) << d.error;
  // The rejected message changed nothing, not even p.
  EXPECT_EQ(d["p"], 1);
  EXPECT_EQ(d["speed > 3"], 1);
}

TEST(JsonDecoderStrict, WrongTypeRejectedNamingTheField) {
  DecoderOptions o;
  o.strict = true;
  Decoder d({"{p}", "{speed > 3}"}, o);
  ASSERT_TRUE(d.feed(R"({"p": true, "speed": 5})"));
  EXPECT_FALSE(d.feed(R"({"p": false, "speed": "fast"})"));
  EXPECT_TRUE(contains(d.error, "field \"speed\" is a string")) << d.error;
  EXPECT_EQ(d["p"], 1);
  EXPECT_EQ(d["speed > 3"], 1);
  EXPECT_FALSE(d.feed(R"({"p": "yes", "speed": 1})"));
  EXPECT_TRUE(contains(d.error, "field \"p\"")) << d.error;
  EXPECT_FALSE(d.feed(R"({"p": true, "speed": null})"));
  EXPECT_TRUE(contains(d.error, "field \"speed\" is null")) << d.error;
  // null is a valid value for {p}: false.
  ASSERT_TRUE(d.feed(R"({"p": null, "speed": 1})"));
  EXPECT_EQ(d["p"], 0);
  EXPECT_EQ(d["speed > 3"], 0);
}

TEST(JsonDecoderStrict, PresenceTestsDoNotRequireTheField) {
  DecoderOptions o;
  o.strict = true;
  Decoder d({"{k: *}"}, o);
  ASSERT_TRUE(d.feed(R"({})")) << d.error;
  EXPECT_EQ(d["k: *"], 0);
  ASSERT_TRUE(d.feed(R"({"k": 0})")) << d.error;
  EXPECT_EQ(d["k: *"], 1);
}

TEST(JsonDecoderStrict, NestedMissingField) {
  DecoderOptions o;
  o.strict = true;
  Decoder d({"{a.b > 1}"}, o);
  EXPECT_FALSE(d.feed(R"({"a": {"c": 1}})"));
  EXPECT_TRUE(contains(d.error, "missing field \"a.b\"")) << d.error;
  EXPECT_FALSE(d.feed(R"({"a": 5})"));
  EXPECT_TRUE(contains(d.error, "missing field \"a.b\"")) << d.error;
  EXPECT_FALSE(d.feed(R"({"x": 1})"));
  EXPECT_TRUE(contains(d.error, "missing field \"a")) << d.error;
  ASSERT_TRUE(d.feed(R"({"a": {"b": 2}})")) << d.error;
  EXPECT_EQ(d["a.b > 1"], 1);
}

// ---------------------------------------------------------------- time

TEST(JsonDecoderTime, RequiredInDense) {
  DecoderOptions o;
  o.need_time = true;
  Decoder d({"{p}"}, o, engine::TimeModel::Dense);
  EXPECT_FALSE(d.feed(R"({"p": true})"));
  EXPECT_TRUE(contains(d.error, "missing time field \"time\"")) << d.error;
  EXPECT_EQ(d["p"], 0);  // rejected: not committed
  EXPECT_FALSE(d.feed(R"({"time": "noon", "p": true})"));
  EXPECT_TRUE(contains(d.error, "time field \"time\" must be a number of seconds or a Time {sec, nanosec}, not a string"))
      << d.error;
  EXPECT_FALSE(d.feed(R"({"time": {"nanosec": 1}})"));
  EXPECT_TRUE(contains(d.error, "is an object without \"sec\"")) << d.error;
  EXPECT_FALSE(d.feed(R"({"time": {"sec": "1"}})"));
  EXPECT_TRUE(contains(d.error, "time field \"time.sec\" must be a number, not a string")) << d.error;
  ASSERT_TRUE(d.feed(R"({"p": true, "time": 1.5})")) << d.error;
  EXPECT_EQ(d.time(), 1.5);
  EXPECT_EQ(d["p"], 1);
  ASSERT_TRUE(d.feed(R"({"time": 4})")) << d.error;
  EXPECT_EQ(d.time(), 4);
  EXPECT_EQ(d["p"], 1);
}

// A stamp as ROS 2 JSON writes it (builtin_interfaces/Time, also ROS 1's secs/nsecs), at a path:
// the same double the typed path computes, (sec * 1e9 + nanosec) / 1e9.
TEST(JsonDecoderTime, TimeObjectAtAPath) {
  DecoderOptions o;
  o.need_time = true;
  o.time_field = "header.stamp";
  Decoder d({"{header.stamp.sec > 5}", "{x}"}, o, engine::TimeModel::Dense);
  ASSERT_TRUE(d.feed(R"({"header": {"frame_id": "a", "stamp": {"sec": 1700000000, "nanosec": 123}}, "x": true})"))
      << d.error;
  EXPECT_EQ(d.time(), (1700000000 * 1e9 + 123) / 1e9);
  EXPECT_EQ(d["header.stamp.sec > 5"], 1);  // the stamp's fields are still tested
  EXPECT_EQ(d["x"], 1);
  ASSERT_TRUE(d.feed(R"({"header": {"stamp": {"nsecs": 500000000, "secs": 2}}})")) << d.error;
  EXPECT_EQ(d.time(), 2.5);
  EXPECT_EQ(d["header.stamp.sec > 5"], 1);  // no "sec" in this one: the field keeps its last value
  ASSERT_TRUE(d.feed(R"({"header": {"stamp": 7.25}})")) << d.error;
  EXPECT_EQ(d.time(), 7.25);
  EXPECT_FALSE(d.feed(R"({"header": {"frame_id": "a"}})"));
  EXPECT_TRUE(contains(d.error, "missing time field \"header.stamp\"")) << d.error;
}

TEST(JsonDecoderTime, CustomTimeFieldAndNotRequiredInDiscrete) {
  DecoderOptions o;
  o.need_time = true;
  o.time_field = "ts";
  Decoder d({"{p}"}, o, engine::TimeModel::Dense);
  EXPECT_FALSE(d.feed(R"({"time": 1, "p": true})"));
  EXPECT_TRUE(contains(d.error, "missing time field \"ts\"")) << d.error;
  ASSERT_TRUE(d.feed(R"({"ts": 2, "p": true})"));
  EXPECT_EQ(d.time(), 2);
  Decoder discrete({"{p}"});
  EXPECT_TRUE(discrete.feed(R"({"p": true})"));
}

TEST(JsonDecoderTime, TimeFieldCanAlsoBeTested) {
  DecoderOptions o;
  o.need_time = true;
  Decoder d({"{time > 5}"}, o, engine::TimeModel::Dense);
  ASSERT_TRUE(d.feed(R"({"time": 7})")) << d.error;
  EXPECT_EQ(d.time(), 7);
  EXPECT_EQ(d["time > 5"], 1);
  ASSERT_TRUE(d.feed(R"({"time": 3})")) << d.error;
  EXPECT_EQ(d.time(), 3);
  EXPECT_EQ(d["time > 5"], 0);
}

}  // namespace
}  // namespace rvc::io
