// Hostile specs: deep nesting is a spec error naming the limit (never a stack
// overflow), long and/or chains stay shallow, huge discrete bounds are
// refused instead of clamped, and columns count characters, not bytes.
#include <gtest/gtest.h>

#include <string>

#include "engine/checker.hpp"
#include "spec/parser.hpp"

namespace rvc::spec {
namespace {

std::string repeat(const std::string& s, int n) {
  std::string out;
  for (int i = 0; i < n; ++i) out += s;
  return out;
}

// The error message of parsing+compiling `text`, or "" if it is accepted.
std::string error_of(const std::string& text, bool dense = false) {
  try {
    engine::Checker c(dense ? engine::TimeModel::Dense : engine::TimeModel::Discrete, false, nullptr);
    c.add_property({"p", text});
    return "";
  } catch (const SpecError& e) {
    return e.what();
  }
}

TEST(SpecLimits, DeepNestingIsASpecErrorNotACrash) {
  for (const std::string& spec : {repeat("(", 10000) + "{p}" + repeat(")", 10000),
                                  repeat("not(", 7000) + "{p}" + repeat(")", 7000), repeat("pre ", 200000) + "{p}",
                                  repeat("{p} -> ", 5000) + "{p}", repeat("exists[x]. ", 3000) + "{p}",
                                  repeat("once ", 100000) + "{p}"}) {
    std::string e = error_of(spec);
    EXPECT_NE(e.find("formula nested deeper than "), std::string::npos) << e.substr(0, 200);
    EXPECT_NE(e.find(" (the limit)"), std::string::npos) << e.substr(0, 200);
  }
  // the height of the formula, whatever the parentheses
  EXPECT_NE(error_of(repeat("pre ", 1200) + "{p}").find("formula nested deeper than 1000 levels (the limit)"),
            std::string::npos);
  EXPECT_NE(error_of(repeat("(", 2100) + "{p}" + repeat(")", 2100)).find("2008 levels of parentheses"),
            std::string::npos);
}

// Found by fuzz_spec: 533 '!' were accepted, but their printed form
// "(not (not ...))" nests twice as deep and was refused. Whatever is accepted
// prints to a text that parses back to itself.
TEST(SpecLimits, FuzzFoundPrintedFormOfADeepFormulaParsesBack) {
  for (int n : {533, 998}) {  // 998: once + 998 nots + the test = 1000 levels
    const std::string spec = "once[:20]" + repeat("!", n) + "{q}";
    auto ast = spec::parse(spec);
    const std::string printed = spec::to_string(*ast);
    EXPECT_EQ(spec::to_string(*spec::parse(printed)), printed) << n;
  }
  EXPECT_NE(error_of("once[:20]" + repeat("!", 1000) + "{q}").find("deeper than 1000 levels"), std::string::npos);
}

TEST(SpecLimits, ReasonableNestingIsAccepted) {
  EXPECT_EQ(error_of(repeat("(", 300) + "{p}" + repeat(")", 300)), "");
  EXPECT_EQ(error_of(repeat("pre ", 300) + "{p}"), "");
  EXPECT_EQ(error_of(repeat("once[0:2] ", 200) + "{p}", true), "");
}

TEST(SpecLimits, LongChainsAreBalanced) {
  std::string chain = "{a0}";
  for (int i = 1; i < 20000; ++i) chain += (i % 2 ? " or {a" : " and {a") + std::to_string(i) + "}";
  EXPECT_EQ(error_of(chain), "");  // 20,000 atoms, 20,000 operators: parsed, compiled, destroyed
  NodePtr tree = parse(repeat("{p} or ", 4095) + "{p}");
  int height = 0;
  for (const Node* n = tree.get(); n; n = n->left.get()) ++height;
  EXPECT_EQ(height, 13);  // log2(4096) + 1, not 4096
  // Short chains keep the left nesting users read in the canonical text.
  EXPECT_EQ(to_string(*parse("{a} or {b} or {c}")), "(({a} or {b}) or {c})");
}

TEST(SpecLimits, TooLargeForOneMonitorIsASpecError) {
  std::string e = error_of(repeat("{p} or ", 49999) + "{p}");
  EXPECT_NE(e.find("property too large"), std::string::npos) << e.substr(0, 200);
  EXPECT_LT(e.size(), 400u);  // the caret line shows a window, not the whole spec
}

TEST(SpecBounds, DiscreteBoundsAreIntegersThatFit) {
  EXPECT_EQ(error_of("once[0:9007199254740992]{p}"), "");
  std::string e = error_of("once[0:99999999999999999999]{p}");
  EXPECT_NE(e.find("spec error at column 8: time bound 99999999999999999999 is too large"), std::string::npos) << e;
  e = error_of("once[0:9007199254740993]{p}");
  EXPECT_NE(e.find("too large"), std::string::npos) << e;
  EXPECT_NE(error_of("once[1e30:]{p}").find("too large"), std::string::npos);
  EXPECT_NE(error_of("once[1.5:3]{p}").find("integer bounds"), std::string::npos);
  EXPECT_NE(error_of("once[-1:3]{p}").find("must not be negative"), std::string::npos);
  EXPECT_NE(error_of("once[5:2]{p}").find("empty time interval"), std::string::npos);
  EXPECT_NE(error_of("once[0:1e999]{p}", true).find("not a finite number"), std::string::npos);
  // Dense bounds are read to exact nanoseconds, up to 2^53 ns (spec/exact_time.hpp).
  EXPECT_NE(error_of("once[0:1e30]{p}", true).find("too large"), std::string::npos);
  EXPECT_NE(error_of("once[0:9007199.254740993]{p}", true).find("too large"), std::string::npos);
  EXPECT_EQ(error_of("once[0:9007199.254740992]{p}", true), "");
  EXPECT_EQ(error_of("once[0.000000001:0.025]{p}", true), "");
}

TEST(SpecColumns, CountCharactersNotBytes) {
  // "äöü" is 3 characters, 6 bytes: the end, where the error is, is character 25.
  std::string e = error_of("{name == \"äöü\"} and ( {x");
  EXPECT_NE(e.find("spec error at column 25:"), std::string::npos) << e;
  // The caret sits under the 25th character of the shown line.
  auto nl = e.find('\n');
  std::string line = e.substr(nl + 3, e.find('\n', nl + 1) - nl - 3);
  std::string caret = e.substr(e.rfind('\n') + 3);
  EXPECT_EQ(caret, std::string(24, ' ') + "^");
  EXPECT_EQ(line, "{name == \"äöü\"} and ( {x");
  // Tabs before the column stay tabs, so the caret lines up.
  e = error_of("\t{p} and (");
  EXPECT_EQ(e.substr(e.rfind('\n') + 3), "\t         ^");
  // Columns inside messages count characters too.
  e = error_of("{s == \"é\"} and ({p}");
  EXPECT_NE(e.find("close the '(' at column 16"), std::string::npos) << e;
}

}  // namespace
}  // namespace rvc::spec
