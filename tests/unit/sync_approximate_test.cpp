// ApproximateTime: message_filters' published test vectors (ported as data),
// hand-traced release reasons, and a brute-force check of the guarantees the
// message_filters wiki states for the algorithm on random inputs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "sync/approximate_time.hpp"
#include "sync/policy.hpp"

namespace rvc::sync {
namespace {

constexpr size_t kAny = SIZE_MAX;  // emission step not asserted

struct Arrival {
  uint32_t input;
  double stamp;
};

// Records what a policy hands out; a message's token is its arrival index.
struct Recorder : Handler {
  struct Set {
    std::vector<Member> members;
    double stamp;
    size_t step;  // arrival index whose add() emitted it (arrivals.size(): finish())
  };
  std::vector<Set> sets;
  std::vector<int> releases;        // per token
  std::vector<Release> why;         // per token, the last reason
  std::vector<size_t> release_step; // per token
  size_t step = 0;

  explicit Recorder(size_t messages) : releases(messages, 0), why(messages, Release::Used), release_step(messages) {}
  void on_set(const Member* members, size_t count, double set_stamp) override {
    sets.push_back(Set{std::vector<Member>(members, members + count), set_stamp, step});
  }
  void on_release(const Member& m, Release reason) override {
    ASSERT_LT(m.token, releases.size());
    ++releases[m.token];
    why[m.token] = reason;
    release_step[m.token] = step;
  }
};

Recorder run(const PolicyOptions& options, const std::vector<Arrival>& arrivals) {
  Recorder rec(arrivals.size());
  auto policy = make_policy(PolicyKind::Approximate, options, rec);
  for (size_t k = 0; k < arrivals.size(); ++k) {
    rec.step = k;
    policy->add(Member{arrivals[k].input, arrivals[k].stamp, k});
  }
  rec.step = arrivals.size();
  policy->finish();
  EXPECT_EQ(policy->held(), 0u);
  return rec;
}

PolicyOptions approx(size_t inputs, size_t queue_size) {
  PolicyOptions o;
  o.inputs = inputs;
  o.queue_size = queue_size;  // age penalty: the default 0.1, as message_filters' tests
  return o;
}

struct ExpectedSet {
  std::vector<double> stamps;  // per input
  size_t after;                // arrival index that emits it, or kAny
};

// Sets (member stamps per input, emission step), every member of a set Used,
// every message released exactly once.
void expect_sets(const Recorder& rec, const std::vector<Arrival>& arrivals, const std::vector<ExpectedSet>& expected) {
  ASSERT_EQ(rec.sets.size(), expected.size());
  for (size_t s = 0; s < expected.size(); ++s) {
    const auto& got = rec.sets[s];
    ASSERT_EQ(got.members.size(), expected[s].stamps.size()) << "set " << s;
    double newest = -std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < got.members.size(); ++i) {
      EXPECT_EQ(got.members[i].input, i) << "set " << s;
      EXPECT_EQ(got.members[i].stamp, expected[s].stamps[i]) << "set " << s << " input " << i;
      EXPECT_EQ(arrivals[got.members[i].token].stamp, got.members[i].stamp);
      EXPECT_EQ(arrivals[got.members[i].token].input, i);
      EXPECT_EQ(rec.why[got.members[i].token], Release::Used);
      newest = std::max(newest, got.members[i].stamp);
    }
    EXPECT_EQ(got.stamp, newest) << "set " << s;
    if (expected[s].after != kAny) {
      EXPECT_EQ(got.step, expected[s].after) << "set " << s;
    }
  }
  for (size_t t = 0; t < rec.releases.size(); ++t) EXPECT_EQ(rec.releases[t], 1) << "message " << t;
}

// ---- message_filters' test_approximate_time_policy.cpp (ROS 1 ros_comm and ROS 2 message_filters) ----
// Each table is the upstream input sequence (topic, stamp in seconds) and its
// expected output sets. Upstream asserts only the sets; `after` additionally
// asserts when each set comes out: as the upstream comment diagrams draw it
// (column = stamp of the arrival that emits it), except where the diagram
// disagrees with a hand trace of the algorithm (said at the test).

TEST(ApproxTimeUpstream, ExactMatch) {
  std::vector<Arrival> in = {{0, 0}, {1, 0}, {0, 3}, {1, 3}, {0, 6}, {1, 6}};
  auto rec = run(approx(2, 10), in);
  expect_sets(rec, in, {{{0, 0}, 1}, {{3, 3}, 3}, {{6, 6}, 5}});
}

TEST(ApproxTimeUpstream, PerfectMatch) {
  std::vector<Arrival> in = {{0, 0}, {1, 1}, {0, 3}, {1, 4}, {0, 6}, {1, 7}};
  auto rec = run(approx(2, 10), in);
  expect_sets(rec, in, {{{0, 1}, 2}, {{3, 4}, 4}});
  EXPECT_EQ(rec.why[4], Release::Unfinished);  // c and C: a better partner for c may still come
  EXPECT_EQ(rec.why[5], Release::Unfinished);
}

TEST(ApproxTimeUpstream, ImperfectMatch) {
  std::vector<Arrival> in = {{0, 0}, {1, 1}, {0, 2}, {0, 3}, {1, 5}, {0, 6}, {1, 7}};
  auto rec = run(approx(2, 10), in);
  expect_sets(rec, in, {{{0, 1}, 2}, {{6, 5}, 5}});
  // Hand trace: when B arrives, {b, B} beats {x, B} and x goes; when c
  // arrives, {c, B} beats {b, B} and b goes.
  EXPECT_EQ(rec.why[2], Release::Unmatched);
  EXPECT_EQ(rec.release_step[2], 4u);
  EXPECT_EQ(rec.why[3], Release::Unmatched);
  EXPECT_EQ(rec.release_step[3], 5u);
  EXPECT_EQ(rec.why[6], Release::Unfinished);
}

TEST(ApproxTimeUpstream, Acceleration) {
  std::vector<Arrival> in = {{0, 0}, {1, 7}, {0, 12}, {1, 15}, {0, 17}, {1, 18}};
  auto rec = run(approx(2, 10), in);
  expect_sets(rec, in, {{{12, 7}, 2}, {{17, 18}, 5}});
  EXPECT_EQ(rec.why[0], Release::Unmatched);  // a: {b, A} is smaller than {a, A}
  EXPECT_EQ(rec.why[3], Release::Unmatched);  // B: {c, C} beats {c, B}
}

const std::vector<Arrival> kDropped = {{0, 0},  {1, 1},  {1, 3},  {0, 4},  {1, 7},
                                       {0, 8},  {0, 10}, {1, 11}, {0, 13}, {1, 14}};

TEST(ApproxTimeUpstream, DroppedMessagesQueue1) {
  auto rec = run(approx(2, 1), kDropped);
  expect_sets(rec, kDropped, {{{4, 3}, 4}, {{10, 11}, 8}});
  // Hand trace: B overflows queue 1 and pushes A out; input 1 then has dropped
  // messages, so it cannot be the pivot and a goes; likewise d pushes c out,
  // and C goes.
  EXPECT_EQ(rec.why[1], Release::Overflow);
  EXPECT_EQ(rec.release_step[1], 2u);
  EXPECT_EQ(rec.why[0], Release::Unmatched);
  EXPECT_EQ(rec.release_step[0], 2u);
  EXPECT_EQ(rec.why[5], Release::Overflow);
  EXPECT_EQ(rec.why[4], Release::Unmatched);
  EXPECT_EQ(rec.release_step[4], 6u);
  EXPECT_EQ(rec.why[8], Release::Unfinished);
  EXPECT_EQ(rec.why[9], Release::Unfinished);
}

TEST(ApproxTimeUpstream, DroppedMessagesQueue2) {
  auto rec = run(approx(2, 2), kDropped);
  expect_sets(rec, kDropped, {{{0, 1}, 3}, {{4, 3}, 4}, {{8, 7}, 7}, {{10, 11}, 8}});
  for (size_t t = 0; t < kDropped.size(); ++t) EXPECT_NE(rec.why[t], Release::Overflow) << t;
}

TEST(ApproxTimeUpstream, LongQueue) {
  std::vector<Arrival> in = {{0, 0}, {0, 1}, {0, 2}, {0, 3}, {0, 4},  {0, 5},  {0, 6},  {0, 7},
                             {0, 8}, {1, 3}, {0, 9}, {0, 10}, {0, 11}, {0, 12}, {1, 10}, {0, 13}};
  auto rec = run(approx(2, 5), in);
  expect_sets(rec, in, {{{10, 10}, 14}});
  // d (stamp 3) matched j exactly but was pushed out of the queue of 5 before j came.
  EXPECT_EQ(rec.why[3], Release::Overflow);
  EXPECT_EQ(rec.why[9], Release::Unmatched);  // j: no partner left near it
}

TEST(ApproxTimeUpstream, DoublePublish) {
  std::vector<Arrival> in = {{0, 0}, {1, 1}, {1, 3}, {0, 3}};
  auto rec = run(approx(2, 10), in);
  expect_sets(rec, in, {{{0, 1}, 3}, {{3, 3}, 3}});  // both sets come out when b arrives
}

TEST(ApproxTimeUpstream, FourTopics) {
  std::vector<Arrival> in = {{0, 0}, {1, 1}, {2, 2},  {3, 3},  {0, 5},  {3, 5},  {1, 6}, {2, 6},
                             {0, 8}, {1, 9}, {2, 10}, {3, 11}, {0, 10}, {0, 13}, {1, 14}};
  auto rec = run(approx(4, 10), in);
  // The diagram draws the second set at 11; the algorithm proves it when i
  // (stamp 8) arrives: any later candidate spans [6, 8] at least, wider
  // than {e, g, h, f} (hand trace).
  expect_sets(rec, in, {{{0, 1, 2, 3}, 6}, {{5, 6, 6, 5}, 8}, {{10, 9, 10, 11}, 14}});
  EXPECT_EQ(rec.why[8], Release::Unmatched);  // i: m is closer to the third set
}

TEST(ApproxTimeUpstream, EarlyPublish) {
  std::vector<Arrival> in = {{0, 0}, {1, 1}, {2, 2}, {3, 3}, {0, 7}};
  auto rec = run(approx(4, 10), in);
  expect_sets(rec, in, {{{0, 1, 2, 3}, 4}});
}

const std::vector<Arrival> kRate = {{0, 0}, {1, 1}, {0, 3}, {1, 4}, {0, 6}, {1, 7}};

TEST(ApproxTimeUpstream, RateBound) {
  // Lower bound 1.5 s on input 0: not enough to prove {a, A} before b (a
  // message of input 0 at 1.5 would pair better with A), so the sets come out
  // as without a bound; the upstream diagram draws them one step earlier,
  // which only the bound of 2 achieves (its assertions do not check timing).
  PolicyOptions o = approx(2, 10);
  o.inter_message_lower_bound = {1.5, 0};
  auto rec = run(o, kRate);
  expect_sets(rec, kRate, {{{0, 1}, 2}, {{3, 4}, 4}});

  o.inter_message_lower_bound = {2, 0};  // now every set is proven when its second message arrives
  auto rec2 = run(o, kRate);
  expect_sets(rec2, kRate, {{{0, 1}, 1}, {{3, 4}, 3}, {{6, 7}, 5}});
}

TEST(ApproxTimeUpstream, RateBoundAll) {  // ROS 1 only: setInterMessageLowerBound(2 s) for every topic
  PolicyOptions o = approx(2, 10);
  o.inter_message_lower_bound = {2, 2};
  auto rec = run(o, kRate);
  expect_sets(rec, kRate, {{{0, 1}, 1}, {{3, 4}, 3}, {{6, 7}, 5}});
}

// ---- beyond the upstream vectors: hand traces of message_filters' code ----

TEST(ApproxTime, EqualStampsBreakTiesAsMessageFilters) {
  // Queue 1. Input 1 overflows (its first message goes), so input 1 has
  // dropped messages. Then input 0 at the same stamp: both heads are at 2.
  // message_filters takes the latest head from the highest input (1: it has
  // dropped messages, so it cannot be the pivot) and the earliest head from
  // the lowest input (0), which is deleted. Either tie broken the other way
  // would make the set {2, 2} or delete input 1's message instead.
  std::vector<Arrival> in = {{1, 2}, {1, 2}, {0, 2}};
  auto rec = run(approx(2, 1), in);
  expect_sets(rec, in, {});
  EXPECT_EQ(rec.why[0], Release::Overflow);
  EXPECT_EQ(rec.why[2], Release::Unmatched);
  EXPECT_EQ(rec.release_step[2], 2u);
  EXPECT_EQ(rec.why[1], Release::Unfinished);
}

TEST(ApproxTime, EqualCandidatesKeepTheOlder) {
  // Age penalty 0: {a=0, A=1} and {b=2, A=1} both span 1; a candidate must be
  // strictly better to replace the current one.
  PolicyOptions o = approx(2, 10);
  o.age_penalty = 0;
  std::vector<Arrival> in = {{0, 0}, {1, 1}, {0, 2}};
  auto rec = run(o, in);
  expect_sets(rec, in, {{{0, 1}, 2}});
  EXPECT_EQ(rec.why[2], Release::Unfinished);
}

TEST(ApproxTime, AgePenaltyPrefersTheOlderSet) {
  // {a=0, A=1} spans 1, {x=1.95, A=1} spans 0.95: better without penalty,
  // but 0.95 * 1.1 >= 1 with the default penalty 0.1.
  std::vector<Arrival> in = {{0, 0}, {1, 1}, {0, 1.95}};
  auto rec = run(approx(2, 10), in);
  expect_sets(rec, in, {{{0, 1}, 2}});
  PolicyOptions o = approx(2, 10);
  o.age_penalty = 0;
  auto rec0 = run(o, in);
  expect_sets(rec0, in, {{{1.95, 1}, 2}});
  EXPECT_EQ(rec0.why[0], Release::Unmatched);
}

TEST(ApproxTime, VirtualTimeIsAtLeastThePivot) {
  // No lower bounds. Candidate {0:1, 1:2, 2:1}, pivot input 1 at 2; input 0's
  // queue is empty, and any set better than the candidate holds a message at
  // or after the pivot, so its virtual stamp is 2, not 1. Moving input 2's
  // head aside (virtually) leaves heads {2, 2, 3}: every later candidate
  // spans [2, 3] at least, so the candidate goes out before input 0 sends again.
  std::vector<Arrival> in = {{1, 2}, {2, 1}, {2, 3}, {0, 1}};
  auto rec = run(approx(3, 10), in);
  expect_sets(rec, in, {{{1, 2, 1}, 3}});
}

// ---- beyond the upstream vectors ----

TEST(ApproxTime, MaxIntervalReleasesTheStartMessage) {
  // Input 0 at 0, input 1 at 5: wider than 2, so message 0 can never be in a
  // set and goes as Interval when 5 arrives; then {4.5, 5}.
  PolicyOptions o = approx(2, 10);
  o.max_interval = 2;
  o.age_penalty = 0;
  std::vector<Arrival> in = {{0, 0}, {1, 5}, {0, 4.5}, {0, 8}, {1, 6}};
  auto rec = run(o, in);
  expect_sets(rec, in, {{{4.5, 5}, 3}});
  EXPECT_EQ(rec.why[0], Release::Interval);
  EXPECT_EQ(rec.release_step[0], 1u);
  EXPECT_EQ(rec.why[3], Release::Unfinished);  // 8 with 6: may still find a closer partner
  EXPECT_EQ(rec.why[4], Release::Unfinished);
}

TEST(ApproxTime, OutOfOrderMessageIsLate) {
  std::vector<Arrival> in = {{0, 1}, {0, 0.5}, {1, 1}, {1, 1}};
  auto rec = run(approx(2, 10), in);
  EXPECT_EQ(rec.why[1], Release::Late);
  EXPECT_EQ(rec.release_step[1], 1u);  // at once
  // An equal stamp is not earlier: the second message of input 1 is kept.
  expect_sets(rec, in, {{{1, 1}, 2}});
  EXPECT_EQ(rec.why[3], Release::Unfinished);
}

TEST(ApproxTime, NonFiniteStampIsLate) {
  std::vector<Arrival> in = {{0, std::nan("")}, {1, std::numeric_limits<double>::infinity()}, {0, 1}, {1, 1}};
  auto rec = run(approx(2, 10), in);
  EXPECT_EQ(rec.why[0], Release::Late);
  EXPECT_EQ(rec.why[1], Release::Late);
  expect_sets(rec, in, {{{1, 1}, 3}});
}

TEST(ApproxTime, OneInputPassesEveryMessage) {
  std::vector<Arrival> in = {{0, 1}, {0, 2}, {0, 2}, {0, 5}};
  auto rec = run(approx(1, 1), in);
  expect_sets(rec, in, {{{1}, 0}, {{2}, 1}, {{2}, 2}, {{5}, 3}});
}

TEST(ApproxTime, TwelveInputs) {
  // message_filters stops at 9 topics. 12 inputs, two rounds with jitter: the
  // rounds are the sets.
  std::vector<Arrival> in;
  for (uint32_t i = 0; i < 12; ++i) in.push_back({i, 10 + 0.01 * i});
  for (uint32_t i = 0; i < 12; ++i) in.push_back({i, 20 - 0.01 * i});
  for (uint32_t i = 0; i < 12; ++i) in.push_back({i, 30.0});
  auto rec = run(approx(12, 10), in);
  ASSERT_EQ(rec.sets.size(), 3u);
  for (size_t s = 0; s < 3; ++s)
    for (uint32_t i = 0; i < 12; ++i) EXPECT_EQ(rec.sets[s].members[i].token, s * 12 + i);
  EXPECT_EQ(rec.sets[0].step, 12u);  // proven when the next round starts
  EXPECT_EQ(rec.sets[2].step, 35u);  // equal stamps: proven at once
}

TEST(ApproxTime, RejectsBadOptions) {
  Recorder rec(0);
  PolicyOptions o = approx(0, 10);
  EXPECT_THROW(make_policy(PolicyKind::Approximate, o, rec), std::invalid_argument);
  o = approx(2, 0);
  EXPECT_THROW(make_policy(PolicyKind::Approximate, o, rec), std::invalid_argument);
  o = approx(2, 10);
  o.age_penalty = -0.5;
  EXPECT_THROW(make_policy(PolicyKind::Approximate, o, rec), std::invalid_argument);
  o = approx(2, 10);
  o.inter_message_lower_bound = {1};
  EXPECT_THROW(make_policy(PolicyKind::Approximate, o, rec), std::invalid_argument);
  o.inter_message_lower_bound = {1, -1};
  EXPECT_THROW(make_policy(PolicyKind::Approximate, o, rec), std::invalid_argument);
  o = approx(2, 10);
  auto p = make_policy(PolicyKind::Approximate, o, rec);
  EXPECT_THROW(p->add(Member{2, 0, 0}), std::out_of_range);
}

// ---- brute force: the wiki's guarantees on random inputs ----
//
// message_filters/ApproximateTime (ROS wiki) promises: messages are used only
// once; sets do not cross; sets are contiguous (some input has no dropped
// message between two consecutive sets); sets are of minimal size among the
// sets contiguous to the previous published set; the output depends only on
// the stamps. With age penalty 0, no max interval and a queue that never
// overflows, check every emitted set against all sets of the remaining
// messages, enumerated.

struct Case {
  std::vector<std::vector<double>> stamps;  // per input, increasing
};

// Index of each member within its input, per set.
using Picks = std::vector<size_t>;

double spread(const Case& c, const Picks& p) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (size_t i = 0; i < p.size(); ++i) {
    lo = std::min(lo, c.stamps[i][p[i]]);
    hi = std::max(hi, c.stamps[i][p[i]]);
  }
  return hi - lo;
}

