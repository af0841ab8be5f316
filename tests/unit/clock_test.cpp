// Clock-driven dense monitoring (Checker::tick, Checker::next_deadline): a
// tick is an empty message at the tick's instant, verdict changes come with
// their exact times whenever the tick comes, and next_deadline() is never
// later than the first change. Values computed by hand; then random traces
// where ticks at deadlines and on a grid must give the verdicts messages
// alone give, each change reported by a tick at its very instant.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "engine/checker.hpp"
#include "test_util.hpp"

namespace rvc::engine {
namespace {

constexpr double kNever = std::numeric_limits<double>::infinity();
using TVs = std::vector<test::TV>;

// A Checker over one or more properties, fed as the runtime feeds it: a
// message at t closes [previous, t) with the values held until then.
class Clocked {
 public:
  explicit Clocked(const std::vector<std::string>& specs, bool emit_all = false)
      : checker_(TimeModel::Dense, emit_all, [this](const Verdict& v) {
          out_[v.property].emplace_back(v.time, v.value);
          reported_at_.push_back({v.time, now_});
        }) {
    for (size_t i = 0; i < specs.size(); ++i) checker_.add_property({"p" + std::to_string(i), specs[i]});
    values_.assign(checker_.atoms().size(), 0);
  }
  void message(double t, const std::map<std::string, int>& values) {
    now_ = t;
    checker_.step(seen_ ? last_ : 0, t, values_.data());
    const auto& tests = checker_.atoms().tests();
    for (const auto& [name, v] : values)
      for (size_t i = 0; i < tests.size(); ++i)  // a field no property tests is not in the table
        if (tests[i].to_string() == name) values_[i] = static_cast<uint8_t>(v);
    seen_ = true;
    last_ = t;
  }
  void tick(double t) {
    now_ = t;
    checker_.tick(t, values_.data());
  }
  double deadline() { return checker_.next_deadline(values_.data()); }
  // Ticks at each deadline before `until` (a runtime sleeping between messages).
  void tick_until(double until) {
    for (double d = deadline(); d < until; d = deadline()) {
      ticks_.push_back(d);
      tick(d);
      ASSERT_NE(deadline(), d) << "deadline stuck at " << d;
    }
  }
  const TVs& verdicts(int property = 0) { return out_["p" + std::to_string(property)]; }
  Checker& checker() { return checker_; }
  const std::vector<double>& ticks() const { return ticks_; }
  // (verdict time, the instant of the step or tick that reported it)
  const std::vector<std::pair<double, double>>& reported_at() const { return reported_at_; }

