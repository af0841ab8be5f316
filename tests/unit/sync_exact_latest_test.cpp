// ExactTime and LatestTime: message_filters' tests ported as data where our
// contract allows, hand-computed traces (Late, Replaced, Overflow, finish),
// and a randomized comparison of ExactTime with a direct model of its contract.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <vector>

#include "sync/policy.hpp"
#include "sync_release_recorder.hpp"

namespace rvc::sync {
namespace {

struct Arrival {
  uint32_t input;
  double stamp;
};

// A set as (token per input) and the step that emitted it; tokens are arrival indexes.
struct SetOut {
  std::vector<uint64_t> tokens;
  double stamp;
  size_t step;
  bool operator==(const SetOut&) const = default;
};

struct Recorder : test::ReleaseRecorder {
  std::vector<SetOut> sets;
  void on_set(const Member* members, size_t n, double set_stamp) override {
    SetOut s{{}, set_stamp, step};
    for (size_t i = 0; i < n; ++i) {
      if (i > 0) {
        EXPECT_LT(members[i - 1].input, members[i].input);  // sorted by input
      }
      s.tokens.push_back(members[i].token);
    }
    sets.push_back(s);
  }
  std::pair<Release, size_t> of(uint64_t token) const {
    auto it = released.find(token);
    EXPECT_NE(it, released.end()) << "message " << token << " never released";
    return it == released.end() ? std::pair{Release::Used, SIZE_MAX} : it->second;
  }
};

// Feeds the arrivals (calling `after(k)` after each), then finish().
template <class After>
Recorder run(PolicyKind kind, const PolicyOptions& o, const std::vector<Arrival>& in, After after) {
  Recorder rec;
  auto p = make_policy(kind, o, rec);
  for (size_t k = 0; k < in.size(); ++k) {
    rec.step = k;
    p->add(Member{in[k].input, in[k].stamp, k});
    after(k, *p);
  }
  rec.step = in.size();
  p->finish();
  EXPECT_EQ(p->held(), 0u);
  for (size_t k = 0; k < in.size(); ++k) EXPECT_EQ(rec.releases_of(k), 1) << "message " << k;
  return rec;
}
Recorder run(PolicyKind kind, const PolicyOptions& o, const std::vector<Arrival>& in) {
  return run(kind, o, in, [](size_t, Policy&) {});
}

PolicyOptions opts(size_t inputs, size_t queue_size = 10) {
  PolicyOptions o;
  o.inputs = inputs;
  o.queue_size = queue_size;
  return o;
}

using R = std::pair<Release, size_t>;

// ---- ExactTime: message_filters' test_exact_time_policy.cpp ----

TEST(ExactTimeUpstream, MultipleTimes) {
  // 3 inputs, queue 2: the set at 0.1 s goes when its third message arrives;
  // the lone message at 0 can no longer complete (upstream: dropped by
  // clearOldTuples; here: Unmatched).
  std::vector<Arrival> in = {{0, 0}, {1, 0.1}, {0, 0.1}, {2, 0.1}};
  auto rec = run(PolicyKind::Exact, opts(3, 2), in);
  ASSERT_EQ(rec.sets, (std::vector<SetOut>{{{2, 1, 3}, 0.1, 3}}));
  EXPECT_EQ(rec.of(0), R(Release::Unmatched, 3));
}

TEST(ExactTimeUpstream, QueueSize) {
  // Queue 1: a second pending stamp pushes the oldest out, every time; no set.
  std::vector<Arrival> in = {{0, 0}, {1, 0}, {1, 0.1}, {1, 0}, {2, 0}};
  auto rec = run(PolicyKind::Exact, opts(3, 1), in);
  EXPECT_TRUE(rec.sets.empty());
  EXPECT_EQ(rec.of(0), R(Release::Overflow, 2));
  EXPECT_EQ(rec.of(1), R(Release::Overflow, 2));
  EXPECT_EQ(rec.of(3), R(Release::Overflow, 3));  // stamp 0 again: older than 0.1, so it is the one to go
  EXPECT_EQ(rec.of(4), R(Release::Overflow, 4));
  EXPECT_EQ(rec.of(2), R(Release::Unfinished, 5));
}

TEST(ExactTimeUpstream, DropCallback) {
  // Queue 1, 2 inputs: the second stamp of input 0 drops the first (upstream
  // counts one drop callback).
  std::vector<Arrival> in = {{0, 0}, {0, 0.1}};
  auto rec = run(PolicyKind::Exact, opts(2, 1), in);
  EXPECT_EQ(rec.of(0), R(Release::Overflow, 1));
  EXPECT_EQ(rec.of(1), R(Release::Unfinished, 2));
}
// Not ported: eventInEventOut checks that receipt times pass through; a
// policy here sees no receipt times, and tokens pass through in every test.

// ---- ExactTime: hand traces ----

TEST(ExactTime, LateReplacedAndOrder) {
  std::vector<Arrival> in = {
      {0, 2}, {1, 1},          // two pending stamps
      {0, 1},                  // completes 1: set; nothing older
      {0, 2},                  // input 0 at 2 again: the first is Replaced
      {1, 2},                  // completes 2 with the second
      {0, 2},                  // 2 went out: Late
      {0, 1.5},                // before the last set: Late
      {0, 3}, {1, 4}, {0, 4},  // 4 completes; 3 can no longer: Unmatched
  };
  auto rec = run(PolicyKind::Exact, opts(2), in);
  ASSERT_EQ(rec.sets, (std::vector<SetOut>{{{2, 1}, 1, 2}, {{3, 4}, 2, 4}, {{9, 8}, 4, 9}}));
  EXPECT_EQ(rec.of(0), R(Release::Replaced, 3));
  EXPECT_EQ(rec.of(5), R(Release::Late, 5));
  EXPECT_EQ(rec.of(6), R(Release::Late, 6));
  EXPECT_EQ(rec.of(7), R(Release::Unmatched, 9));
}

TEST(ExactTime, FinishReleasesPendingInStampOrder) {
  std::vector<Arrival> in = {{0, 3}, {1, 1}, {2, 2}, {0, 1}};
  std::vector<size_t> held;
  Recorder rec;
  auto p = make_policy(PolicyKind::Exact, opts(3), rec);
  for (size_t k = 0; k < in.size(); ++k) {
    p->add(Member{in[k].input, in[k].stamp, k});
    held.push_back(p->held());
  }
  EXPECT_EQ(held, (std::vector<size_t>{1, 2, 3, 4}));
  std::vector<uint64_t> order;
  struct Order : Handler {
    std::vector<uint64_t>* out;
    void on_set(const Member*, size_t, double) override { ADD_FAILURE(); }
    void on_release(const Member& m, Release why) override {
      EXPECT_EQ(why, Release::Unfinished);
      out->push_back(m.token);
    }
  } order_handler;
  order_handler.out = &order;
  auto q = make_policy(PolicyKind::Exact, opts(3), order_handler);
  for (size_t k = 0; k < in.size(); ++k) q->add(Member{in[k].input, in[k].stamp, k});
  q->finish();
  EXPECT_EQ(order, (std::vector<uint64_t>{3, 1, 2, 0}));  // stamp 1 (input 0, then 1), 2, 3
  EXPECT_EQ(q->held(), 0u);
}

// The contract, modelled directly (maps, no cleverness), against the policy
// on random streams with repeated and out-of-order stamps.
TEST(ExactTime, MatchesAModelOnRandomStreams) {
  std::mt19937 rng(99);
  size_t sets = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const size_t n = 1 + rng() % 4, q = 1 + rng() % 4;
    std::vector<Arrival> in;
    for (int k = 0; k < 80; ++k)  // stamps on a 0.25 grid, mostly increasing, often repeated
      in.push_back({static_cast<uint32_t>(rng() % n), (k + static_cast<int>(rng() % 12)) / 4 * 0.25});
    // Model.
    std::vector<SetOut> want;
    std::map<uint64_t, Release> want_why;
    std::map<double, std::map<uint32_t, uint64_t>> pending;
    bool any = false;
    double last = 0;
    for (size_t k = 0; k < in.size(); ++k) {
      auto [i, s] = in[k];
      if (any && s <= last) {
        want_why[k] = Release::Late;
        continue;
      }
      auto& slot = pending[s];
      if (slot.count(i)) want_why[slot[i]] = Release::Replaced;
      slot[i] = k;
      if (slot.size() == n) {
        SetOut out{{}, s, k};
        for (auto& [input, token] : slot) out.tokens.push_back(token), want_why[token] = Release::Used;
        want.push_back(out);
        pending.erase(s);
        while (!pending.empty() && pending.begin()->first < s) {
          for (auto& [input, token] : pending.begin()->second) want_why[token] = Release::Unmatched;
          pending.erase(pending.begin());
        }
        any = true;
        last = s;
      } else {
        while (pending.size() > q) {
          for (auto& [input, token] : pending.begin()->second) want_why[token] = Release::Overflow;
          pending.erase(pending.begin());
        }
      }
    }
    for (auto& [stamp, slot] : pending)
      for (auto& [input, token] : slot) want_why[token] = Release::Unfinished;
    auto rec = run(PolicyKind::Exact, opts(n, q), in);
    ASSERT_EQ(rec.sets, want) << "trial " << trial;
    for (auto& [token, why] : want_why) ASSERT_EQ(rec.of(token).first, why) << "trial " << trial << " token " << token;
    sets += want.size();
  }
  EXPECT_GT(sets, 2000u);
}

TEST(ExactTime, RejectsBadOptions) {
  Recorder rec;
  EXPECT_THROW(make_policy(PolicyKind::Exact, opts(0), rec), std::invalid_argument);
  EXPECT_THROW(make_policy(PolicyKind::Exact, opts(2, 0), rec), std::invalid_argument);
}

// ---- LatestTime: ROS 2 message_filters' test_latest_time_policy.cpp ----
//
// Upstream adds messages at 50 Hz wall time (p every step, q every 2nd, r
// every 4th) and rates come from arrival times; here the stamps are the
// arrival times. One step is 1/64 s rather than 20 ms, so that equal mean
// intervals are equal in floating point. p, q, r are inputs 0, 1, 2.

constexpr double kStep = 1.0 / 64;

// Arrivals of the upstream loops: at step k, q if q_at(k), r if r_at(k), p if p_at(k).
template <class Q, class Rr, class P>
std::vector<Arrival> latest_stream(size_t steps, Q q_at, Rr r_at, P p_at) {
  std::vector<Arrival> in;
  for (size_t k = 0; k < steps; ++k) {
    double t = kStep * static_cast<double>(k);
    if (q_at(k)) in.push_back({1, t});
    if (r_at(k)) in.push_back({2, t});
    if (p_at(k)) in.push_back({0, t});
  }
  return in;
}

int step_of(double stamp) { return static_cast<int>(stamp / kStep); }

// Per set, the step of each member (p, q, r).
std::vector<std::vector<int>> member_steps(const Recorder& rec, const std::vector<Arrival>& in) {
  std::vector<std::vector<int>> out;
  for (const auto& s : rec.sets) {
    std::vector<int> v;
    for (uint64_t t : s.tokens) v.push_back(step_of(in[t].stamp));
    out.push_back(v);
  }
  return out;
}

std::vector<int> set_stamp_steps(const Recorder& rec) {
  std::vector<int> out;
  for (const auto& s : rec.sets) out.push_back(step_of(s.stamp));
  return out;
}

TEST(LatestTimeUpstream, Leading) {
  auto in = latest_stream(8, [](size_t k) { return k % 2 == 0; }, [](size_t k) { return k % 4 == 0; },
                          [](size_t) { return true; });
  auto rec = run(PolicyKind::Latest, opts(3), in);
  // Upstream: a set at every p from step 1 on with q[k/2], r[k/4]. Here also
  // at step 0: before any input has a rate the pivot is the input with most
  // messages (all have one: the lowest, p), where upstream waits for rates.
  std::vector<std::vector<int>> want = {{0, 0, 0}};
  for (int k = 1; k < 8; ++k) want.push_back({k, k / 2 * 2, k / 4 * 4});
  EXPECT_EQ(member_steps(rec, in), want);
  EXPECT_EQ(set_stamp_steps(rec), (std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7}));  // p's stamps
}

