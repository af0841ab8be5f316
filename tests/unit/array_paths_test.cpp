// Array elements in field paths: {ranges[0] < 0.5}, {points[1].x > 0}.
// Oracles: hand-computed verdicts on a JSON trace; the JSON path for typed
// (CDR) samples of the same values; spec errors at the atom's column.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "io/cdr_codec.hpp"
#include "msg/type_registry.hpp"
#include "runtime/pipeline.hpp"
#include "spec/parser.hpp"
#include "spec/spec_error.hpp"

namespace rvc {
namespace {

const spec::FieldTest& only_test(const spec::NodePtr& n) { return n->test; }

TEST(ArrayPaths, ParseAndPrint) {
  auto a = spec::parse("{ranges[0] < 0.5}");
  EXPECT_EQ(only_test(a).path, (std::vector<std::string>{"ranges", "[0]"}));
  EXPECT_EQ(only_test(a).key(), "ranges[0]");
  auto b = spec::parse("{points[12].x > 0}");
  EXPECT_EQ(only_test(b).path, (std::vector<std::string>{"points", "[12]", "x"}));
  EXPECT_EQ(spec::to_string(*b), "{points[12].x > 0}");
  auto c = spec::parse("{grid[2][03]: *}");  // leading zeros are the same index
  EXPECT_EQ(only_test(c).key(), "grid[2][3]");
  EXPECT_EQ(spec::to_string(*spec::parse(spec::to_string(*c))), spec::to_string(*c));  // prints parse back
}

TEST(ArrayPaths, BadIndexesPointAtTheirColumn) {
  auto column_of = [](const std::string& text) {
    try {
      spec::parse(text);
    } catch (const spec::SpecError& e) {
      return e.column();
    }
    return -1;
  };
  EXPECT_EQ(column_of("{ranges[x] < 1}"), 9);
  EXPECT_EQ(column_of("{ranges[1 < 1}"), 10);
  EXPECT_EQ(column_of("{\"[0]\" < 1}"), 2);  // a quoted key that would read as an index
  EXPECT_EQ(column_of("{r[1234567890]}"), 4);
}

std::vector<std::string> run(const std::vector<engine::PropertySpec>& props, const std::vector<std::string>& msgs,
                             const msg::MessageType* type = nullptr, bool strict = false,
                             runtime::PipelineStats* stats = nullptr) {
  runtime::PipelineOptions o;
  o.emit_all = true;
  o.type = type;
  o.strict = strict;
  o.max_reported = 0;
  std::vector<std::string> out;
  runtime::Pipeline p(props, o, [&](const engine::Verdict& v) {
    out.push_back(v.property + (v.value ? "T" : "F"));
  });
  uint64_t seq = 0;
  for (const auto& m : msgs) {
    if (!type) {
      p.feed(m, ++seq);
      continue;
    }
    std::string sample, error;
    EXPECT_TRUE(io::json_to_cdr(*type, m, sample, error)) << error;
    p.feed(sample, ++seq);
  }
  if (stats) *stats = p.stats();
  return out;
}

TEST(ArrayPaths, JsonHandComputed) {
  const std::vector<std::string> msgs = {
      R"({"ranges":[0.3,1.0,2.0],"pts":[{"x":1},{"x":-2}]})",
      R"({"ranges":[0.7],"pts":[{"x":-1}]})",   // no pts[1], no ranges[2]: they keep their values
      R"({"ranges":[0.2,0.1,5],"pts":[]})",
      R"({"ranges":{"[0]":0.1},"pts":[{"x":3},{"x":4}]})",  // an object is no array
  };
  const auto got = run({{"a", "{ranges[0] < 0.5}"}, {"b", "{pts[1].x > 0}"}, {"c", "{ranges[2]: *}"}}, msgs);
  EXPECT_EQ(got, (std::vector<std::string>{"aT", "bF", "cT", "aF", "bF", "cF", "aT", "bF", "cT", "aT", "bT", "cF"}));
  // Strict mode: a missing element is a missing field, named with its index.
  runtime::PipelineStats stats;
  run({{"b", "{pts[1].x > 0}"}}, msgs, nullptr, true, &stats);
  EXPECT_EQ(stats.rejected, 2u);  // messages 2 and 3
}

TEST(ArrayPaths, TypedEqualsJson) {
  msg::TypeRegistry reg;
  reg.add_definition("t_msgs/msg/Scan",
                     "float32[] ranges\ngeometry_msgs/Point[] pts\nint16[3] fixed\nstring[<=2] names\nbool[] on\n",
                     "test");
  const auto& type = reg.resolve("t_msgs/msg/Scan");
  std::mt19937 rng(5);
  auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<unsigned>(n)); };
  std::vector<std::string> msgs;
  for (int i = 0; i < 300; ++i) {
    std::string m = R"({"ranges":[)";
    for (int k = pick(4); k > 0; --k) m += std::to_string(pick(8)) + ".25" + (k > 1 ? "," : "");
    m += R"(],"pts":[)";
    for (int k = pick(3); k > 0; --k)
      m += R"({"x":)" + std::to_string(pick(5) - 2) + R"(,"y":0.5,"z":0})" + (k > 1 ? "," : "");
    m += R"(],"fixed":[)" + std::to_string(pick(9)) + ",1," + std::to_string(pick(3)) + R"(],"names":[)";
    for (int k = pick(3); k > 0; --k) m += std::string(pick(2) ? "\"a\"" : "\"b\"") + (k > 1 ? "," : "");
    m += R"(],"on":[)";
    for (int k = pick(3); k > 0; --k) m += std::string(pick(2) ? "true" : "false") + (k > 1 ? "," : "");
    msgs.push_back(m + "]}");
  }
  const std::vector<engine::PropertySpec> props = {
      {"r", "{ranges[0] < 3} && {ranges[2] >= 4} || {ranges[5]: *}"},
      {"p", "once[0:2]{pts[1].x > 0} && {pts[0]: *}"},
      {"f", "{fixed[0] == 4} || {fixed[2] != 1}"},
      {"n", "{names[1] == \"a\"} -> pre {names[0] == \"b\"}"},
      {"o", "{on[0]} || {on[1] == false} || {names[0] > 2}"},  // the last is of the wrong type: warnings
  };
  runtime::PipelineStats from_json, typed;
  const auto want = run(props, msgs, nullptr, false, &from_json);
  const auto got = run(props, msgs, &type, false, &typed);
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < got.size(); ++i)
    ASSERT_EQ(got[i], want[i]) << "message " << i / props.size() << ": " << msgs[i / props.size()];
  EXPECT_EQ(typed.warnings, from_json.warnings);
  EXPECT_GT(from_json.warnings, 0u);
  EXPECT_EQ(typed.rejected + from_json.rejected, 0u);
}

