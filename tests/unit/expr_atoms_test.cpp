// Arithmetic in atoms and rise/fall (issue 29), hand-computed: the parser's
// syntax, canonical text and error columns; values with missing fields, wrong
// types, NaN and division by zero; margins; two synchronized inputs. RTAMT
// checks random traces (tests/cli/test_expressions.py).
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "runtime/pipeline.hpp"
#include "runtime/synced_pipeline.hpp"
#include "spec/parser.hpp"
#include "spec/spec_error.hpp"
#include "spec_soup.hpp"

namespace rvc {
namespace {

using Verdicts = std::vector<std::pair<double, bool>>;

std::string canon(const std::string& text, bool dense = false) {
  spec::ParseOptions o;
  o.dense = dense;
  return spec::to_string(*spec::parse(text, o));
}

int error_column(const std::string& text, std::string* message = nullptr, bool dense = false) {
  spec::ParseOptions o;
  o.dense = dense;
  try {
    spec::parse(text, o);
  } catch (const spec::SpecError& e) {
    if (message) *message = e.message();
    return e.column();
  }
  return -1;
}

// ---- syntax ----

TEST(ExprParse, CanonicalTextRoundTrips) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"{abs(steer.angle - cmd.angle) < 0.05}", "{abs((steer.angle - cmd.angle)) < 0.05}"},
      {"{a + b * c >= 2}", "{(a + (b * c)) >= 2}"},
      {"{(a + b) * c > 1}", "{((a + b) * c) > 1}"},
      {"{a - b - c > 0}", "{((a - b) - c) > 0}"},
      {"{a / b / 2 <= 1}", "{((a / b) / 2) <= 1}"},
      {"{-x > 3}", "{(-x) > 3}"},
      {"{x > -3}", "{x > -3}"},                    // a literal, as before
      {"{(x) < 3}", "{x < 3}"},                    // a field and a number: the plain test
      {"{3 < x}", "{3 < x}"},
      {"{a < b}", "{a < b}"},                      // field against field
      {"{a == (b)}", "{a == (b)}"},                // a field after ==, in parentheses
      {"{a == b}", "{a == \"b\"}"},                // a bare word after == stays a string
      {"{a.x == b.x}", "{a.x == (b.x)}"},          // a path with a dot is a field
      {"{min(a, b) > 0}", "{min(a, b) > 0}"},
      {"{max(a[0], -b) > 0}", "{max(a[0], (-b)) > 0}"},
      {"{max(x) > 0}", "{max(x) > 0}"},            // one argument: the aggregate over the past
      {"{x - 1 > 0, p}", "({(x - 1) > 0} and {p})"},
      {"{\"odd key\" * 2 > 1}", "{(\"odd key\" * 2) > 1}"},
      {"{abs(x) < 1e-3}", "{abs(x) < 0.001}"},
  };
  for (const auto& [in, want] : cases) {
    const std::string got = canon(in);
    EXPECT_EQ(got, want) << in;
    EXPECT_EQ(canon(got), got) << in;  // the canonical text parses to itself
  }
}

TEST(ExprParse, ErrorsNameTheColumn) {
  std::string m;
  EXPECT_EQ(error_column("{a + }", &m), 6);
  EXPECT_NE(m.find("expected a number, a field"), std::string::npos) << m;
  EXPECT_EQ(error_column("{abs(a, b) < 1}", &m), 7);
  EXPECT_NE(m.find("abs takes one argument"), std::string::npos) << m;
  EXPECT_EQ(error_column("{a + b}", &m), 7);
  EXPECT_NE(m.find("compare it"), std::string::npos) << m;
  EXPECT_EQ(error_column("{(a + b < 1}", &m), 9);
  EXPECT_NE(m.find("expected ')'"), std::string::npos) << m;
  EXPECT_EQ(error_column("{a + x.@age < 1}", &m), 8);  // at the timing atom
  EXPECT_NE(m.find("timing atom"), std::string::npos) << m;
  EXPECT_EQ(error_column("{a + avg[0:1](x) < 1}", &m), 6);
  EXPECT_NE(m.find("aggregate"), std::string::npos) << m;
  EXPECT_EQ(error_column("{a * # > 1}", &m), 6);
  EXPECT_EQ(error_column("{speed > \"fast\"}", &m), 10);
  EXPECT_NE(m.find("this is not a number"), std::string::npos) << m;
}

TEST(ExprParse, LongExpressionsAreRefusedNotOverflowed) {
  std::string big = "{x";
  for (int i = 0; i < 5000; ++i) big += " + x";
  big += " > 0}";
  std::string m;
  EXPECT_GT(error_column(big, &m), 0);
  EXPECT_NE(m.find("expression too long"), std::string::npos) << m;
  std::string deep = "{" + std::string(3000, '(') + "x" + std::string(3000, ')') + " > 0}";
  EXPECT_GT(error_column(deep, &m), 0);
}

