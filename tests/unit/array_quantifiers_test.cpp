// Array quantifiers in atoms (issue 29): {all(ranges[*] > 0.2)},
// {any(objects[*].distance < 2)}, {count(objects[*].distance < 2) >= 3}.
// Oracles: hand-computed verdicts and margins on JSON traces; spec errors at
// the atom's column; the canonical text round-trips (atoms are shared by it).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "io/cdr_codec.hpp"
#include "msg/type_registry.hpp"
#include "runtime/pipeline.hpp"
#include "spec/parser.hpp"
#include "spec/spec_error.hpp"
#include "spec_soup.hpp"

namespace rvc {
namespace {

int column_of(const std::string& text) {
  try {
    spec::parse(text);
  } catch (const spec::SpecError& e) {
    return e.column();
  }
  return -1;
}

TEST(ArrayQuantifiers, ParseAndPrint) {
  auto a = spec::parse("{all( ranges[*]>0.2 )}");
  EXPECT_EQ(a->test.quant.kind, spec::ArrayQuant::Kind::All);
  EXPECT_EQ(a->test.path, (std::vector<std::string>{"ranges", "[*]"}));
  EXPECT_EQ(a->test.to_string(), "all(ranges[*] > 0.2)");
  auto c = spec::parse("{count(objects[*].distance < 2.0) >= 3}");
  EXPECT_EQ(c->test.to_string(), "count(objects[*].distance < 2) >= 3");
  EXPECT_EQ(spec::parse("{any(flags[*])}")->test.to_string(), "any(flags[*])");
  EXPECT_EQ(spec::parse("{all(s[*].name == \"a\")}")->test.to_string(), "all(s[*].name == \"a\")");
  for (const char* text : {"{all(ranges[*] > 0.2)}", "{count(o[*].d < 2) >= 3} && {any(p[*].q[2])}"}) {
    const std::string printed = spec::to_string(*spec::parse(text));
    EXPECT_EQ(spec::to_string(*spec::parse(printed)), printed);  // prints parse back
  }
  // count(x) without '[*]' stays the aggregate over the whole past.
  EXPECT_EQ(spec::parse("{count(x) >= 3}")->test.quant.kind, spec::ArrayQuant::Kind::None);
  EXPECT_TRUE(spec::parse("{count(x) >= 3}")->test.is_timed());
}

TEST(ArrayQuantifiers, ErrorsPointAtTheirColumn) {
  EXPECT_EQ(column_of("{ranges[*] > 0.2}"), 8);        // '[*]' outside a quantifier
  EXPECT_EQ(column_of("{all(ranges > 0.2)}"), 6);      // no '[*]'
  EXPECT_EQ(column_of("{all(a[*].b[*] > 1)}"), 12);    // two
  EXPECT_EQ(column_of("{count(a[*] > 1)}"), 17);       // the count must be compared
  EXPECT_EQ(column_of("{all(a[*] > b)}"), 6);          // an expression, not a test against a value
  EXPECT_EQ(column_of("{all(a[*]: *)}"), 6);           // presence
  EXPECT_EQ(column_of("{all(any(a[*]))}"), 6);         // nested
  EXPECT_EQ(column_of("{all(a[*] > 1}"), 14);          // unclosed
}

struct Out {
  std::vector<std::string> verdicts;
  std::vector<double> margins;
  runtime::PipelineStats stats;
};

// Feeds `msgs` (JSON) to one property; with `type`, each message goes in as
// its CDR sample of that type instead (the typed decoder's path).
Out run(const std::string& spec, const std::vector<std::string>& msgs, bool strict = false, bool robust = false,
        const msg::MessageType* type = nullptr) {
  runtime::PipelineOptions o;
  o.emit_all = true;
  o.strict = strict;
  o.robustness = robust;
  o.type = type;
  o.max_reported = 0;
  Out out;
  runtime::Pipeline p({{"p", spec}}, o, [&](const engine::Verdict& v) {
    out.verdicts.push_back(v.value ? "T" : "F");
    out.margins.push_back(v.robustness);
  });
  uint64_t seq = 0;
  std::string sample, error;
  for (const auto& m : msgs) {
    if (type) {
      EXPECT_TRUE(io::json_to_cdr(*type, m, sample, error)) << error;
    }
    p.feed(type ? sample : m, ++seq);
  }
  out.stats = p.stats();
  return out;
}

const std::vector<std::string> kTrace = {
    R"({"ranges":[0.5,0.3],"objects":[{"distance":1},{"distance":3}]})",
    R"({"ranges":[0.1,0.3],"objects":[]})",
    R"({"ranges":[],"objects":[{"distance":1},{"distance":1.5},{"distance":0.5}]})",
    R"({"ranges":[0.25,0.9,0.4],"objects":[{"distance":2.5},{"distance":1.75}]})",
};

TEST(ArrayQuantifiers, JsonHandComputed) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  auto all = run("{all(ranges[*] > 0.2)}", kTrace, false, true);
  EXPECT_EQ(all.verdicts, (std::vector<std::string>{"T", "F", "T", "T"}));  // the empty array: true
  ASSERT_EQ(all.margins.size(), 4u);
  EXPECT_NEAR(all.margins[0], 0.1, 1e-12);  // min(0.5 - 0.2, 0.3 - 0.2)
  EXPECT_NEAR(all.margins[1], -0.1, 1e-12);
  EXPECT_EQ(all.margins[2], inf);
  EXPECT_NEAR(all.margins[3], 0.05, 1e-12);
  auto any = run("{any(objects[*].distance < 2.0)}", kTrace, false, true);
  EXPECT_EQ(any.verdicts, (std::vector<std::string>{"T", "F", "T", "T"}));
  EXPECT_EQ(any.margins, (std::vector<double>{1, -inf, 1.5, 0.25}));  // max(2 - d); none: -inf
  auto count = run("{count(objects[*].distance < 2.0) >= 2}", kTrace, false, true);
  EXPECT_EQ(count.verdicts, (std::vector<std::string>{"F", "F", "T", "F"}));  // counts 1, 0, 3, 1
  EXPECT_EQ(count.margins, (std::vector<double>{-1, -2, 1, -1}));
  // Boolean runs (no margins: the typed fast paths) agree.
  EXPECT_EQ(run("{all(ranges[*] > 0.2)}", kTrace).verdicts, all.verdicts);
  EXPECT_EQ(run("{count(objects[*].distance < 2.0) >= 2}", kTrace).verdicts, count.verdicts);
  // Temporal operators over a quantified atom, and a plain test on the same message.
  EXPECT_EQ(run("once[0:1]{count(objects[*].distance < 2) == 0} && {ranges[0]: *}", kTrace).verdicts,
            (std::vector<std::string>{"F", "T", "F", "F"}));
}

TEST(ArrayQuantifiers, ElementsWithoutAValue) {
  const std::vector<std::string> msgs = {
      R"({"objects":[{"distance":1}]})",
      R"({"objects":[{"distance":3},{"x":1}]})",        // element 1 lacks the field: keeps T
      R"({"objects":[{"distance":"far"}]})",            // a string: keeps T
      R"({"objects":5})",                               // no array: keeps T
      R"({"other":1})",                                 // missing: keeps T
      R"({"objects":[{"distance":3}]})",
  };
  auto lenient = run("{any(objects[*].distance < 2)}", msgs);
  EXPECT_EQ(lenient.verdicts, (std::vector<std::string>{"T", "T", "T", "T", "T", "F"}));
  EXPECT_EQ(lenient.stats.warnings, 3u);
  auto strict = run("{any(objects[*].distance < 2)}", msgs, true);
  EXPECT_EQ(strict.stats.rejected, 4u);
  EXPECT_EQ(strict.verdicts, (std::vector<std::string>{"T", "F"}));
}

// Typed (CDR) samples of the same values give the JSON trace's verdicts,
// margins and warnings (the CDR decoder folds elements as the JSON one does).
TEST(ArrayQuantifiers, TypedEqualsJson) {
  msg::TypeRegistry reg;
  reg.add_definition("t_msgs/msg/Obj", "float64 distance\nstring name\n", "test");
  reg.add_definition("t_msgs/msg/Scan3", "float32[] ranges\nt_msgs/Obj[] objects\nbool[<=3] flags\n", "test");
  const auto& type = reg.resolve("t_msgs/msg/Scan3");
  const std::vector<std::string> msgs = {
      R"({"ranges":[0.5,0.25],"objects":[{"distance":1,"name":"a"},{"distance":3,"name":"b"}],"flags":[true]})",
      R"({"ranges":[0.125,0.25],"objects":[],"flags":[]})",
      R"({"ranges":[],"objects":[{"distance":1,"name":"b"},{"distance":1.5,"name":"b"},{"distance":0.5,"name":"c"}],"flags":[true,false]})",
      R"({"ranges":[0.25,0.875,0.375],"objects":[{"distance":2.5,"name":"a"}],"flags":[false]})",
  };
  for (const char* spec : {"{all(ranges[*] > 0.2)}", "{any(objects[*].distance < 2.0)}",
                           "{count(objects[*].distance < 2.0) >= 2}", "{all(flags[*])} || {any(objects[*].name == \"c\")}",
                           "{count(objects[*].name != \"b\") == 1} && once[0:2]{all(ranges[*] > 0.2)}",
                           "{any(objects[*].name > 1)}"}) {  // the last: of the wrong type (warnings)
    for (bool robust : {false, true}) {
      const Out json = run(spec, msgs, false, robust);
      const Out typed = run(spec, msgs, false, robust, &type);
      EXPECT_EQ(typed.verdicts, json.verdicts) << spec;
      EXPECT_EQ(typed.margins, json.margins) << spec;
      EXPECT_EQ(typed.stats.warnings, json.stats.warnings) << spec;
    }
  }
  EXPECT_EQ(run("{all(ranges[*] > 0.2)}", msgs).verdicts, (std::vector<std::string>{"T", "F", "T", "T"}));
}

TEST(ArrayQuantifiers, TypedSpecErrorsAtTheColumn) {
  msg::TypeRegistry reg;
  reg.add_definition("t_msgs/msg/Scan4", "float32[] ranges\nfloat64 x\n", "test");
  runtime::PipelineOptions o;
  o.type = &reg.resolve("t_msgs/msg/Scan4");
  try {
    runtime::Pipeline p({{"p", "{ranges[0] > 1} || {all(x[*] > 0.2)}"}}, o, [](const engine::Verdict&) {});
    FAIL() << "accepted";
  } catch (const spec::SpecError& e) {
    EXPECT_EQ(e.column(), 21);
    EXPECT_NE(e.message().find("'x' is float64, not an array"), std::string::npos) << e.message();
  }
}

// A grammar fuzz of the quantifier forms: whatever parses prints to a fixed
// point, and runs on a short trace (JSON, robustness too) without a crash.
TEST(ArrayQuantifiers, TokenSoupParsesToAFixedPointOrASpecError) {
  const char* tokens[] = {"{", "}", "all(", "any(", "count(", "a[*]", "o[*].d", "a[0]", "[*]", ")", "(", ",", "<",
                          ">=", "==", "!=", "2", "-1.5", "\"s\"", "true", "x", "and", "or", "not", "once[0:2]",
                          "{all(a[*] > 1)}", "{count(o[*].d < 2) >= 1}", "count[0:1](", "@age", ":", "*"};
  std::mt19937 rng(2930);
  int parsed = 0;
  for (int i = 0; i < 3000; ++i) {
    std::string s;
    if (i % 2 == 0) {  // from the grammar, cut at a random point half the time
      const char* quants[] = {"all(", "any(", "count("};
      const char* paths[] = {"a[*]", "o[*].d", "a[*][1]", "\"k y\"[*]"};
      const char* tests[] = {" > 1", " <= 2", " == \"s\"", "", ": true", " != -1.5"};
      const char* joins[] = {" and ", " or ", " -> ", " since "};
      for (int k = 1 + static_cast<int>(rng() % 3); k > 0; --k) {
        const int q = static_cast<int>(rng() % 3);
        s += std::string(rng() % 3 == 0 ? "once[0:2]" : "") + "{" + quants[q] + paths[rng() % 4] + tests[rng() % 6] +
             ")" + (q == 2 ? " >= 2" : "") + "}" + (k > 1 ? joins[rng() % 4] : "");
      }
      if (rng() % 2) s = s.substr(0, rng() % (s.size() + 1));
    } else {
      s = test::token_soup(rng, tokens, 10);
    }
    // Accepted specs run on a short trace (robustness every other time).
    parsed += test::accepted_round_trips_and_runs(
        s, i % 2 == 1,
        {R"({"a": [1, 3], "o": [{"d": 1}, {"d": "s"}], "x": 1})", R"({"a": 2, "o": []})",
         R"({"a": [], "o": [{"e": 1}, null]})", R"({"a": [true, null, {}], "o": [{"d": 0}]})"});
  }
  EXPECT_GT(parsed, 500);
}

}  // namespace
}  // namespace rvc