TEST(LatestTimeUpstream, Trailing) {
  auto in = latest_stream(8, [](size_t k) { return k % 2 == 1; }, [](size_t k) { return k % 4 == 3; },
                          [](size_t) { return true; });
  auto rec = run(PolicyKind::Latest, opts(3), in);
  // As upstream: nothing until r's first message (step 3), then a set at every p.
  std::vector<std::vector<int>> want;
  for (int k = 3; k < 8; ++k) want.push_back({k, (k - 1) / 2 * 2 + 1, (k - 3) / 4 * 4 + 3});
  EXPECT_EQ(member_steps(rec, in), want);
  EXPECT_EQ(set_stamp_steps(rec), (std::vector<int>{3, 4, 5, 6, 7}));
}

TEST(LatestTimeUpstream, ChangeRateLeading) {
  // Upstream's stream: p at steps 0-3, then at every 3rd step (6, 9, ...);
  // q every 2nd, r every 4th. Upstream's rate estimate follows the latest
  // intervals and switches the pivot to q at step 6. Ours is the mean
  // interval since the first message, so p (mean 1.5, 1.8, 2 steps after
  // steps 6, 9, 12; 2 ties with q and the lower input wins) stays the pivot
  // until its mean passes q's 2 at step 15 (15/7); from step 16 the sets come
  // with q. Extended to step 18 to show the switch (hand-computed).
  auto in = latest_stream(19, [](size_t k) { return k % 2 == 0; }, [](size_t k) { return k % 4 == 0; },
                          [](size_t k) { return k < 4 || k % 3 == 0; });
  auto rec = run(PolicyKind::Latest, opts(3), in);
  std::vector<std::vector<int>> want = {{0, 0, 0}, {1, 0, 0},    {2, 2, 0},    {3, 2, 0},   {6, 6, 4},
                                        {9, 8, 8}, {12, 12, 12}, {15, 16, 12}, {15, 18, 16}};
  EXPECT_EQ(member_steps(rec, in), want);
  EXPECT_EQ(set_stamp_steps(rec), (std::vector<int>{0, 1, 2, 3, 6, 9, 12, 16, 18}));  // the last two: q's
  // Releases: p at 12 was in a set when p at 15 replaced it; q at 14 never was.
  auto token_of = [&](uint32_t input, int step) {
    for (size_t k = 0; k < in.size(); ++k)
      if (in[k].input == input && step_of(in[k].stamp) == step) return static_cast<uint64_t>(k);
    ADD_FAILURE() << "no message";
    return uint64_t{0};
  };
  EXPECT_EQ(rec.of(token_of(0, 12)).first, Release::Used);
  EXPECT_EQ(rec.of(token_of(1, 14)).first, Release::Replaced);
  EXPECT_EQ(rec.of(token_of(2, 16)), R(Release::Used, in.size()));  // in the last set, released by finish
  EXPECT_EQ(rec.of(token_of(0, 15)), R(Release::Used, in.size() - 1));  // replaced by p at 18, the last arrival
  EXPECT_EQ(rec.of(token_of(0, 18)), R(Release::Unfinished, in.size()));  // no set after it
}
// Not ported: ChangeRateTrailing exercises the same upstream rate estimator
// (latest intervals, detection of a late pivot) that ChangeRateLeading shows
// we do not share.