// ---- values (one input) ----

Verdicts run(const std::string& spec, const std::vector<std::string>& lines, bool robust = false,
             std::vector<double>* margins = nullptr, std::string* err = nullptr, bool strict = false) {
  Verdicts out;
  runtime::PipelineOptions po;
  po.emit_all = true;
  po.robustness = robust;
  po.strict = strict;
  testing::internal::CaptureStderr();
  {
    runtime::Pipeline p({{"p", spec}}, po, [&](const engine::Verdict& v) {
      out.emplace_back(v.time, v.value);
      if (margins) margins->push_back(v.robustness);
    });
    uint64_t n = 0;
    for (const auto& l : lines) p.feed(l, ++n);
  }
  const std::string text = testing::internal::GetCapturedStderr();
  if (err) *err = text;
  return out;
}

std::vector<bool> values(const Verdicts& v) {
  std::vector<bool> out;
  for (const auto& [t, b] : v) out.push_back(b);
  return out;
}

TEST(ExprValues, ArithmeticAndFieldAgainstField) {
  const std::vector<std::string> trace = {R"({"a": 1, "b": 1.02})", R"({"a": 1, "b": 1.2})", R"({"a": 3, "b": 2})",
                                          R"({"a": -2, "b": 2})"};
  EXPECT_EQ(values(run("{abs(a - b) < 0.05}", trace)), (std::vector<bool>{true, false, false, false}));
  EXPECT_EQ(values(run("{a > b}", trace)), (std::vector<bool>{false, false, true, false}));
  EXPECT_EQ(values(run("{a * b == -4}", trace)), (std::vector<bool>{false, false, false, true}));
  EXPECT_EQ(values(run("{min(a, b) >= 1}", trace)), (std::vector<bool>{true, true, true, false}));
  EXPECT_EQ(values(run("{max(a, b) / 2 > 1}", trace)), (std::vector<bool>{false, false, true, false}));
  EXPECT_EQ(values(run("{a == (b)}", {R"({"a": 2, "b": 2})"})), (std::vector<bool>{true}));
}

TEST(ExprValues, MissingFieldsHoldAndUnseenFieldsMakeItFalse) {
  // b is missing at step 0 (never seen: false), step 2 keeps b = 5, step 3 has b a string (kept, warned).
  std::string err;
  const Verdicts v = run("{a + b > 6}", {R"({"a": 4})", R"({"a": 1, "b": 5})", R"({"a": 2})", R"({"a": 3, "b": "x"})",
                                         R"({"a": 0, "b": null})"},
                         false, nullptr, &err);
  EXPECT_EQ(values(v), (std::vector<bool>{false, false, true, true, false}));
  EXPECT_NE(err.find("field \"b\" is a string, but an expression reads it"), std::string::npos) << err;
  // A Boolean counts 1 or 0.
  EXPECT_EQ(values(run("{flag + 1 > 1.5}", {R"({"flag": true})", R"({"flag": false})"})), (std::vector<bool>{true, false}));
}

TEST(ExprValues, StrictRejectsAMessageWithoutTheField) {
  std::string err;
  const Verdicts v = run("{a - b > 0}", {R"({"a": 4, "b": 1})", R"({"a": 1})", R"({"a": 0, "b": -1})"}, false, nullptr,
                         &err, /*strict=*/true);
  EXPECT_EQ(v, (Verdicts{{0, true}, {1, true}}));  // the second message is no step
  EXPECT_NE(err.find("missing field \"b\""), std::string::npos) << err;
}

TEST(ExprValues, DivisionByZeroAndNaN) {
  // 1/0 = inf (> 1 holds); 0/0 = NaN: every comparison false, != too; -1/0 = -inf.
  const std::vector<std::string> trace = {R"({"a": 1, "b": 0})", R"({"a": 0, "b": 0})", R"({"a": -1, "b": 0})"};
  EXPECT_EQ(values(run("{a / b > 1}", trace)), (std::vector<bool>{true, false, false}));
  EXPECT_EQ(values(run("{a / b != 1}", trace)), (std::vector<bool>{true, false, true}));
  std::vector<double> m;
  run("{a / b > 1}", trace, true, &m);
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(m, (std::vector<double>{inf, -inf, -inf}));
}