// Calls f(picks) for every set after `prev` (per input, an index > prev[i];
// prev[i] = -1 before the first set) contiguous to it (some input takes its
// very next message).
template <class F>
void for_each_contiguous(const Case& c, const std::vector<long>& prev, F f) {
  const size_t n = c.stamps.size();
  Picks p(n);
  for (size_t i = 0; i < n; ++i) {
    if (static_cast<size_t>(prev[i] + 1) >= c.stamps[i].size()) return;  // an input has nothing left
    p[i] = static_cast<size_t>(prev[i] + 1);
  }
  for (;;) {
    bool contiguous = false;
    for (size_t i = 0; i < n; ++i) contiguous |= p[i] == static_cast<size_t>(prev[i] + 1);
    if (contiguous) f(p);
    size_t i = 0;
    while (i < n && ++p[i] == c.stamps[i].size()) {
      p[i] = static_cast<size_t>(prev[i] + 1);
      ++i;
    }
    if (i == n) return;
  }
}

Case random_case(std::mt19937& rng, bool integer_stamps) {
  std::uniform_int_distribution<int> inputs(2, 4), count(1, 8), step(0, 3);
  std::uniform_real_distribution<double> real(0, 10);
  Case c;
  c.stamps.resize(static_cast<size_t>(inputs(rng)));
  for (auto& s : c.stamps) {
    int m = count(rng);
    if (integer_stamps) {  // small integers: many equal stamps across inputs
      double t = step(rng);
      for (int k = 0; k < m; ++k, t += 1 + step(rng)) s.push_back(t);
    } else {
      for (int k = 0; k < m; ++k) s.push_back(real(rng));
      std::sort(s.begin(), s.end());
    }
  }
  return c;
}

