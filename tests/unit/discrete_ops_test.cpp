// Discrete-time operators (src/engine/discrete), one group per file, driven
// directly and through a compiled monitor. Every expected trace is written
// out by hand from the definitions; comments give the reasoning.
#include <gtest/gtest.h>

#include "spec/spec_error.hpp"

#include <vector>

#include "engine/discrete/historically.hpp"
#include "engine/discrete/once.hpp"
#include "engine/discrete/pre.hpp"
#include "engine/discrete/since.hpp"
#include "engine/interval_queue.hpp"
#include "test_util.hpp"

namespace rvc::engine::discrete {
namespace {

using test::run_discrete;
using V = std::vector<int>;

V drive(Once& op, const V& in) {
  V out;
  for (size_t i = 0; i < in.size(); ++i) out.push_back(op.update(static_cast<Step>(i), in[i] != 0));
  return out;
}
V drive(Historically& op, const V& in) {
  V out;
  for (size_t i = 0; i < in.size(); ++i) out.push_back(op.update(static_cast<Step>(i), in[i] != 0));
  return out;
}
V drive(Since& op, const V& left, const V& right) {
  V out;
  for (size_t i = 0; i < left.size(); ++i) out.push_back(op.update(static_cast<Step>(i), left[i] != 0, right[i] != 0));
  return out;
}

// ---------------------------------------------------------------- IntervalQueue

TEST(IntervalQueue, MergesTouchingIntegerIntervals) {
  IntervalQueue<int64_t> q;
  q.add(3, 5, 1);
  q.add(6, 8, 1);  // 6 <= 5 + 1: [3,5] and [6,8] are contiguous steps
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q.front().lo, 3);
  EXPECT_EQ(q.front().hi, 8);
  q.add(10, 12, 1);  // 10 > 8 + 1: a gap (step 9)
  ASSERT_EQ(q.size(), 2u);
  q.add(11, 11, 1);  // inside the last one: nothing changes
  ASSERT_EQ(q.size(), 2u);
  EXPECT_EQ(q.at(1).hi, 12);
  q.drop_before(9);  // [3,8] ends before 9
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q.front().lo, 10);
  q.drop_before(12);  // [10,12] still covers 12
  EXPECT_EQ(q.size(), 1u);
  q.drop_before(13);
  EXPECT_TRUE(q.empty());
}

TEST(IntervalQueue, RightOpenRealIntervalsTouchAtTheirEnds) {
  IntervalQueue<double> q;
  q.add(0, 1, 0);
  q.add(1, 2, 0);  // [0,1) and [1,2) together cover [0,2)
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q.front().hi, 2);
  q.add(2.5, 3, 0);
  ASSERT_EQ(q.size(), 2u);
  q.drop_until(2);  // [0,2) is useless from 2 on
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q.front().lo, 2.5);
  q.drop_until(2.9);
  EXPECT_EQ(q.size(), 1u);
}

TEST(IntervalQueue, GrowsAcrossTheRingWrapKeepingOrder) {
  IntervalQueue<int64_t> q;
  for (int64_t i = 0; i < 8; ++i) q.add(10 * i, 10 * i + 1, 1);  // fills the first 8 slots
  for (int i = 0; i < 5; ++i) q.pop_front();                    // head moves to slot 5
  for (int64_t i = 8; i < 13; ++i) q.add(10 * i, 10 * i + 1, 1);  // wraps to slots 0..4
  ASSERT_EQ(q.size(), 8u);
  q.add(130, 131, 1);  // full: grows, must unwrap in order
  ASSERT_EQ(q.size(), 9u);
  for (size_t i = 0; i < q.size(); ++i) EXPECT_EQ(q.at(i).lo, static_cast<int64_t>(10 * (i + 5))) << i;
  q.clear();
  EXPECT_TRUE(q.empty());
}

// ---------------------------------------------------------------- Pre

TEST(DiscretePre, FalseFirstThenPreviousValue) {
  Pre pre;
  // Input T F T T F: output is the input shifted one step, F at step 0.
  EXPECT_FALSE(pre.update(true));
  EXPECT_TRUE(pre.update(false));
  EXPECT_FALSE(pre.update(true));
  EXPECT_TRUE(pre.update(true));
  EXPECT_TRUE(pre.update(false));
}

