// Timing atoms and window aggregates (issue 26), hand-computed at the edges:
// closed discrete windows, dense windows (t-b, t-a], ties, empty windows,
// out-of-order stamps, the gap a silent input leaves; the parser's syntax
// and its errors' columns. The Reelay differential test
// (tests/differential/test_timed_vs_reelay.py) covers random traces.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "engine/timed/window_aggregate.hpp"
#include "runtime/pipeline.hpp"
#include "runtime/synced_pipeline.hpp"
#include "spec/parser.hpp"
#include "spec/spec_error.hpp"

namespace rvc {
namespace {

using Func = spec::Timed::Func;
using Verdicts = std::vector<std::pair<double, bool>>;

spec::Bounds window(double lo, double hi) {
  spec::Bounds b;
  b.lo = lo;
  b.hi = hi;
  b.explicit_bounds = true;
  return b;
}

// ---- WindowAggregate ----

TEST(WindowAggregate, DiscreteWindowsAreClosedAtBothEnds) {
  // count[2:4]: at step t the samples of steps t-4 .. t-2.
  engine::timed::WindowAggregate w(Func::Count, window(2, 4), /*dense=*/false);
  std::vector<double> counts;
  for (int t = 0; t < 8; ++t) {
    w.advance(t);
    if (t <= 2) w.add(t, 1);  // samples at steps 0, 1, 2
    counts.push_back(w.value());
  }
  // step:            0  1  2  3  4  5  6  7
  // in the window:   -  -  0  01 012 12 2  -
  EXPECT_EQ(counts, (std::vector<double>{0, 0, 1, 2, 3, 2, 1, 0}));
}

TEST(WindowAggregate, DenseWindowsHoldASampleFromSPlusAUntilSPlusB) {
  engine::timed::WindowAggregate w(Func::Sum, window(0.5, 2), /*dense=*/true);
  w.advance(1);
  w.add(1, 10);
  EXPECT_EQ(w.value(), 0);               // enters at 1.5
  EXPECT_EQ(w.next_change(1), 1.5);
  w.advance(1.5);
  EXPECT_EQ(w.value(), 10);              // s + a: in (closed)
  EXPECT_EQ(w.next_change(1.5), 3);
  w.advance(2.999);
  EXPECT_EQ(w.value(), 10);
  w.advance(3);
  EXPECT_EQ(w.value(), 0);               // s + b: out (the window is (t-b, t-a])
  EXPECT_EQ(w.next_change(3), std::numeric_limits<double>::infinity());
}

TEST(WindowAggregate, EmptyWindowsHaveNoAverageMinimumOrMaximum) {
  for (Func f : {Func::Avg, Func::Min, Func::Max}) {
    engine::timed::WindowAggregate w(f, window(0, 1), true);
    EXPECT_TRUE(std::isnan(w.value()));
    w.add(0, 4);
    EXPECT_EQ(w.value(), 4);
    w.advance(1);
    EXPECT_TRUE(std::isnan(w.value()));
  }
  engine::timed::WindowAggregate sum(Func::Sum, window(0, 1), true);
  EXPECT_EQ(sum.value(), 0);
}

// Against recomputing each window from scratch, over random samples and
// bounds: sums of integers are exact, min/max and averages equal.
TEST(WindowAggregate, EqualsRecomputingTheWindow) {
  std::mt19937 rng(26);
  for (int round = 0; round < 50; ++round) {
    const double lo = rng() % 4, hi = lo + rng() % 20;
    std::vector<std::pair<Func, engine::timed::WindowAggregate>> ws;
    for (Func f : {Func::Count, Func::Sum, Func::Avg, Func::Min, Func::Max})
      ws.emplace_back(f, engine::timed::WindowAggregate(f, window(lo, hi), false));
    std::vector<std::pair<double, double>> samples;
    for (int t = 0; t < 300; ++t) {
      for (auto& [f, w] : ws) w.advance(t);
      if (rng() % 3) {
        const double v = static_cast<double>(static_cast<int>(rng() % 2001) - 1000);
        samples.emplace_back(t, v);
        for (auto& [f, w] : ws) w.add(t, v);
      }
      double n = 0, sum = 0, mn = INFINITY, mx = -INFINITY;
      for (const auto& [s, v] : samples)
        if (s + lo <= t && t <= s + hi) ++n, sum += v, mn = std::min(mn, v), mx = std::max(mx, v);
      for (const auto& [f, w] : ws) {
        const double got = w.value();
        switch (f) {
          case Func::Count: EXPECT_EQ(got, n); break;
          case Func::Sum: EXPECT_EQ(got, sum); break;
          case Func::Avg: if (n) EXPECT_EQ(got, sum / n); else EXPECT_TRUE(std::isnan(got)); break;
          case Func::Min: if (n) EXPECT_EQ(got, mn); else EXPECT_TRUE(std::isnan(got)); break;
          case Func::Max: if (n) EXPECT_EQ(got, mx); else EXPECT_TRUE(std::isnan(got)); break;
        }
      }
    }
  }
}

// ---- Syntax ----

std::string canonical(const std::string& text, bool dense = true) {
  spec::ParseOptions o;
  o.dense = dense;
  return spec::to_string(*spec::parse(text, o));
}

int error_column(const std::string& text, bool dense = true) {
  spec::ParseOptions o;
  o.dense = dense;
  try {
    spec::parse(text, o);
  } catch (const spec::SpecError& e) {
    return e.column();
  }
  ADD_FAILURE() << "no error for " << text;
  return 0;
}

TEST(TimedSyntax, PrintsAndReparses) {
  for (const std::string s :
       {"{steer.@age <= 0.1}", "{@latency < 0.05}", "{count[0:1](steer.@arrived) >= 20}",
        "{avg[0:2](steer.speed) > 3}", "{max(x) == 4}", "{min[1:](pose.x) != -2}", "{sum[:0.5](a[2]) >= 1}"}) {
    const std::string once = canonical(s);
    EXPECT_EQ(canonical(once), once) << s;
  }
  EXPECT_EQ(canonical("{count[0:1](steer.@arrived)>=20}"), "{count[:1](steer.@arrived) >= 20}");
  EXPECT_EQ(canonical("{x.@arrived}", false), "{x.@arrived}");
  // A field named like an aggregate stays a field: {count > 3}, {count[2] > 3}.
  EXPECT_EQ(canonical("{count > 3}"), "{count > 3}");
  EXPECT_EQ(canonical("{count[2] > 3}"), "{count[2] > 3}");
  // A field whose key is "@age" is quoted, and is no timing atom.
  EXPECT_EQ(canonical("{\"@age\" > 3}"), "{\"@age\" > 3}");
  EXPECT_EQ(canonical("{avg(\"@x\") > 3}"), "{avg(\"@x\") > 3}");
  EXPECT_EQ(canonical("{\"@age\".@age > 3}"), "{\"@age\".@age > 3}");
}

TEST(TimedSyntax, ErrorsPointAtTheColumn) {
  EXPECT_EQ(error_column("{x.@arrived}"), 4);                     // dense: an instant
  EXPECT_EQ(error_column("{x.@agee < 1}"), 4);                    // unknown atom
  EXPECT_EQ(error_column("{x.@age}"), 8);                         // needs a comparison
  EXPECT_EQ(error_column("{a.b.@age < 1}"), 6);                   // after an input, not a field
  EXPECT_EQ(error_column("{count[0:1](x.@arrived)}"), 24);        // needs a comparison
  EXPECT_EQ(error_column("{count[0:1](x.@arrived) > yes}"), 27);  // a number
  EXPECT_EQ(error_column("{sum[0:1](x.@arrived) > 1}"), 11);      // arrivals are counted
  EXPECT_EQ(error_column("{avg[0:1](x.@age) > 1}"), 13);          // not of @age
  EXPECT_EQ(error_column("{count[0:1](x.@arrived > 1}"), 24);     // missing ')'
  EXPECT_EQ(error_column("{count[0:1 (x.@arrived) > 1}"), 12);    // missing ']'
  EXPECT_EQ(error_column("{count[0:1.5](x.@arrived) > 1}", false), 10);  // discrete: steps
  EXPECT_EQ(error_column("{x.@latency < 1}", false), 4);          // discrete: no stamps
  spec::ParseOptions robust;
  robust.dense = robust.robustness = true;
  try {
    spec::parse("{x.@age < 1}", robust);
    ADD_FAILURE() << "dense @age with robustness accepted";
  } catch (const spec::SpecError& e) {
    EXPECT_EQ(e.column(), 4);
  }
}

// ---- One input (Pipeline) ----

Verdicts run(const std::string& spec, const std::vector<std::string>& lines, bool dense, std::string* err = nullptr) {
  Verdicts out;
  runtime::PipelineOptions po;
  po.model = dense ? engine::TimeModel::Dense : engine::TimeModel::Discrete;
  po.origin = runtime::Origin::Zero;  // the timeline from 0, as these expectations count it
  po.emit_all = !dense;
  testing::internal::CaptureStderr();
  {
    runtime::Pipeline p({{"p", spec}}, po, [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
    uint64_t n = 0;
    for (const auto& l : lines) p.feed(l, ++n);
  }
  const std::string text = testing::internal::GetCapturedStderr();
  if (err) *err = text;
  return out;
}

TEST(TimedPipeline, AgeFallsAtTheLastMessagePlusTheBoundWithNoMessageThere) {
  // Messages at 0, 1, 1.5, 4: {@age <= 1} is false from 2.5 (1.5 + 1) to 4;
  // a gap of exactly 1 (0 -> 1) is no violation.
  const Verdicts v = run("{@age <= 1}", {R"({"time": 0})", R"({"time": 1})", R"({"time": 1.5})", R"({"time": 4})",
                                         R"({"time": 4.5})"},
                         true);
  EXPECT_EQ(v, (Verdicts{{0, true}, {2.5, false}, {4, true}}));
  // Before the first message the age is infinite.
  EXPECT_EQ(run("{@age > 2}", {R"({"time": 1})", R"({"time": 3.5})", R"({"time": 5})"}, true),
            (Verdicts{{0, true}, {1, false}, {3, true}, {3.5, false}}));
}

TEST(TimedPipeline, DenseCountDropsWhenASampleLeavesAndTiesAtTheEdge) {
  // count[0:1](@arrived) at 0, 0.5, 1 (the first leaves as the third comes:
  // still 2), 1.5 -> 2 (0.5 left), 2 -> ... (1.0 left at 2), 2.5 -> 0, 3
  const Verdicts v = run("{count[0:1](@arrived) >= 2}",
                         {R"({"time": 0})", R"({"time": 0.5})", R"({"time": 1})", R"({"time": 1.5})",
                          R"({"time": 3})", R"({"time": 3.25})"},
                         true);
  // counts: [0,.5):1 [.5,1):2 [1,1.5):2 [1.5,2):2 [2,2.5):1 [2.5,3):0 [3,3.25):1
  EXPECT_EQ(v, (Verdicts{{0, false}, {0.5, true}, {2, false}}));
}

TEST(TimedPipeline, DenseAggregatesOfAFieldSkipMessagesWithoutIt) {
  // max[0:2](x): samples 5@0, (none)@1, 2@1.5; max 5 until 2, then 2 until 3.5.
  const Verdicts v = run("{max[0:2](x) >= 3}",
                         {R"({"time": 0, "x": 5})", R"({"time": 1})", R"({"time": 1.5, "x": 2})", R"({"time": 5})"},
                         true);
  EXPECT_EQ(v, (Verdicts{{0, true}, {2, false}}));
  const Verdicts avg = run("{avg[0:2](x) > 3}",
                           {R"({"time": 0, "x": 5})", R"({"time": 1})", R"({"time": 1.5, "x": 2})", R"({"time": 5})"},
                           true);
  // avg 5 on [0,1.5), 3.5 on [1.5,2), 2 on [2,3.5), empty after: false
  EXPECT_EQ(avg, (Verdicts{{0, true}, {2, false}}));
}

TEST(TimedPipeline, DiscreteWindowsCountSteps) {
  // sum[1:2](x) at step t: x of steps t-2 and t-1.
  const Verdicts v = run("{sum[1:2](x) >= 3}",
                         {R"({"x": 1})", R"({"x": 2})", R"({"x": 0})", R"({"x": 4})", R"({"x": 0})", R"({"x": 0})"},
                         false);
  // sums: -, 1, 3, 2, 4, 4
  EXPECT_EQ(v, (Verdicts{{0, false}, {1, false}, {2, true}, {3, false}, {4, true}, {5, true}}));
  // @age in discrete time counts steps since the input's last message: 0 with one input.
  EXPECT_EQ(run("{@arrived} and {@age == 0}", {"{}", "{}"}, false), (Verdicts{{0, true}, {1, true}}));
}

TEST(TimedPipeline, OutOfOrderStampsAreRejectedAndLeaveTheWindowsAlone) {
  std::string err;
  const Verdicts v = run("{count[0:1](@arrived) <= 2}",
                         {R"({"time": 0})", R"({"time": 0.5})", R"({"time": 0.2})", R"({"time": 0.5})",
                          R"({"time": 0.75})", R"({"time": 3})"},
                         true, &err);
  EXPECT_NE(err.find("line 3"), std::string::npos) << err;
  EXPECT_NE(err.find("line 4"), std::string::npos) << err;  // equal stamps: not after
  // counts: 1 on [0,.5), 2 on [.5,.75), 3 on [.75,1), 2 on [1,1.5), 1, 0
  EXPECT_EQ(v, (Verdicts{{0, true}, {0.75, false}, {1, true}}));
}

TEST(TimedPipeline, LatencyIsArrivalMinusStamp) {
  Verdicts out;
  runtime::PipelineOptions po;
  po.model = engine::TimeModel::Dense;
  po.origin = runtime::Origin::Zero;  // the timeline from 0, as these expectations count it
  runtime::Pipeline p({{"p", "{@latency < 0.1}"}}, po, [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  p.feed_logged(0, R"({"time": 1})", 1, 1.05);
  p.feed_logged(0, R"({"time": 2})", 2, 2.25);  // 0.25 late
  p.feed_logged(0, R"({"time": 3})", 3, 3.0);
  p.feed_logged(0, R"({"time": 4})", 4, 4.0);
  EXPECT_EQ(out, (Verdicts{{0, false}, {1, true}, {2, false}, {3, true}}));
}

TEST(TimedPipeline, NamedAtomsNeedNamedInputs) {
  runtime::PipelineOptions po;
  po.model = engine::TimeModel::Dense;
  try {
    runtime::Pipeline p({{"p", "{a} and {imu.@age < 1}"}}, po, nullptr);
    ADD_FAILURE() << "accepted";
  } catch (const spec::SpecError& e) {
    EXPECT_EQ(e.column(), 10);
  }
}

// ---- Several inputs (SyncedPipeline, merge) ----

Verdicts run_synced(const std::string& spec, bool dense,
                    const std::vector<std::tuple<uint32_t, double, std::string>>& messages) {
  Verdicts out;
  runtime::PipelineOptions po;
  po.model = dense ? engine::TimeModel::Dense : engine::TimeModel::Discrete;
  po.origin = runtime::Origin::Zero;  // the timeline from 0, as these expectations count it
  po.emit_all = !dense;
  runtime::SyncOptions so;
  so.ordered = false;
  runtime::SyncedPipeline p({{"p", spec}}, po, {{"imu", "test:imu", nullptr, ""}, {"odo", "test:odo", nullptr, ""}},
                            so, [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  uint64_t n = 0;
  for (const auto& [input, arrival, json] : messages) p.feed_at(input, json, ++n, arrival);
  p.end_of_input();
  return out;
}

TEST(TimedSynced, AnInputArrivesInTheSetThatUsesItsMessage) {
  const Verdicts v = run_synced("{imu.@arrived}", false,
                                {{0, 0, R"({"time": 0})"},
                                 {1, 0, R"({"time": 1})"},
                                 {1, 0, R"({"time": 2})"},
                                 {0, 0, R"({"time": 3})"},
                                 {0, 0, R"({"time": 3.5})"}});
  // sets: imu@0, odo@1, odo@2, imu@3, imu@3.5
  EXPECT_EQ(v, (Verdicts{{0, true}, {1, false}, {2, false}, {3, true}, {4, true}}));
}

TEST(TimedSynced, InputsWithEqualStampsArriveInTheSameSet) {
  // merge makes one set per stamp: imu and odo both at 1 -> both arrive there; discrete @age counts sets.
  const Verdicts v = run_synced("{imu.@arrived} and {odo.@arrived}", false,
                                {{0, 0, R"({"time": 0})"}, {1, 0, R"({"time": 1})"}, {0, 0, R"({"time": 1})"},
                                 {1, 0, R"({"time": 2})"}});
  EXPECT_EQ(v, (Verdicts{{0, false}, {1, true}, {2, false}}));
  const Verdicts age = run_synced("{imu.@age >= 1}", false,
                                  {{0, 0, R"({"time": 0})"}, {1, 0, R"({"time": 1})"}, {1, 0, R"({"time": 2})"},
                                   {0, 0, R"({"time": 3})"}});
  // sets: imu@0 (age 0), odo@1 (1), odo@2 (2), imu@3 (0)
  EXPECT_EQ(age, (Verdicts{{0, false}, {1, true}, {2, true}, {3, false}}));
}

TEST(TimedSynced, AGapInOneInputIsFoundBetweenTheOthersMessages) {
  std::vector<std::tuple<uint32_t, double, std::string>> m;
  for (double t : {0.0, 0.1, 0.2, 0.6, 0.7}) m.emplace_back(0, t, "{\"time\": " + std::to_string(t) + "}");
  for (double t : {0.05, 0.15, 0.25, 0.35, 0.45, 0.55, 0.65, 0.75})
    m.emplace_back(1, t, "{\"time\": " + std::to_string(t) + "}");
  std::stable_sort(m.begin(), m.end(), [](const auto& a, const auto& b) { return std::get<1>(a) < std::get<1>(b); });
  const Verdicts v = run_synced("{imu.@age <= 0.15} and {count[0:0.3](odo.@arrived) >= 2}", true, m);
  // imu silent from 0.2: false from 0.35 until 0.6. odo's count: 1 on [0.05, 0.15), 2 after.
  EXPECT_EQ(v, (Verdicts{{0, false}, {0.15, true}, {0.35, false}, {0.6, true}}));
}

}  // namespace
}  // namespace rvc
