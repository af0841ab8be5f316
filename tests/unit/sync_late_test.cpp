// Late messages in the merge (issue 25): the wait that adapts to the lateness
// seen, `--late process`, and several files merged by stamp (a k-way merge
// that does not depend on which input is read first). Hand-computed traces.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "runtime/synced_pipeline.hpp"
#include "sync/policy.hpp"
#include "sync/stamp_merge.hpp"
#include "sync_release_recorder.hpp"

namespace rvc {
namespace {

struct Sets : sync::test::ReleaseRecorder {
  std::vector<std::pair<double, std::vector<uint64_t>>> sets;  // stamp, tokens
  void on_set(const sync::Member* members, size_t n, double stamp) override {
    std::vector<uint64_t> tokens;
    for (size_t i = 0; i < n; ++i) tokens.push_back(members[i].token);
    sets.emplace_back(stamp, tokens);
  }
  size_t late() const {
    size_t n = 0;
    for (const auto& [token, why] : released) n += why.first == sync::Release::Late;
    return n;
  }
};

sync::PolicyOptions merge(double max_delay, double adaptive_limit, bool process_late = false) {
  sync::PolicyOptions o;
  o.inputs = 2;
  o.max_delay = max_delay;
  o.adaptive_limit = adaptive_limit;
  o.process_late = process_late;
  return o;
}

// a at 1, 3 (1 goes), b at 0.5 (late: 1 is gone; 2.5 behind the newest), a at 5, 6, b at 4.5.
void feed_jittery(sync::Policy& p) {
  p.add({0, 1, 1});
  p.add({0, 3, 2});
  p.add({1, 0.5, 3});
  p.add({0, 5, 4});
  p.add({0, 6, 5});
  p.add({1, 4.5, 6});
  p.finish();
}

TEST(MergeLate, FixedDelayDropsEveryLateMessage) {
  Sets rec;
  sync::StampMerge p(merge(0, 0), rec);
  feed_jittery(p);
  // 1 out at a@3; b@0.5 late; 3 out at a@5, 5 at a@6; b@4.5 late.
  EXPECT_EQ(rec.late(), 2u);
  EXPECT_EQ(rec.released.at(3).first, sync::Release::Late);
  EXPECT_EQ(rec.released.at(6).first, sync::Release::Late);
}

TEST(MergeLate, AdaptiveDelayLearnsFromTheFirstLateMessage) {
  Sets rec;
  sync::StampMerge p(merge(0, 60), rec);
  feed_jittery(p);
  // b@0.5 is late (2.5 behind): the wait becomes 5. a@5, a@6: watermarks 0
  // and 1, 3 stays; b@4.5 is after the last set (1): kept, and checked in order.
  EXPECT_EQ(rec.late(), 1u);
  EXPECT_EQ(rec.released.at(3).first, sync::Release::Late);
  EXPECT_EQ(rec.released.at(6).first, sync::Release::Used);
  EXPECT_EQ(p.delay(), 0.0);  // finish() starts the next stream afresh
  std::vector<double> stamps;
  for (const auto& s : rec.sets) stamps.push_back(s.first);
  EXPECT_EQ(stamps, (std::vector<double>{1, 3, 4.5, 5, 6}));
}

TEST(MergeLate, AdaptiveDelayStopsAtItsLimit) {
  Sets rec;
  sync::StampMerge p(merge(0, 5), rec);
  p.add({0, 0, 1});
  p.add({0, 100, 2});  // 0 goes
  p.add({1, 10, 3});   // lateness 90: the wait would be 180, the limit is 5
  EXPECT_EQ(p.delay(), 5.0);
}

TEST(MergeLate, ProcessLateChecksItAsTheNextEvent) {
  Sets rec;
  sync::StampMerge p(merge(0, 0, true), rec);
  feed_jittery(p);
  EXPECT_EQ(rec.late(), 0u);
  // b@0.5 comes after the set at 1: a set of its own just above 1; b@4.5
  // after the set at 5: just above 5. Every message is used exactly once.
  ASSERT_EQ(rec.sets.size(), 6u);
  EXPECT_EQ(rec.sets[1].first, std::nextafter(1.0, 2.0));
  EXPECT_EQ(rec.sets[1].second, (std::vector<uint64_t>{3}));
  EXPECT_EQ(rec.sets[4].first, std::nextafter(5.0, 6.0));
  EXPECT_EQ(rec.sets[4].second, (std::vector<uint64_t>{6}));
  for (size_t i = 1; i < rec.sets.size(); ++i) EXPECT_LT(rec.sets[i - 1].first, rec.sets[i].first);
  for (uint64_t token = 1; token <= 6; ++token) {
    EXPECT_EQ(rec.releases_of(token), 1) << token;
    EXPECT_EQ(rec.released.at(token).first, sync::Release::Used) << token;
  }
}

TEST(MergeLate, TwoLateMessagesOfOneInputAreBothChecked) {
  Sets rec;
  sync::StampMerge p(merge(0, 0, true), rec);
  p.add({0, 1, 1});
  p.add({0, 5, 2});  // 1 goes
  p.add({1, 0.5, 3});
  p.add({1, 0.7, 4});  // must not replace the first late one
  p.finish();
  EXPECT_EQ(rec.released.at(3).first, sync::Release::Used);
  EXPECT_EQ(rec.released.at(4).first, sync::Release::Used);
  EXPECT_EQ(rec.sets.size(), 4u);
}

// ---- files merged by stamp (SyncOptions::ordered) ----

using Lines = std::vector<std::string>;

struct OrderedRun {
  std::vector<std::pair<double, bool>> verdicts;
  uint64_t sets = 0, rejected = 0, late = 0;
  std::string err;
};

// Feeds two "files" the way the monitor loop reads them: the input the
// pipeline asks for next, one line at a time.
OrderedRun run_ordered(const Lines& a, const Lines& b, bool dense) {
  OrderedRun out;
  runtime::PipelineOptions po;
  po.emit_all = true;
  po.model = dense ? engine::TimeModel::Dense : engine::TimeModel::Discrete;
  runtime::SyncOptions so;
  so.ordered = true;
  testing::internal::CaptureStderr();
  {
    runtime::SyncedPipeline p({{"p", "{a.x} -> {b.y > 2}"}}, po, {{"a", "file:a", nullptr, ""}, {"b", "file:b", nullptr, ""}},
                              so, [&](const engine::Verdict& v) { out.verdicts.emplace_back(v.time, v.value); });
    EXPECT_TRUE(p.reads_in_order());
    const Lines* files[2] = {&a, &b};
    size_t next[2] = {0, 0};
    for (int input; (input = p.next_input()) >= 0;) {
      const Lines& lines = *files[input];
      if (next[input] == lines.size()) {
        p.input_ended(static_cast<uint32_t>(input));
        continue;
      }
      p.feed_at(static_cast<uint32_t>(input), lines[next[input]], next[input] + 1, 0);
      ++next[input];
    }
    p.end_of_input();
    out.sets = p.sets();
    out.rejected = p.stats().rejected;
    out.late = p.counters(0).released[static_cast<size_t>(sync::Release::Late)] +
               p.counters(1).released[static_cast<size_t>(sync::Release::Late)];
    p.finish_report();
  }
  out.err = testing::internal::GetCapturedStderr();
  return out;
}

TEST(MergeFiles, ReadInStampOrderWhateverTheirLengths) {
  // a is far "ahead" (all its stamps first in the file), b's come between
  // them: read as two racing threads, most of b would be late.
  Lines a, b;
  for (int t = 0; t < 50; ++t) a.push_back("{\"x\": " + std::string(t % 7 == 3 ? "true" : "false") +
                                           ", \"time\": " + std::to_string(2 * t) + "}");
  for (int t = 0; t < 50; ++t) b.push_back("{\"y\": " + std::to_string(t % 5) + ", \"time\": " + std::to_string(2 * t + 1) + "}");
  for (bool dense : {false, true}) {
    const OrderedRun r = run_ordered(a, b, dense);
    EXPECT_EQ(r.late, 0u) << r.err;
    EXPECT_EQ(r.rejected, 0u) << r.err;
    EXPECT_EQ(r.sets, 100u);  // every message its own event
  }
}

TEST(MergeFiles, AStampThatGoesBackIsRejectedAtItsLine) {
  const Lines a = {R"({"x": false, "time": 1})", R"({"x": true, "time": 4})", R"({"x": false, "time": 3})",
                   R"({"x": true, "time": 5})"};
  const Lines b = {R"({"y": 3, "time": 2})", R"({"y": 1, "time": 6})"};
  const OrderedRun r = run_ordered(a, b, false);
  EXPECT_EQ(r.rejected, 1u);
  EXPECT_EQ(r.late, 0u);
  EXPECT_EQ(r.sets, 5u);
  EXPECT_NE(r.err.find("input a line 3: stamp 3 is before the previous message's 4"), std::string::npos) << r.err;
  // Events at 1 (a), 2 (b), 4 (a), 5 (a), 6 (b): p = a.x -> b.y > 2; false
  // only at 6, where b.y is 1 and a.x still true.
  const std::vector<std::pair<double, bool>> want = {{0, true}, {1, true}, {2, true}, {3, true}, {4, false}};
  EXPECT_EQ(r.verdicts, want);
}

}  // namespace
}  // namespace rvc

