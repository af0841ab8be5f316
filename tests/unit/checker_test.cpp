// Checker: several properties over one atom table; condensed vs emit_all
// verdicts; the violation counter; atom sharing between properties.
#include <gtest/gtest.h>

#include <string>
#include <tuple>
#include <vector>

#include "engine/checker.hpp"
#include "spec/spec_error.hpp"
#include "test_util.hpp"

namespace rvc::engine {
namespace {

using test::atom_index;
using Rec = std::tuple<std::string, double, bool>;

struct Recorder {
  std::vector<Rec> verdicts;
  VerdictCallback callback() {
    return [this](const Verdict& v) { verdicts.emplace_back(v.property, v.time, v.value); };
  }
};

TEST(Checker, CondensedReportsOnlyChanges) {
  Recorder r;
  Checker c(TimeModel::Discrete, /*emit_all=*/false, r.callback());
  c.add_property({"safe", "{p}"});
  // p: F F T T F -> changes at 0 (first verdict), 2 and 4.
  for (uint8_t p : {0, 0, 1, 1, 0}) c.step(&p);
  EXPECT_EQ(r.verdicts, (std::vector<Rec>{{"safe", 0, false}, {"safe", 2, true}, {"safe", 4, false}}));
  EXPECT_EQ(c.violations(), 2u);  // two false verdicts were reported
}

TEST(Checker, EmitAllReportsEveryStep) {
  Recorder r;
  Checker c(TimeModel::Discrete, /*emit_all=*/true, r.callback());
  c.add_property({"safe", "{p}"});
  for (uint8_t p : {0, 0, 1, 1, 0}) c.step(&p);
  EXPECT_EQ(r.verdicts, (std::vector<Rec>{{"safe", 0, false},
                                          {"safe", 1, false},
                                          {"safe", 2, true},
                                          {"safe", 3, true},
                                          {"safe", 4, false}}));
  EXPECT_EQ(c.violations(), 3u);  // steps 0, 1 and 4
}

TEST(Checker, NoViolationWhenAlwaysTrue) {
  Recorder r;
  Checker c(TimeModel::Discrete, false, r.callback());
  c.add_property({"ok", "{p} or not {p}"});
  for (uint8_t p : {0, 1, 0}) c.step(&p);
  EXPECT_EQ(r.verdicts, (std::vector<Rec>{{"ok", 0, true}}));
  EXPECT_EQ(c.violations(), 0u);
}

TEST(Checker, SharedAtomIsInternedOnce) {
  Recorder r;
  Checker c(TimeModel::Discrete, /*emit_all=*/true, r.callback());
  c.add_property({"fast", "{speed > 3}"});
  c.add_property({"always_fast", "historically {speed > 3.0}"});  // 3.0 is the same number
  c.add_property({"sporty", "{speed>3} and {mode: sport}"});
  c.add_property({"either", "{mode: \"sport\"} or {speed >= 3}"});  // quoted = bare; >= is a new test
  ASSERT_EQ(c.size(), 4u);
  EXPECT_EQ(c.names(), (std::vector<std::string>{"fast", "always_fast", "sporty", "either"}));
  // speed > 3, mode == "sport", speed >= 3: three distinct tests, each stored once.
  ASSERT_EQ(c.atoms().size(), 3u);
  int gt = atom_index(c, "speed > 3"), mode = atom_index(c, "mode == \"sport\""), ge = atom_index(c, "speed >= 3");
  EXPECT_EQ(gt, 0);  // interned in order of first use
  EXPECT_EQ(mode, 1);
  EXPECT_EQ(ge, 2);

  // Step 0: speed 5, mode sport. Step 1: speed 3, mode eco.
  uint8_t s0[3], s1[3];
  s0[gt] = 1, s0[mode] = 1, s0[ge] = 1;
  s1[gt] = 0, s1[mode] = 0, s1[ge] = 1;
  c.step(s0);
  c.step(s1);
  // Properties report in the order they were added, every step.
  EXPECT_EQ(r.verdicts, (std::vector<Rec>{{"fast", 0, true},
                                          {"always_fast", 0, true},
                                          {"sporty", 0, true},
                                          {"either", 0, true},
                                          {"fast", 1, false},
                                          {"always_fast", 1, false},
                                          {"sporty", 1, false},
                                          {"either", 1, true}}));
  EXPECT_EQ(c.violations(), 3u);
}

TEST(Checker, CondensedIsPerProperty) {
  Recorder r;
  Checker c(TimeModel::Discrete, false, r.callback());
  c.add_property({"now", "{p}"});
  c.add_property({"before", "pre {p}"});
  // p: T T F. now: T T F -> (0,T) (2,F). before: F T T -> (0,F) (1,T).
  for (uint8_t p : {1, 1, 0}) c.step(&p);
  EXPECT_EQ(r.verdicts, (std::vector<Rec>{{"now", 0, true}, {"before", 0, false}, {"before", 1, true}, {"now", 2, false}}));
  EXPECT_EQ(c.violations(), 2u);
}

TEST(Checker, RejectedPropertyIsNotAdded) {
  Checker c(TimeModel::Discrete, false, nullptr);
  c.add_property({"good", "{p}"});
  EXPECT_THROW(c.add_property({"bad", "{p} and"}), spec::SpecError);
  EXPECT_THROW(c.add_property({"bind", "{q} and {id: *x}"}), spec::SpecError);
  EXPECT_EQ(c.size(), 1u);
  EXPECT_EQ(c.names(), (std::vector<std::string>{"good"}));
  uint8_t values[8] = {1, 1, 1, 1, 1, 1, 1, 1};
  c.step(values);  // still steps fine
  EXPECT_EQ(c.violations(), 0u);
}

TEST(Checker, DenseReportsPiecesWithTheirTimes) {
  Recorder r;
  Checker c(TimeModel::Dense, false, r.callback());
  c.add_property({"late", "once[1:2] {p}"});
  c.add_property({"now", "{p}"});
  uint8_t on = 1, off = 0;
  c.step(0, 1, &on);   // late: F on [0,1); now: T
  c.step(1, 1, &off);  // empty segment: ignored, nothing reported
  c.step(1, 5, &off);  // late: T on [1,3), F on [3,5); now: F
  EXPECT_EQ(r.verdicts, (std::vector<Rec>{{"late", 0, false}, {"now", 0, true}, {"late", 1, true}, {"late", 3, false},
                                          {"now", 1, false}}));
  EXPECT_EQ(c.violations(), 3u);
}

// The atom table is shared by all properties, so its indices can exceed what
// one property holds. A property whose atom comes after 70000 others must
// still read its own atom.
std::string balanced_or(int lo, int hi) {  // {aLO} or ... or {aHI-1}, as a balanced tree
  if (hi - lo == 1) return "{a" + std::to_string(lo) + "}";
  int mid = (lo + hi) / 2;
  return "(" + balanced_or(lo, mid) + " or " + balanced_or(mid, hi) + ")";
}

TEST(Checker, AtomIndexBeyond65535AcrossProperties) {
  // Regression: the discrete Monitor once addressed atoms through uint16_t
  // slots indexed by the Checker-wide AtomTable, so once all properties
  // together used more than ~65,000 atoms, later ones were refused (and an
  // earlier version read atom 70000 as atom 4464). Atom slots are per
  // property now; the limit applies to each property alone.
  Recorder r;
  Checker c(TimeModel::Discrete, false, r.callback());
  for (int k = 0; k < 7; ++k) c.add_property({"big" + std::to_string(k), balanced_or(10000 * k, 10000 * (k + 1))});
  c.add_property({"z", "{z}"});
  ASSERT_EQ(c.atoms().size(), 70001u);
  int z = atom_index(c, "z");
  ASSERT_EQ(z, 70000);
  std::vector<uint8_t> values(c.atoms().size(), 0);
  values[z] = 1;  // only z holds: the big ones are false, z is true
  c.step(values.data());
  ASSERT_EQ(r.verdicts.size(), 8u);
  EXPECT_EQ(r.verdicts.back(), (Rec{"z", 0, true}));
}

}  // namespace
}  // namespace rvc::engine