// ---- LatestTime: hand traces ----

TEST(LatestTime, FixedPivotReplacedAndFinish) {
  PolicyOptions o = opts(2);
  o.pivot = 1;
  std::vector<Arrival> in = {
      {1, 0.0},  // pivot, but input 0 has no data: no set
      {0, 0.1},
      {0, 0.2},  // replaces 0.1, which no set used: Replaced
      {1, 0.3},  // set {0.2, 0.3} at 0.3
      {1, 0.25}, // set {0.2, 0.25} at 0.25: the pivot's own order; 0.3 was used
      {0, 0.5},  // replaces 0.2 (used)
  };
  auto rec = run(PolicyKind::Latest, o, in);
  ASSERT_EQ(rec.sets, (std::vector<SetOut>{{{2, 3}, 0.3, 3}, {{2, 4}, 0.25, 4}}));
  EXPECT_EQ(rec.of(0), R(Release::Replaced, 3));
  EXPECT_EQ(rec.of(1), R(Release::Replaced, 2));
  EXPECT_EQ(rec.of(3), R(Release::Used, 4));
  EXPECT_EQ(rec.of(2), R(Release::Used, 5));
  EXPECT_EQ(rec.of(4), R(Release::Used, 6));        // finish: used
  EXPECT_EQ(rec.of(5), R(Release::Unfinished, 6));  // finish: never in a set
}