TEST(ExprValues, MarginsAreTheDifferenceOfTheSides) {
  std::vector<double> m;
  run("{abs(a - b) < 0.5}", {R"({"a": 1, "b": 1.25})", R"({"a": 1, "b": 3})"}, true, &m);
  EXPECT_EQ(m, (std::vector<double>{0.25, -1.5}));
  m.clear();
  run("{a >= 2 * b}", {R"({"a": 5, "b": 2})"}, true, &m);
  EXPECT_EQ(m, (std::vector<double>{1}));
  m.clear();
  run("{a == (b)}", {R"({"a": 5, "b": 2})"}, true, &m);
  EXPECT_EQ(m, (std::vector<double>{-3}));
  m.clear();
  run("{a + b > 0}", {R"({"a": 5})"}, true, &m);  // b never seen
  EXPECT_EQ(m, (std::vector<double>{-std::numeric_limits<double>::infinity()}));
}

TEST(ExprValues, DenseTimeChangesOnlyAtMessages) {
  Verdicts out;
  runtime::PipelineOptions po;
  po.model = engine::TimeModel::Dense;
  runtime::Pipeline p({{"p", "once[0:1]{a - b > 0}"}}, po, [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  uint64_t n = 0;
  // a - b: -1 on [0, 1.5), 1 on [1.5, 2) (b held), -2 from 2: once[0:1] holds on [1.5, 3).
  for (const char* l : {R"({"time": 0, "a": 1, "b": 2})", R"({"time": 1.5, "a": 3})", R"({"time": 2, "b": 5})",
                        R"({"time": 4, "a": 0})"})
    p.feed(l, ++n);
  EXPECT_EQ(out, (Verdicts{{0, false}, {1.5, true}, {3, false}}));
}

TEST(ExprValues, ExplainNamesTheNumbers) {
  std::vector<std::vector<std::string>> why;
  runtime::PipelineOptions po;
  po.explain = true;
  runtime::Pipeline p({{"p", "historically({abs(a - b) < 0.5})"}}, po, [&](const engine::Verdict& v) {
    if (v.explanation) why.push_back(*v.explanation);
  });
  p.feed(R"({"a": 1, "b": 1.25})", 1);
  p.feed(R"({"a": 1, "b": 3})", 2);
  ASSERT_EQ(why.size(), 1u);
  ASSERT_EQ(why[0].size(), 2u);
  EXPECT_EQ(why[0][1], "{abs((a - b)) < 0.5} is false at step 1 (a = 1, b = 3)");
}

// ---- rise and fall ----

TEST(Edges, RiseAndFallInDiscreteTime) {
  const std::vector<std::string> trace = {R"({"p": true})", R"({"p": true})", R"({"p": false})", R"({"p": true})",
                                          R"({"p": false})"};
  // rise at step 0 is p itself (the step before the first reads false); fall at step 0 is not p.
  EXPECT_EQ(values(run("rise({p})", trace)), (std::vector<bool>{true, false, false, true, false}));
  EXPECT_EQ(values(run("fall({p})", trace)), (std::vector<bool>{false, false, true, false, true}));
  EXPECT_EQ(values(run("fall({p})", {R"({"p": false})", R"({"p": false})"})), (std::vector<bool>{true, false}));
  EXPECT_EQ(canon("rise {p}"), "({p} and (not (pre {p})))");
  EXPECT_EQ(canon("fall({x > 1})"), "((not {x > 1}) and (not (pre (not {x > 1}))))");
}

TEST(Edges, RobustnessIsRtamts) {
  // RTAMT: rise = min(x, -previous x), previous -inf at first; fall = min(previous x, -x), previous +inf.
  std::vector<double> m;
  run("rise({x > 0})", {R"({"x": 2})", R"({"x": 3})", R"({"x": -1})", R"({"x": 4})"}, true, &m);
  EXPECT_EQ(m, (std::vector<double>{2, -2, -3, 1}));
  m.clear();
  run("fall({x > 0})", {R"({"x": 2})", R"({"x": 3})", R"({"x": -1})", R"({"x": 4})"}, true, &m);
  EXPECT_EQ(m, (std::vector<double>{-2, -3, 1, -4}));
}

TEST(Edges, DenseTimeRefusesThem) {
  std::string m;
  EXPECT_EQ(error_column("{a} and rise({p})", &m, /*dense=*/true), 9);
  EXPECT_NE(m.find("instant"), std::string::npos) << m;
}

TEST(Edges, NestingIsBounded) {
  std::string deep;
  for (int i = 0; i < 40; ++i) deep += "rise ";
  deep += "{p}";
  std::string m;
  EXPECT_GT(error_column(deep, &m), 0);  // 2^40 copies would be built: refused instead
  EXPECT_NE(m.find("rise/fall"), std::string::npos) << m;
}

// ---- fuzz: the extended grammar (tests/fuzz/fuzz_spec runs the same oracle under libFuzzer) ----

TEST(ExprFuzz, TokenSoupParsesToAFixedPointOrASpecError) {
  const char* tokens[] = {"{", "}", "a", "b.c", "x[1]", "\"k y\"", "+", "-", "*", "/", "abs(", "min(", "max(",
                          ",", "(", ")", "<", "<=", "==", "!=", ">", "2", "-1.5", "1e3", "0", "rise", "fall", "and",
                          "or", "not", "pre", "once[0:2]", "{a - b > 1}", "{abs(x) < 2}", "@age", "count[0:1]("};
  std::mt19937 rng(2929);
  // Half the cases from the grammar (valid, then cut at a random point half the time), half soup.
  const char* leaves[] = {"a", "b.c", "x[1]", "\"k y\"", "2", "1e3", "0", ".5"};
  const char* binary[] = {" + ", " - ", " * ", " / ", "-", "*"};
  const char* comparisons[] = {" < ", " <= ", " == ", " != ", " > ", ">="};
  std::function<std::string(int)> expr = [&](int depth) -> std::string {
    if (depth == 0 || rng() % 3 == 0) return leaves[rng() % 8];
    switch (rng() % 5) {
      case 0: return "abs(" + expr(depth - 1) + ")";
      case 1: return std::string(rng() % 2 ? "min(" : "max(") + expr(depth - 1) + ", " + expr(depth - 1) + ")";
      case 2: return "-" + expr(depth - 1);
      case 3: return "(" + expr(depth - 1) + ")";
      default: return expr(depth - 1) + binary[rng() % 6] + expr(depth - 1);
    }
  };
  std::function<std::string(int)> formula = [&](int depth) -> std::string {
    if (depth == 0 || rng() % 3 == 0) return "{" + expr(3) + comparisons[rng() % 6] + expr(3) + "}";
    switch (rng() % 4) {
      case 0: return std::string(rng() % 2 ? "rise " : "fall(") + formula(depth - 1) + (rng() % 2 ? "" : ")");
      case 1: return "not " + formula(depth - 1);
      case 2: return "(" + formula(depth - 1) + " and " + formula(depth - 1) + ")";
      default: return "once[0:2] " + formula(depth - 1);
    }
  };
  int parsed = 0, generated_parsed = 0;
  for (int i = 0; i < 4000; ++i) {
    std::string s;
    const bool generated = i % 2 == 0;
    if (generated) {
      s = formula(3);
      if (rng() % 2) s = s.substr(0, rng() % (s.size() + 1));
    } else {
      s = test::token_soup(rng, tokens, 12);
    }
    // Accepted specs run: the expression atoms are valued on a short trace.
    const bool accepted = test::accepted_round_trips_and_runs(
        s, i % 2 == 1,
        {R"({"a": 1, "b": {"c": 0}, "x": [0, -2], "k y": true})", R"({"a": 0})",
         R"({"a": "s", "x": [1e308, 1e308]})", R"({"b": {"c": null}, "x": [0, 0]})"});
    parsed += accepted;
    generated_parsed += accepted && generated;
  }
  EXPECT_GT(generated_parsed, 500) << "the grammar's cases are mostly valid";
  EXPECT_GT(parsed, generated_parsed);
}

// ---- two inputs ----

TEST(ExprSynced, ComparesFieldsOfTwoInputs) {
  Verdicts out;
  runtime::PipelineOptions po;
  po.emit_all = true;
  runtime::SyncOptions so;
  runtime::SyncedPipeline p({{"p", "{abs(steer.angle - cmd.angle) < 0.1}"}}, po,
                            {{"steer", "test:steer", nullptr, ""}, {"cmd", "test:cmd", nullptr, ""}}, so,
                            [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  const std::vector<std::tuple<uint32_t, std::string>> m = {
      {1, R"({"time": 0, "angle": 0.5})"},   // steer unseen: false
      {0, R"({"time": 1, "angle": 0.45})"},  // |0.45 - 0.5| < 0.1
      {1, R"({"time": 2, "angle": 0.9})"},   // steer holds 0.45
      {0, R"({"time": 3, "angle": 0.85})"}};
  uint64_t n = 0;
  for (const auto& [input, json] : m) p.feed_at(input, json, ++n, 0);
  p.end_of_input();
  EXPECT_EQ(values(out), (std::vector<bool>{false, true, false, true}));
}

TEST(ExprSynced, AFieldMustNameAnInput) {
  runtime::PipelineOptions po;
  runtime::SyncOptions so;
  try {
    runtime::SyncedPipeline p({{"p", "{steer.angle - angle > 0}"}}, po,
                              {{"steer", "test:steer", nullptr, ""}, {"cmd", "test:cmd", nullptr, ""}}, so, nullptr);
    FAIL() << "accepted";
  } catch (const spec::SpecError& e) {
    EXPECT_EQ(e.column(), 16);
    EXPECT_NE(e.message().find("names no input"), std::string::npos) << e.message();
  }
}

}  // namespace
}  // namespace rvc
