// StampMerge ("merge"): hand-computed traces (watermark, equal stamps as one
// set, Replaced, Late, advance, finish) and a randomized comparison with a
// direct model of the contract (an ordered map), which also checks the order
// of the sets and that every message is released exactly once.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <vector>

#include "sync/policy.hpp"
#include "sync_release_recorder.hpp"

namespace rvc::sync {
namespace {

struct SetOut {
  std::vector<std::pair<uint32_t, uint64_t>> members;  // (input, token)
  double stamp;
  size_t step;
  bool operator==(const SetOut&) const = default;
};

struct Recorder : test::ReleaseRecorder {
  std::vector<SetOut> sets;
  void on_set(const Member* members, size_t n, double set_stamp) override {
    SetOut s{{}, set_stamp, step};
    for (size_t i = 0; i < n; ++i) {
      EXPECT_EQ(members[i].stamp, set_stamp);
      s.members.emplace_back(members[i].input, members[i].token);
    }
    sets.push_back(s);
  }
};

using R = std::pair<Release, size_t>;

PolicyOptions merge_opts(size_t inputs, double max_delay) {
  PolicyOptions o;
  o.inputs = inputs;
  o.max_delay = max_delay;
  return o;
}

TEST(StampMerge, HandTraceMaxDelayZero) {
  Recorder rec;
  auto p = make_policy(PolicyKind::Merge, merge_opts(2, 0), rec);
  auto add = [&](size_t step, uint32_t input, double stamp) {
    rec.step = step;
    p->add(Member{input, stamp, step});
  };
  add(0, 0, 1.0);
  add(1, 1, 1.0);  // same stamp, other input: same set, still held (1.0 is not below the watermark 1.0)
  EXPECT_EQ(p->held(), 2u);
  EXPECT_TRUE(rec.sets.empty());
  add(2, 0, 2.0);  // watermark 2.0: 1.0 goes, both inputs in one set
  add(3, 1, 1.5);  // after the last set (1.0) but below the watermark: out at once, alone
  add(4, 0, 1.5);  // not after the last set (1.5): Late
  add(5, 1, 2.0);
  add(6, 0, 2.0);  // input 0 at 2.0 again: replaces message 2
  EXPECT_EQ(p->held(), 2u);
  rec.step = 7;
  p->advance(1.0);  // behind the watermark: nothing
  EXPECT_EQ(rec.sets.size(), 2u);
  p->advance(2.5);  // watermark 2.5: the set at 2.0
  EXPECT_EQ(p->held(), 0u);
  rec.step = 8;
  p->finish();
  EXPECT_EQ(rec.sets, (std::vector<SetOut>{{{{0, 0}, {1, 1}}, 1.0, 2},
                                           {{{1, 3}}, 1.5, 3},
                                           {{{0, 6}, {1, 5}}, 2.0, 7}}));
  EXPECT_EQ(rec.released[4], R(Release::Late, 4));
  EXPECT_EQ(rec.released[2], R(Release::Replaced, 6));
  EXPECT_EQ(rec.released[0], R(Release::Used, 2));
  for (uint64_t t = 0; t < 7; ++t) EXPECT_EQ(rec.count[t], 1) << t;
}

TEST(StampMerge, MaxDelayIsStrictAndFinishReleasesInOrder) {
  Recorder rec;
  auto p = make_policy(PolicyKind::Merge, merge_opts(3, 0.5), rec);
  std::vector<std::pair<uint32_t, double>> in = {{0, 1.0}, {1, 3.0}, {2, 1.2}, {0, 1.5}, {2, 1.0}, {1, 2.5}};
  for (size_t k = 0; k < in.size(); ++k) {
    rec.step = k;
    p->add(Member{in[k].first, in[k].second, k});
  }
  // 3.0 at step 1: watermark 2.5, 1.0 goes. 1.2 and 1.5 arrive below the
  // watermark and go at once; 2.5 arrives exactly at it: held.
  ASSERT_EQ(rec.sets.size(), 3u);
  EXPECT_EQ(rec.sets[0], (SetOut{{{0, 0}}, 1.0, 1}));  // message 4 (input 2 at 1.0) came later: Late
  EXPECT_EQ(rec.sets[1], (SetOut{{{2, 2}}, 1.2, 2}));
  EXPECT_EQ(rec.sets[2], (SetOut{{{0, 3}}, 1.5, 3}));
  EXPECT_EQ(rec.released[4], R(Release::Late, 4));
  EXPECT_EQ(p->held(), 2u);
  rec.step = 6;
  p->advance(3.0);  // watermark stays 2.5: 2.5 is not below it
  EXPECT_EQ(rec.sets.size(), 3u);
  p->finish();
  ASSERT_EQ(rec.sets.size(), 5u);
  EXPECT_EQ(rec.sets[3], (SetOut{{{1, 5}}, 2.5, 6}));
  EXPECT_EQ(rec.sets[4], (SetOut{{{1, 1}}, 3.0, 6}));
  EXPECT_EQ(p->held(), 0u);
}

TEST(StampMerge, EqualStampsOutOfOrderWithinAnInput) {
  // Input 0 sends 5, then 4, then 4 again while 4 is still pending: the walk
  // over the group (not the in-order fast path) finds and replaces it.
  Recorder rec;
  auto p = make_policy(PolicyKind::Merge, merge_opts(2, 10), rec);
  p->add(Member{0, 5, 0});
  p->add(Member{1, 4, 1});
  p->add(Member{0, 4, 2});
  p->add(Member{0, 4, 3});
  EXPECT_EQ(rec.released[2].first, Release::Replaced);
  EXPECT_EQ(p->held(), 3u);
  p->finish();
  EXPECT_EQ(rec.sets, (std::vector<SetOut>{{{{0, 3}, {1, 1}}, 4, 0}, {{{0, 0}}, 5, 0}}));
}

TEST(StampMerge, ManyPendingStamps) {
  // An unbounded delay holds everything: 5000 distinct stamps (the hash
  // grows, and shrinks by erasure on release) come out in order at finish.
  Recorder rec;
  auto p = make_policy(PolicyKind::Merge, merge_opts(3, std::numeric_limits<double>::infinity()), rec);
  std::mt19937 rng(3);
  std::vector<double> stamps;
  for (int k = 0; k < 5000; ++k) stamps.push_back(k * 0.001);
  std::shuffle(stamps.begin(), stamps.end(), rng);
  for (size_t k = 0; k < stamps.size(); ++k) p->add(Member{static_cast<uint32_t>(k % 3), stamps[k], k});
  EXPECT_EQ(p->held(), 5000u);
  EXPECT_TRUE(rec.sets.empty());
  p->finish();
  ASSERT_EQ(rec.sets.size(), 5000u);
  for (size_t k = 0; k < 5000; ++k) ASSERT_EQ(rec.sets[k].stamp, k * 0.001);
}

TEST(StampMerge, RejectsBadOptions) {
  Recorder rec;
  EXPECT_THROW(make_policy(PolicyKind::Merge, merge_opts(0, 0), rec), std::invalid_argument);
  EXPECT_THROW(make_policy(PolicyKind::Merge, merge_opts(2, -1), rec), std::invalid_argument);
  EXPECT_THROW(make_policy(PolicyKind::Merge, merge_opts(2, std::nan("")), rec), std::invalid_argument);
  auto p = make_policy(PolicyKind::Merge, merge_opts(2, 0), rec);
  EXPECT_THROW(p->add(Member{2, 0, 0}), std::out_of_range);
  p->add(Member{0, std::nan(""), 7});
  EXPECT_EQ(rec.released[7].first, Release::Late);
}

// The contract as a model: pending = stamp -> (input -> token), released
// while the smallest stamp is below the watermark.
TEST(StampMerge, MatchesAModelOnRandomStreams) {
  std::mt19937 rng(11);
  size_t total_sets = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const size_t n = 1 + rng() % 5;
    const double delay = (rng() % 4) * 0.5;  // 0, 0.5, 1, 1.5
    Recorder rec;
    auto p = make_policy(PolicyKind::Merge, merge_opts(n, delay), rec);
    std::vector<SetOut> want;
    std::map<uint64_t, Release> want_why;
    std::map<double, std::map<uint32_t, uint64_t>> pending;
    double newest = -std::numeric_limits<double>::infinity(), last = 0;
    bool any = false;
    auto model_release = [&](size_t step) {
      while (!pending.empty() && pending.begin()->first < newest - delay) {
        SetOut s{{}, pending.begin()->first, step};
        for (auto& [input, token] : pending.begin()->second) {
          s.members.emplace_back(input, token);
          want_why[token] = Release::Used;
        }
        want.push_back(s);
        any = true;
        last = pending.begin()->first;
        pending.erase(pending.begin());
      }
    };
    double clock = 0;
    const size_t messages = 200;
    for (size_t k = 0; k < messages; ++k) {
      rec.step = k;
      if (rng() % 10 == 0) {  // idle: advance the watermark
        double to = clock + (rng() % 8) * 0.25;
        p->advance(to);
        newest = std::max(newest, to);
        model_release(k);
      }
      clock += 0.25;
      // Stamps on a 0.25 grid around the clock: equal stamps across and
      // within inputs, and some out of order, some late.
      double stamp = clock + (static_cast<int>(rng() % 9) - 6) * 0.25;
      uint32_t input = static_cast<uint32_t>(rng() % n);
      p->add(Member{input, stamp, k});
      if (any && stamp <= last) {
        want_why[k] = Release::Late;
      } else {
        auto& slot = pending[stamp];
        if (slot.count(input)) want_why[slot[input]] = Release::Replaced;
        slot[input] = k;
        newest = std::max(newest, stamp);
        model_release(k);
      }
      size_t held = 0;
      for (auto& [s, slot] : pending) held += slot.size();
      ASSERT_EQ(p->held(), held) << "trial " << trial << " step " << k;
    }
    rec.step = messages;
    newest = std::numeric_limits<double>::infinity();
    model_release(messages);
    p->finish();
    ASSERT_EQ(rec.sets, want) << "trial " << trial;
    for (size_t k = 0; k < messages; ++k) {
      ASSERT_EQ(rec.count[k], 1) << "trial " << trial << " message " << k;
      ASSERT_EQ(rec.released[k].first, want_why[k]) << "trial " << trial << " message " << k;
    }
    for (size_t s = 1; s < rec.sets.size(); ++s) ASSERT_LT(rec.sets[s - 1].stamp, rec.sets[s].stamp);
    total_sets += rec.sets.size();
  }
  EXPECT_GT(total_sets, 20000u);
}

}  // namespace
}  // namespace rvc::sync