TEST(DiscretePre, ThroughMonitor) {
  EXPECT_EQ(run_discrete("pre {p}", {{"p", {1, 0, 1, 1, 0}}}), (V{0, 1, 0, 1, 1}));
  // pre pre p: shifted twice.
  EXPECT_EQ(run_discrete("pre pre {p}", {{"p", {1, 0, 1, 1, 0}}}), (V{0, 0, 1, 0, 1}));
  // Y is the same operator; not pre p is true at step 0.
  EXPECT_EQ(run_discrete("not Y {p}", {{"p", {1, 1, 0}}}), (V{1, 0, 0}));
}

// ---------------------------------------------------------------- Once

TEST(DiscreteOnce, Unbounded) {
  Once once;  // [0, forever)
  // True from the first p on, forever.
  EXPECT_EQ(drive(once, {0, 0, 1, 0, 0, 1, 0}), (V{0, 0, 1, 1, 1, 1, 1}));
}

TEST(DiscreteOnce, FirstStep) {
  Once a;
  EXPECT_EQ(drive(a, {1}), (V{1}));  // [0:] includes the current step
  Once b{1, kForever, {}};
  EXPECT_EQ(drive(b, {1, 0}), (V{0, 1}));  // [1:] cannot see step 0 until step 1
}

TEST(DiscreteOnce, ZeroZeroIsTheInput) {
  Once once{0, 0, {}};  // now - j in [0,0]: j = now
  EXPECT_EQ(drive(once, {1, 0, 0, 1, 1, 0}), (V{1, 0, 0, 1, 1, 0}));
}

TEST(DiscreteOnce, Window) {
  Once once{2, 4, {}};
  // p only at step 1: true at steps 1+2 .. 1+4 = 3..5.
  EXPECT_EQ(drive(once, {0, 1, 0, 0, 0, 0, 0, 0}), (V{0, 0, 0, 1, 1, 1, 0, 0}));
}

TEST(DiscreteOnce, WindowsOfTwoInputsMergeOrNot) {
  Once merged{2, 3, {}};
  // p at 1 and 3: [3,4] and [5,6] touch -> true on 3..6.
  EXPECT_EQ(drive(merged, {0, 1, 0, 1, 0, 0, 0, 0}), (V{0, 0, 0, 1, 1, 1, 1, 0}));
  Once gap{2, 3, {}};
  // p at 1 and 4: [3,4] and [6,7]; step 5 sees j in {2,3}, where p is false.
  EXPECT_EQ(drive(gap, {0, 1, 0, 0, 1, 0, 0, 0, 0}), (V{0, 0, 0, 1, 1, 0, 1, 1, 0}));
}

TEST(DiscreteOnce, LowerBoundOnly) {
  Once once{2, kForever, {}};
  // p at 1: true from step 3 on.
  EXPECT_EQ(drive(once, {0, 1, 0, 0, 0, 0}), (V{0, 0, 0, 1, 1, 1}));
}

TEST(DiscreteOnce, UpperBoundOnly) {
  Once once{0, 2, {}};
  // p at 1: true at 1, 2, 3; p again at 6: true at 6, 7, 8.
  EXPECT_EQ(drive(once, {0, 1, 0, 0, 0, 0, 1, 0, 0, 0}), (V{0, 1, 1, 1, 0, 0, 1, 1, 1, 0}));
}

TEST(DiscreteOnce, ThroughMonitorWithBounds) {
  EXPECT_EQ(run_discrete("once[2:4] {p}", {{"p", {0, 1, 0, 0, 0, 0, 0, 0}}}), (V{0, 0, 0, 1, 1, 1, 0, 0}));
  EXPECT_EQ(run_discrete("once[:0] {p}", {{"p", {1, 0, 1}}}), (V{1, 0, 1}));
  EXPECT_EQ(run_discrete("P[3:] {p}", {{"p", {1, 0, 0, 0, 0}}}), (V{0, 0, 0, 1, 1}));
  // A bound larger than any step count is as good as none; one that does not
  // fit the engine is refused (it used to be clamped silently).
  EXPECT_EQ(run_discrete("once[:9007199254740992] {p}", {{"p", {0, 1, 0}}}), (V{0, 1, 1}));
  EXPECT_THROW(run_discrete("once[:1e30] {p}", {{"p", {0}}}), spec::SpecError);
}