TEST(ApproxTimeBruteForce, GuaranteesOnRandomInputs) {
  std::mt19937 rng(20240612);
  size_t sets_checked = 0, greedy_checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const bool integer_stamps = trial % 2 == 0;
    Case c = random_case(rng, integer_stamps);
    const size_t n = c.stamps.size();
    // Arrivals in stamp order (equal stamps: a random input order), then, for
    // distinct stamps, a far sentinel per input so that every set the real
    // messages allow can be proven.
    std::vector<Arrival> in;
    for (uint32_t i = 0; i < n; ++i)
      for (double s : c.stamps[i]) in.push_back({i, s});
    std::shuffle(in.begin(), in.end(), rng);
    std::stable_sort(in.begin(), in.end(), [](const Arrival& a, const Arrival& b) { return a.stamp < b.stamp; });
    const size_t real = in.size();
    if (!integer_stamps)
      for (uint32_t i = 0; i < n; ++i) in.push_back({i, 1000.0 + i});
    std::vector<size_t> index_of(in.size());  // token -> index within its input
    {
      std::vector<size_t> next(n, 0);
      for (size_t k = 0; k < in.size(); ++k) index_of[k] = next[in[k].input]++;
    }
    PolicyOptions o = approx(n, 1000);
    o.age_penalty = 0;
    Recorder rec = run(o, in);

    for (size_t t = 0; t < in.size(); ++t) ASSERT_EQ(rec.releases[t], 1) << "trial " << trial << " message " << t;
    std::vector<long> prev(n, -1);
    bool sentinel_seen = false;
    std::vector<Picks> emitted;
    for (const auto& set : rec.sets) {
      ASSERT_EQ(set.members.size(), n);
      Picks p(n);
      bool has_sentinel = false;
      for (size_t i = 0; i < n; ++i) {
        ASSERT_EQ(set.members[i].input, i);
        ASSERT_EQ(rec.why[set.members[i].token], Release::Used);
        p[i] = index_of[set.members[i].token];
        has_sentinel |= set.members[i].token >= real;
        // No crossing, each message once: strictly after the previous set's member.
        ASSERT_GT(static_cast<long>(p[i]), prev[i]) << "trial " << trial;
      }
      if (has_sentinel) {
        sentinel_seen = true;
        break;
      }
      ASSERT_FALSE(sentinel_seen);
      bool contiguous = false;
      for (size_t i = 0; i < n; ++i) contiguous |= static_cast<long>(p[i]) == prev[i] + 1;
      ASSERT_TRUE(contiguous) << "trial " << trial;
      double best = std::numeric_limits<double>::infinity();
      Picks arg;
      for_each_contiguous(c, prev, [&](const Picks& q) {
        double s = spread(c, q);
        if (s < best) best = s, arg = q;
      });
      ASSERT_EQ(spread(c, p), best) << "trial " << trial << ": a contiguous set is smaller";
      emitted.push_back(p);
      for (size_t i = 0; i < n; ++i) prev[i] = static_cast<long>(p[i]);
      ++sets_checked;
    }
    if (integer_stamps) continue;
    // Distinct real stamps: the smallest contiguous set is unique, so the
    // sets must be exactly the greedy sequence, to the last set the real
    // messages allow (the sentinels let every one of them be proven).
    std::vector<Picks> greedy;
    std::vector<long> g(n, -1);
    for (;;) {
      double best = std::numeric_limits<double>::infinity();
      Picks arg;
      for_each_contiguous(c, g, [&](const Picks& q) {
        double s = spread(c, q);
        if (s < best) best = s, arg = q;
      });
      if (arg.empty()) break;
      greedy.push_back(arg);
      for (size_t i = 0; i < n; ++i) g[i] = static_cast<long>(arg[i]);
    }
    ASSERT_EQ(emitted, greedy) << "trial " << trial;
    greedy_checked += greedy.size();
  }
  // The check ran on real work: thousands of sets, not a handful.
  EXPECT_GT(sets_checked, 3000u);
  EXPECT_GT(greedy_checked, 1500u);
}