 private:
  Checker checker_;
  std::vector<uint8_t> values_;
  std::map<std::string, TVs> out_;
  std::vector<std::pair<double, double>> reported_at_;
  std::vector<double> ticks_;
  double now_ = 0, last_ = 0;
  bool seen_ = false;
};

// ---------------------------------------------------------------- by hand

// The example: alive on [0, 0.05), then silence. Without ticks the
// fall at 0.25 waits for the next message; a tick reports it with its time.
TEST(ClockTick, OnceFallsAtTheExactInstantThoughTheTickComesLater) {
  Clocked c({"once[0:0.2]{alive}"});
  c.message(0, {{"alive", 1}});
  c.message(0.05, {{"alive", 0}});
  EXPECT_EQ(c.verdicts(), (TVs{{0, true}}));
  EXPECT_EQ(c.deadline(), 0.25);
  c.tick(1.0);  // late: the verdict carries 0.25, not 1.0
  EXPECT_EQ(c.verdicts(), (TVs{{0, true}, {0.25, false}}));
  EXPECT_EQ(c.deadline(), kNever);  // alive stays false: nothing can change any more
  EXPECT_EQ(c.checker().clock(), 1.0);
  c.message(1.5, {{"alive", 1}});  // goes on from the tick: [1, 1.5) false, nothing new
  EXPECT_EQ(c.verdicts(), (TVs{{0, true}, {0.25, false}}));
  EXPECT_EQ(c.deadline(), 1.5);  // the value at the message's own instant is not told yet
  c.tick(1.5);
  EXPECT_EQ(c.verdicts(), (TVs{{0, true}, {0.25, false}, {1.5, true}}));
}

TEST(ClockTick, TickAtTheDeadlineReportsTheChangeThere) {
  Clocked c({"once[0:0.2]{alive}"});
  c.message(0, {{"alive", 1}});
  c.message(0.05, {{"alive", 0}});
  c.tick_until(10);
  EXPECT_EQ(c.ticks(), (std::vector<double>{0.25}));  // at 0.05 it is still true, as told
  EXPECT_EQ(c.verdicts(), (TVs{{0, true}, {0.25, false}}));
  EXPECT_EQ(c.reported_at().back(), (std::pair<double, double>{0.25, 0.25}));  // detected at the deadline
}

TEST(ClockTick, SilenceFromTheStartFallsAtTheBound) {
  // A sensor heard once at 0 then never: historically(once[0:0.2]{alive}) breaks for good at 0.2.
  Clocked c({"historically(once[0:0.2]{alive})"});
  c.message(0, {{"alive", 1}});
  c.message(0.001953125, {});  // a message that changes nothing (alive holds)
  c.message(0.0625, {{"alive", 0}});
  c.tick_until(100);
  EXPECT_EQ(c.verdicts(), (TVs{{0, true}, {0.2625, false}}));
  EXPECT_EQ(c.reported_at().back().second, 0.2625);
  EXPECT_EQ(c.deadline(), kNever);
}

// once[0.5:1]{p}, p on [1, 1.5): true on [1.5, 2.5). Both bounds are met
// exactly: true at 1.5 itself (closed lower edge), false at 2.5 itself.
TEST(ClockTick, BoundEdgesWithAPositiveLowerBound) {
  Clocked c({"once[0.5:1]{p}"});
  c.message(0, {{"p", 0}});
  c.message(1, {{"p", 1}});
  EXPECT_EQ(c.verdicts(), (TVs{{0, false}}));
  EXPECT_EQ(c.deadline(), 1.5);  // p holds from 1: once turns true at 1 + 0.5
  c.message(1.5, {{"p", 0}});
  EXPECT_EQ(c.deadline(), 1.5);  // the rise at 1.5 itself, not reported by the step [1, 1.5)
  c.tick(1.5);
  EXPECT_EQ(c.verdicts(), (TVs{{0, false}, {1.5, true}}));
  EXPECT_EQ(c.deadline(), 2.5);
  c.tick(2.4999);
  EXPECT_EQ(c.verdicts().size(), 2u);
  c.tick(2.5);
  EXPECT_EQ(c.verdicts(), (TVs{{0, false}, {1.5, true}, {2.5, false}}));
  EXPECT_EQ(c.deadline(), kNever);
}

TEST(ClockTick, HeldTrueWithALowerBoundRisesOnceThenNeverWakesAgain) {
  Clocked c({"once[0.5:1]{p}"});
  c.message(1, {{"p", 1}});
  c.tick_until(50);
  EXPECT_EQ(c.ticks(), (std::vector<double>{1.5}));  // the rise; then p's window and the held p are one
  EXPECT_EQ(c.verdicts(), (TVs{{0, false}, {1.5, true}}));
}

// historically[0.1:0.2]{ok}, ok false on [1, 1.05): its violations shift to
// [1.1, 1.25), so historically is false exactly there.
TEST(ClockTick, HistoricallyWithBounds) {
  Clocked c({"historically[0.1:0.2]{ok}", "historically[0:0.2]{ok}"});
  c.message(0, {{"ok", 1}});
  c.message(1, {{"ok", 0}});
  c.message(1.05, {{"ok", 1}});
  c.tick_until(10);
  EXPECT_EQ(c.verdicts(0), (TVs{{0, true}, {1.1, false}, {1.25, true}}));
  EXPECT_EQ(c.verdicts(1), (TVs{{0, true}, {1, false}, {1.25, true}}));
  for (double t : {1.1, 1.25}) EXPECT_NE(std::find(c.ticks().begin(), c.ticks().end(), t), c.ticks().end()) << t;
}

// {a} since[0:0.5] {b}: b on [0, 1), a throughout: true until 1.5; a falls
// at 2 (message): false there, at once.
TEST(ClockTick, SinceWithBounds) {
  Clocked c({"{a} since[0:0.5] {b}", "{a} since[0.25:0.5] {b}"});
  c.message(0, {{"a", 1}, {"b", 1}});
  c.message(1, {{"b", 0}});
  EXPECT_EQ(c.deadline(), 1.5);
  c.tick_until(10);
  EXPECT_EQ(c.verdicts(0), (TVs{{0, true}, {1.5, false}}));
  EXPECT_EQ(c.verdicts(1), (TVs{{0, false}, {0.25, true}, {1.5, false}}));
  Clocked d({"{a} since[0:0.5] {b}"});
  d.message(0, {{"a", 1}, {"b", 1}});
  d.message(1, {{"b", 0}});
  d.message(1.25, {{"a", 0}});
  EXPECT_EQ(d.deadline(), 1.25);  // the left side failing at the message
  d.tick_until(10);
  EXPECT_EQ(d.verdicts(), (TVs{{0, true}, {1.25, false}}));
}

TEST(ClockTick, NestedDeadlinesFollowEachOther) {
  // not once[0:0.2]{alive} rises at 0.25; once[0.5:1] of it rises 0.5 later, at 0.75.
  Clocked c({"once[0.5:1](not once[0:0.2]{alive})"});
  c.message(0, {{"alive", 1}});
  c.message(0.05, {{"alive", 0}});
  c.tick_until(10);
  EXPECT_EQ(c.verdicts(), (TVs{{0, false}, {0.75, true}}));
  EXPECT_EQ(c.reported_at().back().second, 0.75);
}

// Ties: two properties changing at the same instant, a tick exactly at a
// change, a message at a tick's instant.
TEST(ClockTick, Ties) {
  Clocked c({"once[0:1]{p}", "historically[0:1](not {p})", "{p}"});
  c.message(0, {{"p", 1}});
  c.message(1, {{"p", 0}});
  EXPECT_EQ(c.deadline(), 1);  // {p} falls at 1 itself
  c.tick(1);
  EXPECT_EQ(c.deadline(), 2);
  c.tick(2);
  EXPECT_EQ(c.verdicts(0), (TVs{{0, true}, {2, false}}));
  EXPECT_EQ(c.verdicts(1), (TVs{{0, false}, {2, true}}));
  EXPECT_EQ(c.verdicts(2), (TVs{{0, true}, {1, false}}));
  // A message stamped with the tick's instant: its values hold from 2, and
  // the value at 2 is told again (the tick told it with the values held then).
  c.message(2, {{"p", 1}});
  c.tick(2);
  c.tick(1.5);  // behind the clock: nothing
  c.message(3, {});
  EXPECT_EQ(c.verdicts(0), (TVs{{0, true}, {2, false}, {2, true}}));
  EXPECT_EQ(c.verdicts(2), (TVs{{0, true}, {1, false}, {2, true}}));
}

TEST(ClockTick, EmitAllReportsTheTickOnce) {
  Clocked c({"once[0:0.2]{alive}"}, /*emit_all=*/true);
  c.message(0, {{"alive", 1}});
  c.message(0.05, {{"alive", 0}});
  c.tick(0.25);
  c.message(0.5, {});
  // [0, 0.05): T; [0.05, 0.25): T (a new piece, emit_all); the tick at 0.25: F; [0.25, 0.5) not again.
  EXPECT_EQ(c.verdicts(), (TVs{{0, true}, {0.05, true}, {0.25, false}}));
}

TEST(ClockTick, DiscreteTimeHasNoClock) {
  std::vector<double> times;
  Checker c(TimeModel::Discrete, false, [&](const Verdict& v) { times.push_back(v.time); });
  c.add_property({"p", "once[0:2]{p}"});
  std::vector<uint8_t> values(c.atoms().size(), 1);
  c.step(values.data());
  c.tick(5, values.data());
  EXPECT_EQ(c.next_deadline(values.data()), kNever);
  EXPECT_EQ(times, (std::vector<double>{0}));
}

TEST(ClockTick, DataReferences) {
  // Every value seen must be seen again within 0.5 (forall over the ids met).
  std::vector<test::TV> out;
  Checker c(TimeModel::Dense, false, [&](const Verdict& v) { out.emplace_back(v.time, v.value); });
  c.add_property({"p", "forall[x]. (once{id: *x} -> once[0:0.5]{id: *x})"});
  std::vector<uint8_t> values(c.atoms().size(), 0);
  std::vector<uint32_t> bound(c.atoms().size(), 0);
  c.step(0, 1, values.data(), bound.data());  // [0, 1): no id yet
  bound[0] = 7;                                // {id: *x} reads value id 7 from 1
  c.tick(1, values.data(), bound.data());
  EXPECT_EQ(c.next_deadline(values.data(), bound.data()), kNever);  // held: seen all the time
  c.step(1, 2, values.data(), bound.data());  // message at 2: id 9 from there
  bound[0] = 9;
  c.tick(2, values.data(), bound.data());
  EXPECT_EQ(c.next_deadline(values.data(), bound.data()), 2.5);  // 7 was last seen just before 2
  c.tick(3, values.data(), bound.data());
  EXPECT_EQ(out, (TVs{{0, true}, {2.5, false}}));
}

// once[0:0.2]{x > 1} with --robustness: x = 3 on [0, 0.05), then 0: the
// window's maximum 2 leaves at 0.25, when the held -1 is all that is left.
TEST(ClockTick, RobustnessAtTheDeadline) {
  std::vector<std::pair<double, double>> out;
  Checker c(TimeModel::Dense, false, [&](const Verdict& v) { out.emplace_back(v.time, v.robustness); });
  c.enable_robustness();
  c.add_property({"p", "once[0:0.2]{x > 1}"});
  c.add_property({"q", "historically[0.25:0.5]{x > 1}"});
  double margin[1] = {2};
  c.step_robust(0, 0.05, margin);
  margin[0] = -1;
  // p: 2 until [0, 0.05) leaves its window; q: +inf (empty window) until 2 enters at 0.25.
  EXPECT_EQ(c.next_deadline_robust(margin), 0.25);
  c.tick_robust(0.25, margin);
  EXPECT_EQ(c.next_deadline_robust(margin), 0.3);  // q: the held -1 enters its window at 0.05 + 0.25
  c.tick_robust(0.3, margin);
  // q: its window [t-0.5, t-0.25] is empty before 0.25 (+inf), then holds 2 until the -1 enters.
  EXPECT_EQ(c.next_deadline_robust(margin), kNever);
  EXPECT_EQ(out, (std::vector<std::pair<double, double>>{{0, 2}, {0, kNever}, {0.25, -1}, {0.25, 2}, {0.3, -1}}));
}

// ---------------------------------------------------------------- random

// Random formulas over {p}, {q}, messages at multiples of 1/8 (dyadic, so
// every sum of times and bounds is exact): the verdicts of (a) messages
// alone, (b) ticks at every deadline and (c) ticks on a fine grid are the
// same list, and in (b) each change between messages is reported by the
// tick at its own instant: no deadline came after a change.
std::string random_formula(std::mt19937& rng, int depth) {
  const auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<unsigned>(n)); };
  if (depth == 0 || pick(5) == 0) return pick(2) ? "{p}" : "{q}";
  static const char* bounds[] = {"", "[0:0.5]", "[0.25:0.75]", "[0.5:]", "[:1.25]", "[0:0.125]", "[1:1]"};
  const std::string b = bounds[pick(7)];
  const auto sub = [&] { return "(" + random_formula(rng, depth - 1) + ")"; };
  switch (pick(7)) {
    case 0: return "not " + sub();
    case 1: return "once" + b + " " + sub();
    case 2: return "historically" + b + " " + sub();
    case 3: return sub() + " since" + b + " " + sub();
    case 4: return sub() + " and " + sub();
    case 5: return sub() + " or " + sub();
    default: return sub() + " -> " + sub();
  }
}