// once[:1000] over 5000 steps: with a zero lower bound two live windows
// [j, j+1000] can never be disjoint, so the queue never holds more than one.
TEST(DiscreteOnce, LargeUpperBoundKeepsQueueAtOne) {
  Once once{0, 1000, {}};
  uint64_t x = 88172645463325252ull;  // xorshift: a sparse pseudo-random input
  std::vector<int> in;
  for (int i = 0; i < 5000; ++i) {
    x ^= x << 13, x ^= x >> 7, x ^= x << 17;
    in.push_back(x % 700 == 0);
  }
  size_t max_size = 0;
  int last_p = -1000000;
  for (int now = 0; now < 5000; ++now) {
    if (in[now]) last_p = now;
    bool got = once.update(now, in[now] != 0);
    EXPECT_EQ(got, now - last_p <= 1000) << now;  // definition: some p in [now-1000, now]
    max_size = std::max(max_size, once.window.size());
  }
  EXPECT_LE(max_size, 1u);
}

// once[990:1000] with p every 20 steps: windows [j+990, j+1000] are 11 wide
// with gaps, so they never merge; the live ones have j in [now-1000, now],
// i.e. at most 51 multiples of 20, reached when now is a multiple of 20.
TEST(DiscreteOnce, LargeBoundedWindowQueueStaysBounded) {
  Once once{990, 1000, {}};
  size_t max_size = 0;
  for (int now = 0; now < 5000; ++now) {
    bool got = once.update(now, now % 20 == 0);
    // True iff some multiple of 20 lies in [now-1000, now-990], j >= 0.
    bool expected = false;
    for (int j = now - 1000; j <= now - 990; ++j) expected = expected || (j >= 0 && j % 20 == 0);
    ASSERT_EQ(got, expected) << now;
    max_size = std::max(max_size, once.window.size());
  }
  EXPECT_EQ(max_size, 51u);
}

TEST(DiscreteOnce, LargeBoundSpotValues) {
  Once once{990, 1000, {}};
  std::vector<int> out;
  for (int now = 0; now <= 1010; ++now) out.push_back(once.update(now, now % 20 == 0));
  EXPECT_EQ(out[989], 0);   // j would be -1..-11
  EXPECT_EQ(out[990], 1);   // j = 0
  EXPECT_EQ(out[1000], 1);  // j in [0, 10] holds 0
  EXPECT_EQ(out[1001], 0);  // j in [1, 11]: no multiple of 20
  EXPECT_EQ(out[1009], 0);  // j in [9, 19]
  EXPECT_EQ(out[1010], 1);  // j in [10, 20] holds 20
}

// ---------------------------------------------------------------- Historically

TEST(DiscreteHistorically, Unbounded) {
  Historically h;
  // False from the first failure on, forever.
  EXPECT_EQ(drive(h, {1, 1, 0, 1, 1}), (V{1, 1, 0, 0, 0}));
}

TEST(DiscreteHistorically, ZeroZeroIsTheInput) {
  Historically h{Once{0, 0, {}}};
  EXPECT_EQ(drive(h, {1, 0, 1, 1, 0}), (V{1, 0, 1, 1, 0}));
}

TEST(DiscreteHistorically, WindowIsVacuouslyTrueAtTheStart) {
  Historically h{Once{2, 3, {}}};
  // Steps 0, 1: the window [now-3, now-2] lies before step 0 -> true.
  // Step 2: j = 0 (T). Step 3: j in {0,1} (T,T). Step 4: {1,2} has F at 2.
  // Step 5: {2,3} has F. Step 6: {3,4} all T.
  EXPECT_EQ(drive(h, {1, 1, 0, 1, 1, 1, 1}), (V{1, 1, 1, 1, 0, 0, 1}));
}

