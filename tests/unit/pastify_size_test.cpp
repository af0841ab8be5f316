// The size of the bounded-future rewrite (issue 36): spec::pastified_size
// predicts, node for node, what spec::pastify makes, and a rewrite past
// kMaxPastifiedNodes is refused before it is made, at the until's column, in
// time linear in the formula (nested until[0:255] used to take ~90 s and
// 2.2 GB for two levels, std::bad_alloc for three).
#include <gtest/gtest.h>

#include <string>

#include "engine/checker.hpp"
#include "spec/parser.hpp"
#include "spec/pastify.hpp"
#include "spec/spec_error.hpp"

namespace rvc {
namespace {

uint64_t count_nodes(const spec::Node& n) {
  return 1 + (n.left ? count_nodes(*n.left) : 0) + (n.right ? count_nodes(*n.right) : 0);
}

spec::FieldTest end_marker() {
  spec::FieldTest end;
  end.path = {"\x01end"};
  return end;
}

TEST(PastifySize, PredictsTheRewriteNodeForNode) {
  const char* discrete[] = {
      "eventually[1:3] {p}", "always[0:2] {p}", "next next {q}", "{p} until[0:4] {q}",
      "{p} until[2:5] next {q}", "{p} until[0:0] {q}", "eventually[0:0] {p}",
      "once[0:9] (eventually[0:2] {p}) and next next {q}", "(always[0:7] {p}) since[1:2] {q}",
      "pre (next {x > 0})", "(once {p}) or (next {p})", "(historically {q}) and (next {q})",
      "not eventually[2:4] ({p} -> always[1:3] {q})", "({p} until[1:3] {q}) until[0:4] ({r} until[0:2] {p})",
      "historically[2:5] (eventually[0:3] {p} since {q})", "true until[0:3] false",
  };
  const spec::FieldTest end = end_marker();
  for (const char* text : discrete) {
    const auto ast = spec::parse(text);
    const double h = spec::horizon(*ast);
    const auto rewritten = spec::pastify(*ast, h, end, false, text);
    EXPECT_EQ(spec::pastified_size(*ast, h, false, text), count_nodes(*rewritten)) << text;
  }
  spec::ParseOptions dense;
  dense.dense = true;
  for (const char* text : {"eventually[0.5:1.5] {p}", "always[0:0.25] eventually[0.1:0.2] {p}",
                           "once[0:1] (always[0.3:0.7] {p}) and historically {q}"}) {
    const auto ast = spec::parse(text, dense);
    const double h = spec::horizon(*ast);
    const auto rewritten = spec::pastify(*ast, h, end, true, text);
    EXPECT_EQ(spec::pastified_size(*ast, h, true, text), count_nodes(*rewritten)) << text;
  }
}

// The column a SpecError points at (1-based), -1 if none was thrown.
int refused_at(const std::string& text, std::string* message = nullptr) {
  engine::Checker c(engine::TimeModel::Discrete, false, [](const engine::Verdict&) {});
  try {
    c.add_property({"f", text});
  } catch (const spec::SpecError& e) {
    if (message) *message = e.what();
    return e.column();
  }
  return -1;
}

TEST(PastifySize, NestedUntilIsRefusedBeforeItIsBuilt) {
  const std::string two = "{p} until[0:255] ({q} until[0:255] {r})";
  std::string message;
  EXPECT_EQ(refused_at(two, &message), 5);  // the outer until: the inner one alone fits
  EXPECT_NE(message.find("property too large"), std::string::npos) << message;
  EXPECT_NE(message.find("would need"), std::string::npos) << message;
  EXPECT_NE(message.find("the limit is 65000"), std::string::npos) << message;
  // Three and more levels: the counts saturate, never overflow, never allocate the rewrite.
  std::string deep = "{r}";
  for (int level = 0; level < 12; ++level) deep = "({p} until[0:255] " + deep + ")";
  EXPECT_GT(refused_at(deep, &message), 0);
  EXPECT_NE(message.find("property too large"), std::string::npos) << message;
  const auto ast = spec::parse(deep);
  EXPECT_GT(spec::pastified_size(*ast, spec::horizon(*ast), false, deep), uint64_t{1} << 60);
}

TEST(PastifySize, AChainJustUnderTheLimitStillWorks) {
  // Find the widest inner until that keeps the rewrite within the limit, by the size alone.
  int widest = -1;
  for (int k = 0; k < 255; ++k) {
    const std::string text = "{p} until[0:255] ({q} until[0:" + std::to_string(k) + "] {r})";
    const auto ast = spec::parse(text);
    if (spec::pastified_size(*ast, spec::horizon(*ast), false, text) > spec::kMaxPastifiedNodes) break;
    widest = k;
  }
  ASSERT_GT(widest, 0);
  const std::string fits = "{p} until[0:255] ({q} until[0:" + std::to_string(widest) + "] {r})";
  const std::string over = "{p} until[0:255] ({q} until[0:" + std::to_string(widest + 1) + "] {r})";
  EXPECT_EQ(refused_at(fits), -1) << fits;
  EXPECT_EQ(refused_at(over), 5) << over;
}

TEST(PastifySize, UntilChecksComeFirst) {
  std::string message;
  EXPECT_EQ(refused_at("{p} until[0:256] {q}", &message), 5);
  EXPECT_NE(message.find("b - a >= 256"), std::string::npos) << message;
}

}  // namespace
}  // namespace rvc