TEST(ArrayPaths, TypedSpecErrors) {
  msg::TypeRegistry reg;
  reg.add_definition("t_msgs/msg/Scan2", "float32[] ranges\nint16[3] fixed\nfloat64 x\n", "test");
  const auto& type = reg.resolve("t_msgs/msg/Scan2");
  auto error_of = [&](const std::string& spec) -> std::string {
    runtime::PipelineOptions o;
    o.type = &type;
    try {
      runtime::Pipeline p({{"p", spec}}, o, [](const engine::Verdict&) {});
    } catch (const spec::SpecError& e) {
      return e.message();
    }
    return "";
  };
  EXPECT_NE(error_of("{fixed[3] > 1}").find("index 3 is past the end of 'fixed' (int16[3])"), std::string::npos)
      << error_of("{fixed[3] > 1}");
  EXPECT_NE(error_of("{x[0] > 1}").find("'x' is float64, not an array"), std::string::npos) << error_of("{x[0] > 1}");
  EXPECT_NE(error_of("{ranges[0].y > 1}").find("'ranges[0]' is float32, not a message"), std::string::npos)
      << error_of("{ranges[0].y > 1}");
  EXPECT_EQ(error_of("{ranges[100] > 1}"), "");  // a sequence may be that long
}

}  // namespace
}  // namespace rvc