TEST(DiscreteHistorically, FalseAtStepZeroIsSeenOnlyFromTheLowerBound) {
  Historically h{Once{2, kForever, {}}};
  // p false at 0: the window [0, now-2] contains step 0 from now = 2 on.
  EXPECT_EQ(drive(h, {0, 1, 1, 1}), (V{1, 1, 0, 0}));
}

TEST(DiscreteHistorically, UpperBoundOnly) {
  Historically h{Once{0, 2, {}}};
  // p false at 1 only: false at 1, 2, 3; true again from 4.
  EXPECT_EQ(drive(h, {1, 0, 1, 1, 1, 1}), (V{1, 0, 0, 0, 1, 1}));
}

TEST(DiscreteHistorically, ThroughMonitor) {
  EXPECT_EQ(run_discrete("historically[2:3] {p}", {{"p", {1, 1, 0, 1, 1, 1, 1}}}), (V{1, 1, 1, 1, 0, 0, 1}));
  EXPECT_EQ(run_discrete("H {p}", {{"p", {1, 0, 1}}}), (V{1, 0, 0}));
  // historically[:1000] over a trace with one failure at step 10.
  std::vector<int> p(1500, 1);
  p[10] = 0;
  V got = run_discrete("historically[:1000] {p}", {{"p", p}});
  for (int i = 0; i < 1500; ++i) EXPECT_EQ(got[i], (i >= 10 && i <= 1010) ? 0 : 1) << i;
}

// ---------------------------------------------------------------- Since

TEST(DiscreteSince, Unbounded) {
  Since s;
  //        step: 0  1  2  3  4  5  6
  V a =          {0, 0, 1, 1, 0, 1, 1};
  V b =          {0, 1, 0, 0, 0, 0, 1};
  // b at 1 starts it; a holds at 2, 3; a fails at 4 (b false) -> off until b at 6.
  EXPECT_EQ(drive(s, a, b), (V{0, 1, 1, 1, 0, 0, 1}));
}

TEST(DiscreteSince, FirstStepNeedsOnlyRight) {
  Since s;
  // psi at step 0 makes it true whatever phi is (phi is needed only after j).
  EXPECT_EQ(drive(s, {0, 1}, {1, 0}), (V{1, 1}));
}

TEST(DiscreteSince, RightAtTheStepWhereLeftFailsStillCounts) {
  Since s;
  //   a: T T F T T ; b: T F T F F
  // Step 2: a fails, dropping j = 0, but b holds at 2 itself -> true; then a holds.
  EXPECT_EQ(drive(s, {1, 1, 0, 1, 1}, {1, 0, 1, 0, 0}), (V{1, 1, 1, 1, 1}));
  Since t;
  //   a: T T F T ; b: T F F F -> j = 0 is dropped at 2 for good.
  EXPECT_EQ(drive(t, {1, 1, 0, 1}, {1, 0, 0, 0}), (V{1, 1, 0, 0}));
}

TEST(DiscreteSince, ZeroZeroIsTheRightOperand) {
  Since s{0, 0, {}};
  EXPECT_EQ(drive(s, {0, 1, 0, 1}, {1, 0, 1, 1}), (V{1, 0, 1, 1}));
}

TEST(DiscreteSince, Window) {
  Since s{2, 4, {}};
  // b at 0, a always: true where now - 0 in [2, 4].
  EXPECT_EQ(drive(s, {1, 1, 1, 1, 1, 1, 1}, {1, 0, 0, 0, 0, 0, 0}), (V{0, 0, 1, 1, 1, 0, 0}));
  Since t{2, 4, {}};
  // Same, but a fails at 3: true at 2 only.
  EXPECT_EQ(drive(t, {1, 1, 1, 0, 1, 1, 1}, {1, 0, 0, 0, 0, 0, 0}), (V{0, 0, 1, 0, 0, 0, 0}));
}

TEST(DiscreteSince, LowerBoundOnly) {
  Since s{2, kForever, {}};
  // b at 1, a always: true from 3 on.
  EXPECT_EQ(drive(s, {1, 1, 1, 1, 1, 1}, {0, 1, 0, 0, 0, 0}), (V{0, 0, 0, 1, 1, 1}));
}