TEST(ClockDeadline, NeverLaterThanTheFirstChangeOnRandomTraces) {
  std::mt19937 rng(2026);
  for (int round = 0; round < 300; ++round) {
    std::vector<std::string> specs;
    for (int k = 0; k < 4; ++k) specs.push_back(random_formula(rng, 1 + static_cast<int>(rng() % 4)));
    std::vector<std::pair<double, std::map<std::string, int>>> trace;
    double t = (rng() % 3) * 0.125;
    for (int n = 3 + static_cast<int>(rng() % 12); n > 0; --n) {
      std::map<std::string, int> m;
      if (rng() % 4) m["p"] = static_cast<int>(rng() % 2);
      if (rng() % 4) m["q"] = static_cast<int>(rng() % 2);
      trace.emplace_back(t, m);
      t += (1 + rng() % 12) * 0.125;
    }
    Clocked plain(specs), at_deadlines(specs), on_grid(specs);
    for (size_t i = 0; i < trace.size(); ++i) {
      const auto& [time, values] = trace[i];
      if (i > 0)
        for (double g = std::floor(trace[i - 1].first / 0.03) * 0.03; g < time; g += 0.03) on_grid.tick(g);
      plain.message(time, values);
      at_deadlines.message(time, values);
      on_grid.message(time, values);
      if (i + 1 < trace.size()) at_deadlines.tick_until(trace[i + 1].first);
    }
    for (int k = 0; k < 4; ++k) {
      // Ticks report the value at their instant, which messages alone report with the next segment:
      // compare up to the last message.
      TVs want = plain.verdicts(k), deadline_ticks, grid_ticks;
      for (const auto& v : at_deadlines.verdicts(k))
        if (v.first < trace.back().first) deadline_ticks.push_back(v);
      for (const auto& v : on_grid.verdicts(k))
        if (v.first < trace.back().first) grid_ticks.push_back(v);
      ASSERT_EQ(deadline_ticks, want) << specs[k] << " (round " << round << ")";
      ASSERT_EQ(grid_ticks, want) << specs[k] << " (round " << round << ")";
    }
    for (const auto& [time, reported] : at_deadlines.reported_at()) {
      if (time < trace.front().first) continue;  // before the first message nothing ticks
      ASSERT_EQ(reported, time) << "a change at " << time << " reported only at " << reported << " in "
                                << specs[0] << " | " << specs[1] << " | " << specs[2] << " | " << specs[3]
                                << " (round " << round << ")";
    }
  }
}

}  // namespace
}  // namespace rvc::engine