TEST(LatestTime, FastestByMeanInterval) {
  // Input 1 at 10 Hz, input 0 at 4 Hz: once both have rates, sets follow input 1.
  // Before that, the input with most messages is the pivot (ties: lower).
  std::vector<Arrival> in = {{0, 0.0}, {1, 0.0}, {1, 0.1}, {1, 0.2}, {0, 0.25}, {1, 0.3}};
  std::vector<size_t> held;
  auto rec = run(PolicyKind::Latest, opts(2), in, [&](size_t, Policy& p) { held.push_back(p.held()); });
  // step 1: both have 1 message, pivot input 0 (lower): input 1's message makes no set.
  // step 2: input 1 has a rate (0.1), input 0 none: input 1 is the pivot.
  ASSERT_EQ(rec.sets, (std::vector<SetOut>{{{0, 2}, 0.1, 2}, {{0, 3}, 0.2, 3}, {{4, 5}, 0.3, 5}}));
  EXPECT_EQ(held, (std::vector<size_t>{1, 2, 2, 2, 2, 2}));
  EXPECT_EQ(rec.of(1), R(Release::Replaced, 2));
}

TEST(LatestTime, PivotMovesBackWhenTheFastestSlowsDown) {
  // Input 0 fast at first (every 1/8 s), input 1 every 1/2 s; then input 0
  // pauses: its mean interval 2.25 / 3 = 0.75 passes input 1's 0.5, and
  // input 1 becomes the pivot. (A faster input taking over is the O(1) path;
  // the pivot slowing down is the rescan.)
  std::vector<Arrival> in = {{1, 0.0}, {0, 0.0}, {0, 0.125}, {1, 0.5}, {0, 0.25}, {1, 1.0}, {0, 2.25}, {1, 1.5}};
  auto rec = run(PolicyKind::Latest, opts(2), in);
  // step 1: no rates, equal counts: pivot 0 -> set. step 2: 0 has a rate -> set.
  // step 3: 1 has a rate 0.5 > 0.125: no set. step 4: 0 (mean 0.125) -> set.
  // step 5: 1 (0.5) no set. step 6: 0 slows to 0.75 > 0.5: pivot 1, no set.
  // step 7: input 1 (still 0.5) -> set.
  ASSERT_EQ(rec.sets, (std::vector<SetOut>{{{1, 0}, 0.0, 1}, {{2, 0}, 0.125, 2}, {{4, 3}, 0.25, 4}, {{6, 7}, 1.5, 7}}));
}

TEST(LatestTime, RejectsBadOptions) {
  Recorder rec;
  PolicyOptions o = opts(2);
  o.pivot = 2;
  EXPECT_THROW(make_policy(PolicyKind::Latest, o, rec), std::invalid_argument);
  o.pivot = -2;
  EXPECT_THROW(make_policy(PolicyKind::Latest, o, rec), std::invalid_argument);
  EXPECT_THROW(make_policy(PolicyKind::Latest, opts(0), rec), std::invalid_argument);
}

TEST(SyncPolicy, Names) {
  for (auto k : {PolicyKind::Approximate, PolicyKind::Exact, PolicyKind::Latest, PolicyKind::Merge})
    EXPECT_EQ(policy_from_string(to_string(k)), k);
  EXPECT_THROW(policy_from_string("Exact"), std::invalid_argument);
  std::vector<std::string> names;
  for (size_t r = 0; r < kReleaseKinds; ++r) names.push_back(to_string(static_cast<Release>(r)));
  EXPECT_EQ(names, (std::vector<std::string>{"used", "unmatched", "overflow", "interval", "replaced", "late",
                                             "unfinished"}));
}

}  // namespace
}  // namespace rvc::sync
