// Dense-time operators (src/engine/dense): Signal and zip, then Once,
// Historically and Since on hand-built piecewise-constant signals, directly
// and through a compiled monitor. Signals are right-open: a piece (t, v)
// holds on [t, next piece) and the last one until the segment's end.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "engine/dense/historically.hpp"
#include "engine/dense/once.hpp"
#include "engine/dense/signal.hpp"
#include "engine/dense/since.hpp"
#include "engine/explain.hpp"
#include "test_util.hpp"

namespace rvc::engine::dense {
namespace {

using test::DenseMsg;
using test::run_dense;
using test::TV;
using TVs = std::vector<TV>;

Signal sig(const TVs& pieces) {
  Signal s;
  for (const auto& [t, v] : pieces) s.pieces.push_back({t, v});
  return s;
}
TVs pieces(const Signal& s) {
  TVs out;
  for (const Piece& p : s.pieces) out.emplace_back(p.t, p.v);
  return out;
}

// ---------------------------------------------------------------- Signal

TEST(DenseSignal, SetKeepsPiecesNormalized) {
  Signal s;
  s.set(0, false);
  s.set(1, false);  // same value: no new piece
  EXPECT_EQ(pieces(s), (TVs{{0, false}}));
  s.set(1, true);
  EXPECT_EQ(pieces(s), (TVs{{0, false}, {1, true}}));
  s.set(1, false);  // replaces the zero-length piece at 1, and merges with (0, F)
  EXPECT_EQ(pieces(s), (TVs{{0, false}}));
  s.set(2, true);
  s.set(3, false);
  EXPECT_EQ(pieces(s), (TVs{{0, false}, {2, true}, {3, false}}));
  s.constant(5, true);
  EXPECT_EQ(pieces(s), (TVs{{5, true}}));
  Signal z;
  z.set(0, false);
  z.set(0, true);  // a zero-length first piece is replaced
  EXPECT_EQ(pieces(z), (TVs{{0, true}}));
}

TEST(DenseSignal, ZipVisitsEveryChangeOfEitherSignalOnce) {
  Signal a = sig({{0, false}, {1, true}, {2.5, false}});
  Signal b = sig({{0, true}, {1, false}, {2, true}});
  std::vector<std::tuple<double, bool, bool>> seen;
  zip(a, b, [&](double t, bool l, bool r) { seen.emplace_back(t, l, r); });
  // 0: (F,T); 1: both change -> one call (T,F); 2: b -> (T,T); 2.5: a -> (F,T).
  std::vector<std::tuple<double, bool, bool>> expected = {
      {0, false, true}, {1, true, false}, {2, true, true}, {2.5, false, true}};
  EXPECT_EQ(seen, expected);
}

TEST(DenseSignal, ZipWithAConstant) {
  Signal a = sig({{3, true}});
  Signal b = sig({{3, false}, {3.5, true}, {4, false}});
  std::vector<std::tuple<double, bool, bool>> seen;
  zip(a, b, [&](double t, bool l, bool r) { seen.emplace_back(t, l, r); });
  std::vector<std::tuple<double, bool, bool>> expected = {{3, true, false}, {3.5, true, true}, {4, true, false}};
  EXPECT_EQ(seen, expected);
}

// ---------------------------------------------------------------- Once

TEST(DenseOnce, RightOpenShift) {
  // p true on [0,1) => once[1:2] p true on [1, 1+2) = [1,3).
  EXPECT_EQ(run_dense("once[1:2] {p}", {{0, {{"p", 1}}}, {1, {{"p", 0}}}}, 5), (TVs{{0, false}, {1, true}, {3, false}}));
}

TEST(DenseOnce, ChangePointsInsideASegment) {
  Once once{1, 1, {}};
  Signal out;
  // Input over [0,3): T on [0,0.5), F on [0.5,1.5), T on [1.5,3).
  // Shifted by exactly 1: T on [1,1.5) and from 2.5 (until 4, known so far).
  once.update(sig({{0, true}, {0.5, false}, {1.5, true}}), 3, out);
  EXPECT_EQ(pieces(out), (TVs{{0, false}, {1, true}, {1.5, false}, {2.5, true}}));
  // Next segment [3,5), input false: the pending [2.5,4) still shows on [3,4).
  once.update(sig({{3, false}}), 5, out);
  EXPECT_EQ(pieces(out), (TVs{{3, true}, {4, false}}));
  // Nothing left after 4.
  once.update(sig({{5, false}}), 6, out);
  EXPECT_EQ(pieces(out), (TVs{{5, false}}));
}

TEST(DenseOnce, Unbounded) {
  Once once;
  Signal out;
  once.update(sig({{0, false}, {2, true}}), 3, out);
  EXPECT_EQ(pieces(out), (TVs{{0, false}, {2, true}}));
  once.update(sig({{3, false}}), 10, out);  // stays true forever
  EXPECT_EQ(pieces(out), (TVs{{3, true}}));
}

TEST(DenseOnce, ZeroZeroIsTheInput) {
  Once once{0, 0, {}};
  Signal out;
  once.update(sig({{0, true}, {1, false}, {1.75, true}}), 2, out);
  EXPECT_EQ(pieces(out), (TVs{{0, true}, {1, false}, {1.75, true}}));
}

TEST(DenseOnce, LowerAndUpperOnly) {
  // p true on [1,2) (messages at 0, 1, 2).
  std::vector<DenseMsg> msgs = {{0, {{"p", 0}}}, {1, {{"p", 1}}}, {2, {{"p", 0}}}};
  // [3:] -> true from 1+3 = 4 on.
  EXPECT_EQ(run_dense("once[3:] {p}", msgs, 10), (TVs{{0, false}, {4, true}}));
  // [:0.5] -> true on [1, 2.5).
  EXPECT_EQ(run_dense("once[:0.5] {p}", msgs, 10), (TVs{{0, false}, {1, true}, {2.5, false}}));
}

TEST(DenseOnce, LargeBoundQueueStaysAtOne) {
  // once[0:1000] over 5000 unit segments, p true on every third one: two live
  // windows [x, y+1000) can never be disjoint, so at most one is queued.
  Once once{0, 1000, {}};
  Signal out;
  size_t max_size = 0;
  for (int k = 0; k < 5000; ++k) {
    bool p = k % 3 == 0 && k < 2000;
    once.update(sig({{double(k), p}}), k + 1, out);
    max_size = std::max(max_size, once.window.size());
    // The last p segment starting at or before k is [j, j+1) with j <= 1998:
    // once is true on [j, j+1001). For k >= 2000 that is k < 2998 + 1001.
    bool expected = k < 1998 + 1001;
    ASSERT_EQ(pieces(out), (TVs{{double(k), expected}})) << k;
  }
  EXPECT_LE(max_size, 1u);
}

// ---------------------------------------------------------------- Historically

TEST(DenseHistorically, WindowWithVacuousStart) {
  // p false only on [3,4): historically[1:2] p is false on [3+1, 4+2) = [4,6);
  // before t = 1 the window lies before 0 and holds vacuously.
  EXPECT_EQ(run_dense("historically[1:2] {p}", {{0, {{"p", 1}}}, {3, {{"p", 0}}}, {4, {{"p", 1}}}}, 10),
            (TVs{{0, true}, {4, false}, {6, true}}));
}

TEST(DenseHistorically, Unbounded) {
  EXPECT_EQ(run_dense("historically {p}", {{0, {{"p", 1}}}, {2, {{"p", 0}}}, {3, {{"p", 1}}}}, 5),
            (TVs{{0, true}, {2, false}}));
}

TEST(DenseHistorically, FalseAtZeroSeenFromTheLowerBound) {
  // p false on [0,1): historically[2:] p false from 0+2 on, true before.
  EXPECT_EQ(run_dense("historically[2:] {p}", {{0, {{"p", 0}}}, {1, {{"p", 1}}}}, 5), (TVs{{0, true}, {2, false}}));
}

TEST(DenseHistorically, DirectWithInsideChanges) {
  Historically h;
  h.violations.lo = 0.5;
  h.violations.hi = 1;
  Signal out;
  // p false on [1,1.25) inside the segment [0,4): false on [1.5, 2.25).
  h.update(sig({{0, true}, {1, false}, {1.25, true}}), 4, out);
  EXPECT_EQ(pieces(out), (TVs{{0, true}, {1.5, false}, {2.25, true}}));
}

// ---------------------------------------------------------------- Since

TEST(DenseSince, LeftFalsePieceIsFalseEvenForZeroLowerBound) {
  // [0,2): a false, b true -> false (Reelay's rule, even with a = 0), and a
  // candidate at the piece's right end 2. [2,4): a true -> true from 2.
  EXPECT_EQ(run_dense("{a} since {b}", {{0, {{"a", 0}, {"b", 1}}}, {2, {{"a", 1}, {"b", 0}}}}, 4),
            (TVs{{0, false}, {2, true}}));
}

TEST(DenseSince, RightEndCandidateIsShiftedByTheBounds) {
  // Same trace, since[1:2]: the candidate at 2 becomes [2+1, 2+2) = [3,4).
  EXPECT_EQ(run_dense("{a} since[1:2] {b}", {{0, {{"a", 0}, {"b", 1}}}, {2, {{"a", 1}, {"b", 0}}}}, 6),
            (TVs{{0, false}, {3, true}, {4, false}}));
}

TEST(DenseSince, RightEndCandidateDiesWithTheNextLeftFalsePiece) {
  // [0,2): a F, b T -> candidate at 2. [2,3): a F, b F -> dropped, none left.
  // [3,5): a T, b F -> nothing to continue: false throughout.
  EXPECT_EQ(run_dense("{a} since {b}",
                      {{0, {{"a", 0}, {"b", 1}}}, {2, {{"a", 0}, {"b", 0}}}, {3, {{"a", 1}, {"b", 0}}}}, 5),
            (TVs{{0, false}}));
}

TEST(DenseSince, BoundedChangePointsInsideASegment) {
  // a always; b true on [0,0.5) only: since[1:2] true on [0+1, 0.5+2) = [1,2.5),
  // both ends inside the segment [0.5,4).
  EXPECT_EQ(run_dense("{a} since[1:2] {b}", {{0, {{"a", 1}, {"b", 1}}}, {0.5, {{"a", 1}, {"b", 0}}}}, 4),
            (TVs{{0, false}, {1, true}, {2.5, false}}));
  // a fails at 2: cut short there.
  EXPECT_EQ(run_dense("{a} since[1:2] {b}",
                      {{0, {{"a", 1}, {"b", 1}}}, {0.5, {{"a", 1}, {"b", 0}}}, {2, {{"a", 0}, {"b", 0}}}}, 4),
            (TVs{{0, false}, {1, true}, {2, false}}));
}

TEST(DenseSince, LeftOperandChangingInsideASegment) {
  // once[0:1]{a} is true on [0,2) (a true on [0,1)), so the left operand of
  // since falls at 2, inside the segment [1,3): true on [0,2), false after.
  EXPECT_EQ(run_dense("(once[0:1]{a}) since {b}",
                      {{0, {{"a", 1}, {"b", 1}}}, {0.5, {{"a", 1}, {"b", 0}}}, {1, {{"a", 0}, {"b", 0}}}}, 3),
            (TVs{{0, true}, {2, false}}));
}

TEST(DenseSince, DirectPiecesWithinOneSegment) {
  Since s;
  Signal out;
  // Over [0,3): left T on [0,1), F on [1,2), T on [2,3); right T on [0.5,1.5).
  //   [0,0.5)  left T, right F, no candidate    -> F
  //   [0.5,1)  left T, right T                  -> T (candidate from 0.5)
  //   [1,1.5)  left F, right T                  -> F, candidate at 1.5
  //   [1.5,2)  left F, right F                  -> F, candidates dropped
  //   [2,3)    left T, right F, no candidate    -> F
  s.update(sig({{0, true}, {1, false}, {2, true}}), sig({{0, false}, {0.5, true}, {1.5, false}}), 3, out);
  EXPECT_EQ(pieces(out), (TVs{{0, false}, {0.5, true}, {1, false}}));
}

TEST(DenseSince, DirectRightHoldingAcrossALeftFailure) {
  Since s;
  Signal out;
  // Left T, F on [1,2), T; right T from 0.5 on.
  //   [1,2) left F, right T -> F, candidate at 2; [2,3) left T, right T -> T.
  s.update(sig({{0, true}, {1, false}, {2, true}}), sig({{0, false}, {0.5, true}}), 3, out);
  EXPECT_EQ(pieces(out), (TVs{{0, false}, {0.5, true}, {1, false}, {2, true}}));
}

TEST(DenseSince, DirectBoundedWindowAcrossSegments) {
  Since s;
  s.lo = 0.5;
  s.hi = 1;
  Signal out;
  // Segment [0,0.25): both true -> candidate [0.5, 1.25); output F.
  s.update(sig({{0, true}}), sig({{0, true}}), 0.25, out);
  EXPECT_EQ(pieces(out), (TVs{{0, false}}));
  // Segment [0.25,2): left T, right F -> the candidate shows on [0.5,1.25).
  s.update(sig({{0.25, true}}), sig({{0.25, false}}), 2, out);
  EXPECT_EQ(pieces(out), (TVs{{0.25, false}, {0.5, true}, {1.25, false}}));
}

// ---------------------------------------------------------------- monitor

TEST(DenseMonitor, BooleanOfShiftedSignals) {
  // q always; once[1:2] p true on [1,3) -> the conjunction changes at 1 and 3,
  // inside the segment [1,4).
  EXPECT_EQ(run_dense("{q} and once[1:2]{p}", {{0, {{"p", 1}, {"q", 1}}}, {1, {{"p", 0}, {"q", 1}}}}, 4),
            (TVs{{0, false}, {1, true}, {3, false}}));
  // Shifting again by 0.5 moves both change points.
  EXPECT_EQ(run_dense("once[0.5:0.5] once[1:2]{p}", {{0, {{"p", 1}}}, {1, {{"p", 0}}}}, 5),
            (TVs{{0, false}, {1.5, true}, {3.5, false}}));
  // not / or / implies of inside change points.
  EXPECT_EQ(run_dense("not once[1:2]{p} or {q}", {{0, {{"p", 1}, {"q", 0}}}, {1, {{"p", 0}, {"q", 0}}}}, 5),
            (TVs{{0, true}, {1, false}, {3, true}}));
  EXPECT_EQ(run_dense("once[1:2]{p} -> {q}", {{0, {{"p", 1}, {"q", 0}}}, {1, {{"p", 0}, {"q", 0}}}}, 5),
            (TVs{{0, true}, {1, false}, {3, true}}));
}

TEST(DenseMonitor, EmitAllReportsEveryPiece) {
  // p constant true over three segments: condensed reports once, all three times.
  std::vector<DenseMsg> msgs = {{0, {{"p", 1}}}, {1, {{"p", 1}}}, {2.5, {{"p", 1}}}};
  EXPECT_EQ(run_dense("{p}", msgs, 4), (TVs{{0, true}}));
  EXPECT_EQ(run_dense("{p}", msgs, 4, /*emit_all=*/true), (TVs{{0, true}, {1, true}, {2.5, true}}));
}

// ---------------------------------------------------------------- --explain

// The explanations of `spec` over `msgs` (run_dense's trace): (time, sentences)
// per violation start. Also checks that --explain changes no verdict.
using Explained = std::vector<std::pair<double, std::vector<std::string>>>;
Explained explain_dense(const std::string& spec, const std::vector<DenseMsg>& msgs, double end) {
  Explained out;
  TVs verdicts;
  engine::Checker checker(engine::TimeModel::Dense, false, [&](const engine::Verdict& v) {
    verdicts.emplace_back(v.time, v.value);
    EXPECT_EQ(v.explanation != nullptr, !v.value) << "at " << v.time;  // every change to false, only those
    if (v.explanation) out.emplace_back(v.time, *v.explanation);
  });
  checker.enable_explain();
  checker.add_property({"p", spec});
  std::vector<uint8_t> values(checker.atoms().size(), 0);
  for (size_t i = 0; i < msgs.size(); ++i) {
    for (const auto& [name, v] : msgs[i].values) values[test::atom_index(checker, name)] = static_cast<uint8_t>(v);
    checker.step(msgs[i].time, i + 1 < msgs.size() ? msgs[i + 1].time : end, values.data());
  }
  EXPECT_EQ(verdicts, run_dense(spec, msgs, end)) << spec;
  return out;
}

TEST(DenseExplain, BoundedOnceTurningFalseInsideASegment) {
  // brake on [0, 1), then off: once[0:1.5] holds until 1 + 1.5 = 2.5, inside the segment [2, 5).
  EXPECT_EQ(explain_dense("once[0:1.5]{brake}", {{0, {{"brake", 1}}}, {1, {{"brake", 0}}}, {2, {{"brake", 0}}}}, 5),
            (Explained{{2.5,
                        {"(once[:1.5] {brake}) is false: {brake} never held in [1, 2.5]",
                         "{brake} is false throughout [2, 5)"}}}));
}

TEST(DenseExplain, HistoricallyOfAnImplicationFollowsTheFailingMoment) {
  // e from 1 on; h on [1, 2) only: once[0:1]{h} holds on [1, 3), so the implication fails at 3 and
  // historically with it; the reasons are read at 3, inside the segment [2, 4).
  EXPECT_EQ(explain_dense("historically({e} -> once[0:1]{h})",
                          {{0, {{"e", 0}, {"h", 0}}}, {1, {{"e", 1}, {"h", 1}}}, {2, {{"e", 1}, {"h", 0}}}}, 4),
            (Explained{{3,
                        {"(historically ({e} implies (once[:1] {h}))) is false: ({e} implies (once[:1] {h})) failed "
                         "at least once in [0, 3]",
                         "{e} is true throughout [2, 4)", "(once[:1] {h}) is false: {h} never held in [2, 3]",
                         "{h} is false throughout [2, 4)"}}}));
}

TEST(DenseExplain, HistoricallyBoundedNamesItsWindow) {
  // p false on [1, 2): historically[1:2]{p} reads [t-2, t-1], so it is false on [2, 4). Its
  // lower bound is not 0: the cause lies in the window, not now, and the walk stops there.
  EXPECT_EQ(explain_dense("historically[1:2]{p}", {{0, {{"p", 1}}}, {1, {{"p", 0}}}, {2, {{"p", 1}}}}, 6),
            (Explained{{2, {"(historically[1:2] {p}) is false: {p} failed at least once in [0, 1]"}}}));
  // Lower bound 0 and failing now: the atom that broke it.
  EXPECT_EQ(explain_dense("historically[0:2]{p}", {{0, {{"p", 1}}}, {1.5, {{"p", 0}}}}, 3),
            (Explained{{1.5,
                        {"(historically[:2] {p}) is false: {p} failed at least once in [0, 1.5]",
                         "{p} is false throughout [1.5, 3)"}}}));
}

TEST(DenseExplain, UnboundedOnceSinceAndBooleans) {
  // q from 1 on, p never: the implication fails at 1; once{p} looks at everything since 0.
  EXPECT_EQ(explain_dense("{q} -> once{p}", {{0, {{"q", 0}, {"p", 0}}}, {1, {{"q", 1}, {"p", 0}}}}, 3),
            (Explained{{1,
                        {"{q} is true throughout [1, 3)", "(once {p}) is false: {p} never held in [0, 1]",
                         "{p} is false throughout [1, 3)"}}}));
  // not/or/and: only the deciding operands (c, not b, for the false conjunction).
  EXPECT_EQ(explain_dense("not {a} or ({b} and {c})",
                          {{0, {{"a", 0}, {"b", 0}, {"c", 0}}}, {2, {{"a", 1}, {"b", 1}, {"c", 0}}}}, 3),
            (Explained{{2, {"{a} is true throughout [2, 3)", "{c} is false throughout [2, 3)"}}}));
  // since[1:2]: b on [0, 1) makes it true on [1, 3) while a holds. False at 0 (the window is
  // still before time 0) and from 3 (b's moment left the window [t-2, t-1]).
  EXPECT_EQ(explain_dense("{a} since[1:2] {b}", {{0, {{"a", 1}, {"b", 1}}}, {1, {{"a", 1}, {"b", 0}}}}, 5),
            (Explained{{0, {"({a} since[1:2] {b}) is false: {b} never held at no time yet with {a} holding from "
                            "then until now"}},
                       {3, {"({a} since[1:2] {b}) is false: {b} never held in [1, 2] with {a} holding from then "
                            "until now"}}}));
  // The left side failing now ends since: the walk follows it.
  EXPECT_EQ(explain_dense("{a} since {b}", {{0, {{"a", 1}, {"b", 1}}}, {1, {{"a", 1}, {"b", 0}}},
                                            {2.25, {{"a", 0}, {"b", 0}}}}, 4),
            (Explained{{2.25,
                        {"({a} since {b}) is false: {b} never held in [0, 2.25] with {a} holding from then until now",
                         "{a} is false throughout [2.25, 4)"}}}));
}

TEST(DenseExplain, ShortTimes) {
  EXPECT_EQ(engine::explain::seconds(3.3 - 1.5), "1.8");
  EXPECT_EQ(engine::explain::seconds(2.5), "2.5");
  EXPECT_EQ(engine::explain::seconds(0), "0");
  EXPECT_EQ(engine::explain::seconds(1795400000.125), "1795400000.125");
}

}  // namespace
}  // namespace rvc::engine::dense