namespace rvc {
namespace {

// Live publishers that start apart: a's whole stream before b's first
// message. Waiting for every input, nothing is late; without, all of b is.
TEST(MergeWait, APublisherThatStartsLateLosesNothing) {
  for (bool wait : {false, true}) {
    Sets rec;
    sync::PolicyOptions o = merge(0, 60);
    o.wait_for_inputs = wait;
    sync::StampMerge p(o, rec);
    uint64_t token = 0;
    for (int k = 0; k < 100; ++k) p.add({0, static_cast<double>(k), ++token});
    EXPECT_EQ(p.held(), wait ? 100u : 1u);
    for (int k = 0; k < 100; ++k) p.add({1, k + 0.5, ++token});
    p.finish();
    // Without waiting: a's 0..98 are out, b's 0.5..97.5 late (98), 98.5 and 99.5 in time.
    EXPECT_EQ(rec.late(), wait ? 0u : 98u);
    EXPECT_EQ(rec.sets.size(), wait ? 200u : 102u);
  }
}

TEST(MergeWait, ASilentOrEndedInputIsNoLongerWaitedFor) {
  Sets rec;
  sync::PolicyOptions o = merge(0, 0);
  o.wait_for_inputs = true;
  sync::StampMerge p(o, rec);
  p.add({0, 1, 1});
  p.add({0, 2, 2});
  EXPECT_TRUE(rec.sets.empty());  // b has said nothing yet
  p.exclude(1, true);             // b silent (--dead-after) or ended
  EXPECT_EQ(rec.sets.size(), 1u);  // 1 goes; 2 waits for a later stamp, as without waiting
  p.exclude(1, false);            // b is back: wait for it again
  p.add({0, 3, 3});
  EXPECT_EQ(rec.sets.size(), 1u);
  p.add({1, 2.5, 4});
  EXPECT_EQ(rec.sets.size(), 2u);  // 2 < min(3, 2.5)
  p.finish();
  EXPECT_EQ(rec.late(), 0u);
}

TEST(MergeWait, HeldMessagesAreBounded) {
  Sets rec;
  sync::PolicyOptions o = merge(0, 0);
  o.wait_for_inputs = true;
  o.max_held = 10;
  sync::StampMerge p(o, rec);
  for (int k = 0; k < 50; ++k) p.add({0, static_cast<double>(k), static_cast<uint64_t>(k + 1)});
  EXPECT_EQ(p.held(), 10u);
  EXPECT_EQ(rec.sets.size(), 40u);
}

}  // namespace
}  // namespace rvc
