// Bounded future (issue 29): the horizon, the printed form of the new
// operators, and the checker's delayed verdicts (hand-computed), including
// the incremental (change-driven) and plain evaluations giving the same ones
// and large bounds (a horizon of 100,000 steps).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include "engine/checker.hpp"
#include "spec/parser.hpp"
#include "spec/pastify.hpp"

namespace rvc {
namespace {

double horizon_of(const std::string& text) { return spec::horizon(*spec::parse(text)); }

TEST(Future, Horizon) {
  EXPECT_EQ(horizon_of("{p}"), 0);
  EXPECT_EQ(horizon_of("once[0:9] {p}"), 0);
  EXPECT_EQ(horizon_of("eventually[1:3] {p}"), 3);
  EXPECT_EQ(horizon_of("eventually[1:3] always[0:2] {p}"), 5);
  EXPECT_EQ(horizon_of("{p} until[0:4] next {q}"), 5);
  EXPECT_EQ(horizon_of("once[0:9] (eventually[0:2] {p}) and next next {q}"), 2);
  EXPECT_EQ(horizon_of("(always[0:7] {p}) since[1:2] {q}"), 7);
}

TEST(Future, PrintedFormParsesBack) {
  for (const char* text : {"eventually[1:3] {p}", "{p} until[0:4] ({q} or next {r})", "not always[:2] {p}"}) {
    const std::string printed = spec::to_string(*spec::parse(text));
    EXPECT_EQ(spec::to_string(*spec::parse(printed)), printed) << text;
  }
  EXPECT_EQ(spec::to_string(*spec::parse("{p} until[0:4] {q}")), "({p} until[:4] {q})");
}

using Rec = std::tuple<double, bool, double>;  // time, value, known_at

std::vector<Rec> run(const std::string& text, const std::vector<int>& p, bool all, bool incremental) {
  std::vector<Rec> out;
  engine::Checker c(engine::TimeModel::Discrete, all, [&](const engine::Verdict& v) {
    out.emplace_back(v.time, v.value, v.known_at);
  });
  c.set_incremental(incremental);
  c.add_property({"f", text});
  std::vector<uint8_t> atoms(c.atoms().size(), 0);
  size_t at = 0;  // {p}'s slot (the end-of-stream marker has one too)
  while (c.atoms().tests()[at].key() != "p") ++at;
  for (int v : p) {
    atoms[at] = static_cast<uint8_t>(v);
    c.step(atoms.data());
  }
  c.finish();
  return out;
}

TEST(Future, DiscreteDelayAndEnd) {
  // p only at step 2: eventually[1:2] true for 0, 1; false from 2 (steps 3, 4 settled at the end).
  const std::vector<Rec> all{{0, true, 2}, {1, true, 3}, {2, false, 4}, {3, false, 4}, {4, false, 4}};
  const std::vector<Rec> changes{{0, true, 2}, {2, false, 4}};
  for (bool incremental : {false, true}) {
    EXPECT_EQ(run("eventually[1:2] {p}", {0, 0, 1, 0, 0}, true, incremental), all);
    EXPECT_EQ(run("eventually[1:2] {p}", {0, 0, 1, 0, 0}, false, incremental), changes);
  }
}

TEST(Future, FirstVerdictComesAtTheDelayEvenWithoutAChange) {
  // Constant input: the change-driven path must still report step 0, at step 3.
  const std::vector<Rec> want{{0, true, 3}};
  EXPECT_EQ(run("always[0:3] {p}", {1, 1, 1, 1, 1}, false, true), want);
  EXPECT_EQ(run("always[0:3] {p}", {1, 1, 1, 1, 1}, false, false), want);
}

TEST(Future, LargeHorizon) {
  // eventually[0:100000] over 200,000 steps with p only at step 150,000: true for 50,000..150,000.
  std::vector<int> p(200000, 0);
  p[150000] = 1;
  const std::vector<Rec> got = run("eventually[0:100000] {p}", p, false, true);
  const std::vector<Rec> want{{0, false, 100000}, {50000, true, 150000}, {150001, false, 199999}};
  EXPECT_EQ(got, want);
}

TEST(Future, PastOnlyHasNoKnownAt) {
  const std::vector<Rec> got = run("once {p}", {0, 1}, false, true);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_TRUE(std::isnan(std::get<2>(got[0])));
}

}  // namespace
}  // namespace rvc