TEST(DiscreteSince, UpperBoundOnly) {
  Since s{0, 2, {}};
  // b at 1, a always: true at 1, 2, 3 (now - 1 <= 2), false after.
  EXPECT_EQ(drive(s, {1, 1, 1, 1, 1, 1}, {0, 1, 0, 0, 0, 0}), (V{0, 1, 1, 1, 0, 0}));
}

TEST(DiscreteSince, ThroughMonitor) {
  EXPECT_EQ(run_discrete("{a} since {b}", {{"a", {0, 0, 1, 1, 0, 1, 1}}, {"b", {0, 1, 0, 0, 0, 0, 1}}}),
            (V{0, 1, 1, 1, 0, 0, 1}));
  EXPECT_EQ(run_discrete("{a} S[2:4] {b}", {{"a", {1, 1, 1, 0, 1, 1, 1}}, {"b", {1, 0, 0, 0, 0, 0, 0}}}),
            (V{0, 0, 1, 0, 0, 0, 0}));
  // not-p since q: q at 0, p at 3 breaks it.
  EXPECT_EQ(run_discrete("(not {p}) since {q}", {{"p", {0, 0, 0, 1, 0}}, {"q", {1, 0, 0, 0, 0}}}),
            (V{1, 1, 1, 0, 0}));
}

// since[:1000] with a always true and b sparse: like once, the candidates
// never need more than one interval.
TEST(DiscreteSince, LargeBoundQueueStaysSmall) {
  Since s{0, 1000, {}};
  int last_b = -1000000;
  size_t max_size = 0;
  for (int now = 0; now < 5000; ++now) {
    bool b = now % 1300 == 7;
    bool a = now % 2600 != 1800;  // a fails now and then, dropping candidates
    if (!a) last_b = -1000000;
    if (b) last_b = now;
    bool got = s.update(now, a, b);
    EXPECT_EQ(got, now - last_b <= 1000) << now;
    max_size = std::max(max_size, s.candidates.size());
  }
  EXPECT_LE(max_size, 1u);
}

// ---------------------------------------------------------------- combined

TEST(DiscreteMonitor, BooleanConnectivesAndConstants) {
  std::map<std::string, std::vector<int>> ab = {{"a", {0, 0, 1, 1}}, {"b", {0, 1, 0, 1}}};
  EXPECT_EQ(run_discrete("{a} and {b}", ab), (V{0, 0, 0, 1}));
  EXPECT_EQ(run_discrete("{a} or {b}", ab), (V{0, 1, 1, 1}));
  EXPECT_EQ(run_discrete("{a} -> {b}", ab), (V{1, 1, 0, 1}));
  EXPECT_EQ(run_discrete("not {a}", {{"a", {0, 1}}}), (V{1, 0}));
  EXPECT_EQ(run_discrete("true and not false or {a}", {{"a", {0, 0}}}), (V{1, 1}));
}

TEST(DiscreteMonitor, NestedTemporal) {
  // historically({r} -> once[1:2]{p}): every r needs a p 1 or 2 steps before.
  //   step: 0 1 2 3 4 5 6
  //   p:    1 0 0 0 1 0 0
  //   r:    0 1 1 0 0 0 1
  // r at 1: p at 0 (dist 1) ok. r at 2: p at 0 (dist 2) ok. r at 6: p at 4 (dist 2) ok.
  EXPECT_EQ(run_discrete("historically({r} -> once[1:2]{p})", {{"p", {1, 0, 0, 0, 1, 0, 0}}, {"r", {0, 1, 1, 0, 0, 0, 1}}}),
            (V{1, 1, 1, 1, 1, 1, 1}));
  // r at 3 instead of 6: p at 0 is 3 away, p at 4 is in the future -> false from 3 on.
  EXPECT_EQ(run_discrete("historically({r} -> once[1:2]{p})", {{"p", {1, 0, 0, 0, 1, 0, 0}}, {"r", {0, 1, 1, 1, 0, 0, 0}}}),
            (V{1, 1, 1, 0, 0, 0, 0}));
}

}  // namespace
}  // namespace rvc::engine::discrete