// Finite queues, max interval, lower bounds, default age penalty, random
// arrival interleaving: whatever the options, every message leaves exactly
// once, sets never cross, never span more than max_interval, and the policy
// never holds more than queue_size messages of an input.
TEST(ApproxTimeBruteForce, AccountingWithOptions) {
  std::mt19937 rng(7);
  size_t sets = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const size_t n = 2 + static_cast<size_t>(trial % 4);
    PolicyOptions o = approx(n, 1 + static_cast<size_t>(rng() % 5));
    if (trial % 3 == 0) o.max_interval = 0.5 + (rng() % 20) * 0.1;
    if (trial % 4 == 1) {
      o.inter_message_lower_bound.assign(n, 0.2);
    }
    std::vector<Arrival> in;
    std::vector<double> t(n, 0);
    for (int k = 0; k < 60; ++k) {  // per input increasing, inputs interleaved at random
      uint32_t i = static_cast<uint32_t>(rng() % n);
      t[i] += 0.2 + (rng() % 100) * 0.01;
      in.push_back({i, t[i]});
    }
    Recorder rec(in.size());
    auto p = make_policy(PolicyKind::Approximate, o, rec);
    for (size_t k = 0; k < in.size(); ++k) {
      rec.step = k;
      p->add(Member{in[k].input, in[k].stamp, k});
      ASSERT_LE(p->held(), n * o.queue_size);
    }
    p->finish();
    EXPECT_EQ(p->held(), 0u);
    for (size_t k = 0; k < in.size(); ++k) ASSERT_EQ(rec.releases[k], 1) << "trial " << trial;
    std::vector<double> prev(n, -1);
    double prev_set = -1;
    for (const auto& s : rec.sets) {
      double lo = 1e300, hi = -1e300;
      for (size_t i = 0; i < n; ++i) {
        ASSERT_GT(s.members[i].stamp, prev[i]);
        prev[i] = s.members[i].stamp;
        lo = std::min(lo, s.members[i].stamp);
        hi = std::max(hi, s.members[i].stamp);
      }
      ASSERT_LE(hi - lo, o.max_interval);
      ASSERT_GT(s.stamp, prev_set);
      prev_set = s.stamp;
      ++sets;
    }
  }
  EXPECT_GT(sets, 1000u);
}

}  // namespace
}  // namespace rvc::sync
