// The monitor loop on a clock (issue 26): StreamClock's mapping of stream
// time to the steady clock, checked with a fake time source; then the loop
// itself with a scripted source that goes silent: the fall of a bounded
// operator must be published at its exact instant while the source is still
// silent (it resumes only once it sees the verdict, or after 5 s, when the
// test fails), and the loop must tick only at deadlines, not on a period.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "io/cdr_codec.hpp"
#include "msg/type_registry.hpp"
#include "runtime/monitor_loop.hpp"
#include "runtime/pipeline.hpp"
#include "runtime/ros_clock.hpp"
#include "runtime/stream_clock.hpp"
#include "runtime/synced_pipeline.hpp"
#include "runtime/verdict_outputs.hpp"

namespace rvc::runtime {
namespace {

using Steady = std::chrono::steady_clock;
using namespace std::chrono_literals;

// A fake time source: the test sets both clocks.
struct FakeTime {
  double wall = 1.7e9;
  Steady::time_point steady = Steady::time_point(1000s);
  TimeSource source() {
    return TimeSource{[this] { return wall; }, [this] { return steady; }};
  }
  void advance(double seconds) {
    wall += seconds;
    steady += std::chrono::duration_cast<Steady::duration>(std::chrono::duration<double>(seconds));
  }
};

double seconds(Steady::duration d) { return std::chrono::duration<double>(d).count(); }

TEST(StreamClock, DoesNotRunBeforeAStampedMessage) {
  FakeTime t;
  StreamClock c(ClockKind::Wall, t.source());
  EXPECT_FALSE(c.running());
  EXPECT_EQ(c.when(1.7e9, t.steady), Steady::time_point::max());
  c.on_message(std::nan(""), t.steady);  // no stamp: still not running
  EXPECT_FALSE(c.running());
}

TEST(StreamClock, WallMapsEpochDeadlinesToSteadyInstants) {
  FakeTime t;
  StreamClock c(ClockKind::Wall, t.source());
  c.on_message(t.wall - 0.001, t.steady);  // a stamp 1 ms old: the clock is the system clock, not the stamp
  ASSERT_TRUE(c.running());
  EXPECT_DOUBLE_EQ(c.now(t.steady), t.wall);
  // Epoch seconds in a double resolve 0.24 us: the mapping is that exact.
  EXPECT_NEAR(seconds(c.when(t.wall + 0.2, t.steady) - t.steady), 0.2, 1e-6);
  EXPECT_EQ(c.when(t.wall - 5, t.steady), t.steady);  // reached already: now
  EXPECT_EQ(c.when(INFINITY, t.steady), Steady::time_point::max());
  t.advance(0.15);  // both clocks move: 50 ms left
  EXPECT_NEAR(seconds(c.when(t.wall + 0.05, t.steady) - t.steady), 0.05, 1e-6);
}

TEST(StreamClock, StampsRunFromTheLastStampAtRealTimeSpeed) {
  FakeTime t;
  StreamClock c(ClockKind::Stamps, t.source());
  c.on_message(10.0, t.steady);
  t.advance(0.25);
  EXPECT_NEAR(c.now(t.steady), 10.25, 1e-9);
  EXPECT_NEAR(seconds(c.when(10.5, t.steady) - t.steady), 0.25, 1e-9);
  c.on_message(10.3, t.steady);  // a new message sets the clock to its stamp, even behind
  EXPECT_NEAR(c.now(t.steady), 10.3, 1e-9);
}

TEST(StreamClock, AutoPicksWallForEpochStampsElseStamps) {
  FakeTime t;
  StreamClock epoch(ClockKind::Auto, t.source());
  epoch.on_message(t.wall - 30, t.steady);  // 30 s off: still epoch seconds
  EXPECT_EQ(epoch.kind(), ClockKind::Wall);
  StreamClock sim(ClockKind::Auto, t.source());
  sim.on_message(12.5, t.steady);  // simulation time from 0
  EXPECT_EQ(sim.kind(), ClockKind::Stamps);
  StreamClock old(ClockKind::Auto, t.source());
  old.on_message(t.wall - 3600, t.steady);  // a replayed recording, an hour old
  EXPECT_EQ(old.kind(), ClockKind::Stamps);
  StreamClock off(ClockKind::Off, t.source());
  off.on_message(t.wall, t.steady);
  EXPECT_FALSE(off.running());
}

TEST(StreamClock, ParsesItsNames) {
  EXPECT_EQ(parse_clock("wall"), ClockKind::Wall);
  EXPECT_EQ(parse_clock("stamps"), ClockKind::Stamps);
  EXPECT_EQ(parse_clock("auto"), ClockKind::Auto);
  EXPECT_EQ(parse_clock("off"), ClockKind::Off);
  EXPECT_FALSE(parse_clock("ros").has_value());  // ros=URI: the command parses it
}

// ROS time (use_sim_time) is the latest /clock value: it stands still
// between /clock messages, whatever the host's clocks do; a deadline is
// reached when /clock passes it (never by sleeping); a /clock going back is
// refused; stamps of messages do not move it.
TEST(StreamClock, RosTimeIsTheLatestClockValue) {
  FakeTime t;
  StreamClock c(ClockKind::Ros, t.source());
  c.on_message(5.0, t.steady);  // a message's stamp: not ROS time
  EXPECT_FALSE(c.running());
  EXPECT_EQ(c.when(0.0, t.steady), Steady::time_point::max());  // before the first /clock nothing ticks
  ASSERT_TRUE(c.set_ros_time(2.0));
  ASSERT_TRUE(c.running());
  t.advance(100);  // an hour of host time changes nothing
  EXPECT_EQ(c.now(t.steady), 2.0);
  EXPECT_EQ(c.when(1.5, t.steady), t.steady);  // passed: due now
  EXPECT_EQ(c.when(2.0, t.steady), t.steady);  // reached exactly: due now
  EXPECT_EQ(c.when(2.0 + 1e-9, t.steady), Steady::time_point::max());  // only /clock can bring it
  EXPECT_FALSE(c.set_ros_time(1.0));  // backwards (a reset, a looped bag): ignored
  EXPECT_EQ(c.now(t.steady), 2.0);
  EXPECT_TRUE(c.set_ros_time(2.0));  // the same time again: no harm
  EXPECT_TRUE(c.set_ros_time(3.5));
  EXPECT_EQ(c.when(3.0, t.steady), t.steady);
  EXPECT_FALSE(StreamClock(ClockKind::Wall, t.source()).set_ros_time(1.0));  // only the ros clock takes /clock
}

// A /clock sample: typed CDR (as ROS 2 publishes it on DDS or rmw_zenoh) or
// JSON (a Time or seconds, as `rvc echo` prints it); anything else refused.
TEST(RosClockReader, ReadsCdrAndJsonClocks) {
  msg::TypeRegistry registry;
  const msg::MessageType& type = registry.resolve("rosgraph_msgs/msg/Clock");
  RosClockReader reader(type);
  std::string cdr, error;
  ASSERT_TRUE(io::json_to_cdr(type, R"({"clock":{"sec":3,"nanosec":500000000}})", cdr, error)) << error;
  ASSERT_EQ(cdr.size(), 12u);  // header, int32 sec, uint32 nanosec
  double t = 0;
  ASSERT_TRUE(reader.read(cdr, t, error)) << error;
  EXPECT_EQ(t, 3.5);
  ASSERT_TRUE(reader.read(R"({"clock":{"sec":7,"nanosec":250000000}})", t, error)) << error;
  EXPECT_EQ(t, 7.25);
  ASSERT_TRUE(reader.read(R"({"clock":2.125})", t, error)) << error;
  EXPECT_EQ(t, 2.125);
  EXPECT_FALSE(reader.read(R"({"time":1})", t, error));
  EXPECT_FALSE(reader.read("not json", t, error));
  EXPECT_FALSE(reader.read(std::string("\0\1\0\0\3", 5), t, error));  // a truncated sample
}

using Verdicts = std::vector<std::pair<double, bool>>;

// Ticks at every deadline until none is left (at most 10): what the loop does
// over a long silence.
std::vector<double> tick_through(Feed& feed) {
  std::vector<double> ticks;
  for (double d = feed.next_deadline(); d < INFINITY && ticks.size() < 10; d = feed.next_deadline()) {
    feed.tick(d);
    ticks.push_back(d);
  }
  return ticks;
}

// The Feed contract on Pipeline, by hand: after {alive} at 0.25 and {!alive}
// at 0.5, the only deadline is 0.625, where once[0:0.125] falls (the value
// at 0.5 is true, as already reported: verdicts are changes), then none.
TEST(FeedTicks, PipelineTicksAtItsDeadlines) {
  Verdicts out;
  PipelineOptions po;
  po.model = engine::TimeModel::Dense;
  po.origin = runtime::Origin::Zero;  // the timeline from 0, as these expectations count it
  Pipeline p({{"p", "once[0:0.125]{alive}"}}, po, [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  EXPECT_EQ(p.next_deadline(), INFINITY);  // nothing taken yet: no clock
  EXPECT_TRUE(std::isnan(p.last_stamp()));
  p.feed(R"({"time":0.25,"alive":true})", 1);
  p.feed(R"({"time":0.5,"alive":false})", 2);
  EXPECT_EQ(p.last_stamp(), 0.5);
  EXPECT_EQ(tick_through(p), (std::vector<double>{0.625}));
  EXPECT_EQ(out, (Verdicts{{0, false}, {0.25, true}, {0.625, false}}));
  p.tick(0.1);  // behind the clock: nothing
  p.feed(R"({"time":0.6,"alive":true})", 3);  // before the ticks' 0.625: checked there, counted
  EXPECT_EQ(p.stats().late_to_clock, 1u);
  EXPECT_EQ(p.stats().accepted, 3u);
  tick_through(p);
  EXPECT_EQ(out.back(), (std::pair<double, bool>{0.625, true}));
}

TEST(FeedTicks, DiscreteTimeHasNoDeadline) {
  PipelineOptions po;
  Pipeline p({{"p", "once[0:2]{alive}"}}, po, [](const engine::Verdict&) {});
  p.feed(R"({"alive":true})", 1);
  EXPECT_EQ(p.next_deadline(), INFINITY);
}

// SyncedPipeline ticks with its combined values: input a stops being alive
// at 0.5 while b goes on to 0.51; the fall comes at 0.625 by a tick.
TEST(FeedTicks, SyncedPipelineTicksWithTheLatestSet) {
  Verdicts out;
  PipelineOptions po;
  po.model = engine::TimeModel::Dense;
  SyncOptions so;
  so.policy = sync::PolicyKind::Merge;
  SyncedPipeline p({{"p", "once[0:0.125]{a.alive}"}}, po, {{"a", "test:a", nullptr, ""}, {"b", "test:b", nullptr, ""}},
                   so, [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  EXPECT_EQ(p.next_deadline(), INFINITY);
  p.feed_at(0, R"({"time":0.25,"alive":true})", 1, 0);
  p.feed_at(1, R"({"time":0.26,"v":1})", 2, 0);
  p.feed_at(0, R"({"time":0.5,"alive":false})", 3, 0);
  p.feed_at(1, R"({"time":0.51,"v":2})", 4, 0);
  p.end_of_input();  // every set formed
  EXPECT_EQ(p.last_stamp(), 0.51);
  tick_through(p);
  EXPECT_EQ(out.back(), (std::pair<double, bool>{0.625, false}));
}

// Ticks and timing atoms together (issue 26): the publisher of a heartbeat
// stops after 0.5; {@age <= 0.25} falls at 0.75 (dense: true on [last,
// last + 0.25), docs/semantics.md) by a tick, with no message after it; the
// field itself ({alive}) holds true forever, so only the timing atom sees it.
TEST(FeedTicks, TimingAtomsFallByATickDuringSilence) {
  Verdicts out;
  PipelineOptions po;
  po.model = engine::TimeModel::Dense;
  po.origin = runtime::Origin::Zero;  // the timeline from 0, as these expectations count it
  Pipeline p({{"p", "{@age <= 0.25} and {alive}"}}, po,
             [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  p.feed(R"({"time":0.25,"alive":true})", 1);
  p.feed(R"({"time":0.5,"alive":true})", 2);
  EXPECT_EQ(tick_through(p), (std::vector<double>{0.75}));  // the value at 0.5 is the one already told
  EXPECT_EQ(out, (Verdicts{{0, false}, {0.25, true}, {0.75, false}}));
  EXPECT_EQ(p.next_deadline(), INFINITY);  // nothing more can change while silent
  // The next heartbeat restores it at its own instant, and it falls again
  // 0.25 later: the timed atoms go on from the tick.
  p.feed(R"({"time":2,"alive":true})", 3);
  EXPECT_EQ(tick_through(p), (std::vector<double>{2, 2.25}));
  EXPECT_EQ(out, (Verdicts{{0, false}, {0.25, true}, {0.75, false}, {2, true}, {2.25, false}}));
}

// A rate: count[0:1](@arrived) >= 3 with heartbeats at 0.25, 0.5, 0.75 holds
// from 0.75 until the first leaves the window (t - 1, t] at 1.25, found by a
// tick while nothing arrives (same instants as `rvc check` on the file).
TEST(FeedTicks, WindowCountDropsByATickDuringSilence) {
  Verdicts out;
  PipelineOptions po;
  po.model = engine::TimeModel::Dense;
  po.origin = runtime::Origin::Zero;  // the timeline from 0, as these expectations count it
  Pipeline p({{"p", "{count[0:1](@arrived) >= 3}"}}, po,
             [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  p.feed(R"({"time":0.25})", 1);
  p.feed(R"({"time":0.5})", 2);
  p.feed(R"({"time":0.75})", 3);
  tick_through(p);
  EXPECT_EQ(out, (Verdicts{{0, false}, {0.75, true}, {1.25, false}}));
}

// Named inputs: a's age falls by a tick while b goes on delivering until
// 0.51 and then everything is silent ({a.@age <= 0.25}: a last at 0.5).
TEST(FeedTicks, SyncedTimingAtomsFallByATick) {
  Verdicts out;
  PipelineOptions po;
  po.model = engine::TimeModel::Dense;
  SyncOptions so;
  so.policy = sync::PolicyKind::Merge;
  SyncedPipeline p({{"p", "{a.@age <= 0.25}"}}, po, {{"a", "test:a", nullptr, ""}, {"b", "test:b", nullptr, ""}},
                   so, [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  p.feed_at(0, R"({"time":0.25})", 1, 0);
  p.feed_at(1, R"({"time":0.26})", 2, 0);
  p.feed_at(0, R"({"time":0.5})", 3, 0);
  p.feed_at(1, R"({"time":0.51})", 4, 0);
  p.end_of_input();
  tick_through(p);
  EXPECT_EQ(out.back(), (std::pair<double, bool>{0.75, false}));
  EXPECT_EQ(p.next_deadline(), INFINITY);
}

// Verdict lines, and a signal to the source when one arrives.
struct Collected {
  std::mutex mu;
  std::condition_variable changed;
  std::vector<std::string> lines;
  // A ClockSource has handed all its frames to the loop's queue (one FIFO for
  // every source): a data source that waits for it ends after them.
  bool clock_sent = false;
  bool has(const std::string& text) {
    for (const auto& l : lines)
      if (l.find(text) != std::string::npos) return true;
    return false;
  }
};

class CollectingSink final : public transport::Sink {
 public:
  explicit CollectingSink(Collected& c) : c_(c) {}
  void put(std::string_view payload, uint64_t) override {
    std::lock_guard lock(c_.mu);
    c_.lines.emplace_back(payload);
    c_.changed.notify_all();
  }
  void put_eos(uint64_t) override {}

 private:
  Collected& c_;
};

// Publishes `before`, waits (as a silent publisher) until the verdict
// `awaited` is out or 5 s passed, notes which, then publishes `after` and
// its end-of-stream marker.
class SilentSource final : public transport::Source {
 public:
  SilentSource(Collected& c, std::vector<std::string> before, std::string awaited, std::vector<std::string> after,
               std::chrono::milliseconds patience)
      : c_(c), before_(std::move(before)), awaited_(std::move(awaited)), after_(std::move(after)), patience_(patience) {}
  ~SilentSource() override { stop(); }
  void start(transport::FrameHandler handler) override {
    thread_ = std::thread([this, handler] {
      uint64_t seq = 0;
      auto send = [&](const std::string& p) {
        transport::Frame f;
        f.payload = p;
        f.seq = ++seq;
        f.publisher = 1;
        handler(f);
      };
      for (const auto& p : before_) send(p);
      {
        std::unique_lock lock(c_.mu);
        seen_before_resume = c_.changed.wait_for(
            lock, patience_, [&] { return c_.has(awaited_) && (!after_clock || c_.clock_sent); });
      }
      for (const auto& p : after_) send(p);
      transport::Frame eos;
      eos.eos = true;
      eos.seq = seq;
      eos.publisher = 1;
      handler(eos);
    });
  }
  void stop() override {
    if (thread_.joinable()) thread_.join();
  }
  bool seen_before_resume = false;
  bool after_clock = false;  // also wait until the ClockSource sent everything
  // The loop may check on this source's thread (LoopOptions::Handoff::Inline, Zenoh's case).
  bool may_block = false;
  bool handler_may_block() const override { return may_block; }

 private:
  Collected& c_;
  std::vector<std::string> before_;
  std::string awaited_;
  std::vector<std::string> after_;
  std::chrono::milliseconds patience_;
  std::thread thread_;
};

struct LoopRun {
  Collected collected;
  bool seen_before_resume = false;
  uint64_t ticks = 0;
  std::string stats;
};

void run_loop(LoopRun& r, const std::string& spec, ClockKind clock, std::vector<std::string> before,
              const std::string& awaited, std::vector<std::string> after, double tick_bound = 0,
              bool inline_handoff = false) {
  std::vector<std::unique_ptr<transport::Sink>> sinks;
  sinks.push_back(std::make_unique<CollectingSink>(r.collected));
  VerdictOutputs outputs(std::move(sinks), false);
  PipelineOptions po;
  po.model = engine::TimeModel::Dense;
  po.position_name = "seq";
  Pipeline pipeline({{"p", spec}}, po, [&](const engine::Verdict& v) { outputs.put(v); });
  LoopOptions lo;
  lo.input = "test";
  lo.exit_on_eos = true;
  lo.clock = clock;
  lo.tick_bound = tick_bound;
  MonitorLoop loop(pipeline, outputs, nullptr, lo);
  // Without a clock nothing can come: half a second shows it (with one, the
  // verdict ends the wait, and 5 s only bound a failing run).
  SilentSource source(r.collected, std::move(before), awaited, std::move(after),
                      clock == ClockKind::Off || awaited == "never" ? 500ms : 5s);
  source.may_block = inline_handoff;
  loop.run(source);
  r.seen_before_resume = source.seen_before_resume;
  r.ticks = loop.ticks();
  r.stats = loop.final_stats();
}

// alive until 0.5, then false and silence: once[0:0.125]{alive} falls at
// 0.625 exactly, a tick's work (by hand: the operand last held at 0.5).
TEST(MonitorLoopClock, ReportsAFallDuringSilenceAtItsInstant) {
  LoopRun r;
  run_loop(r, "once[0:0.125]{alive}", ClockKind::Stamps,
           {R"({"time":0.25,"alive":true})", R"({"time":0.5,"alive":false})"},
           R"({"time":0.625,"property":"p","value":false})", {R"({"time":5,"alive":true})"});
  EXPECT_TRUE(r.seen_before_resume) << "the fall at 0.625 was not published while the source was silent";
  // Ticks at deadlines only: the message's own instants and the fall, not
  // one per polling period over the silence.
  EXPECT_LE(r.ticks, 6u);
  EXPECT_NE(r.stats.find(R"("clock":"stamps")"), std::string::npos) << r.stats;
  EXPECT_NE(r.stats.find(R"("late_to_clock":0)"), std::string::npos) << r.stats;
}

// The same on the inline hand-off (the source's thread checks, the loop's
// thread ticks, both under the engine's lock): the fall is still published
// at its instant during the silence, and the counters say which ran.
TEST(MonitorLoopClock, ReportsAFallDuringSilenceInline) {
  LoopRun r;
  run_loop(r, "once[0:0.125]{alive}", ClockKind::Stamps,
           {R"({"time":0.25,"alive":true})", R"({"time":0.5,"alive":false})"},
           R"({"time":0.625,"property":"p","value":false})", {R"({"time":5,"alive":true})"}, 0, true);
  EXPECT_TRUE(r.seen_before_resume) << "the fall at 0.625 was not published while the source was silent";
  EXPECT_LE(r.ticks, 6u);
  EXPECT_NE(r.stats.find(R"("handoff":"inline")"), std::string::npos) << r.stats;
  EXPECT_NE(r.stats.find(R"("checked":3)"), std::string::npos) << r.stats;
  EXPECT_TRUE(r.collected.has(R"({"time":5,"property":"p","value":true})"));
}

TEST(MonitorLoopClock, CountsMessagesLateToTheClockInline) {
  LoopRun r;
  run_loop(r, "once[0:0.125]{alive}", ClockKind::Stamps,
           {R"({"time":0.25,"alive":true})", R"({"time":0.5,"alive":false})"},
           R"({"time":0.625,"property":"p","value":false})", {R"({"time":0.6,"alive":true})"}, 0, true);
  EXPECT_TRUE(r.seen_before_resume);
  EXPECT_NE(r.stats.find(R"("late_to_clock":1)"), std::string::npos) << r.stats;
  EXPECT_NE(r.stats.find(R"("handoff":"inline")"), std::string::npos) << r.stats;
}

// A source whose thread must not block gets the queue even when inline is
// asked for by default (auto): the counters say "queue".
TEST(MonitorLoopClock, AutoKeepsTheQueueForSourcesThatMustNotBlock) {
  LoopRun r;
  run_loop(r, "{alive}", ClockKind::Off, {R"({"time":0.25,"alive":true})"}, "never", {});
  EXPECT_NE(r.stats.find(R"("handoff":"queue")"), std::string::npos) << r.stats;
}

// Without a clock the fall is reported only once the next message comes.
TEST(MonitorLoopClock, WithoutAClockTheFallWaitsForTheNextMessage) {
  LoopRun r;
  run_loop(r, "once[0:0.125]{alive}", ClockKind::Off,
           {R"({"time":0.25,"alive":true})", R"({"time":0.5,"alive":false})"},
           R"({"time":0.625,"property":"p","value":false})", {R"({"time":0.75,"alive":true})"});
  EXPECT_FALSE(r.seen_before_resume);
  EXPECT_TRUE(r.collected.has(R"({"time":0.625,"property":"p","value":false})"));  // after the resume
  EXPECT_EQ(r.ticks, 0u);
}

// historically[0:0.125]{ok} after ok turns true: rises at t + 0.125 during
// the silence (by hand: true at 0.5, so from 0.625 the window holds only true).
TEST(MonitorLoopClock, ReportsARiseDuringSilence) {
  LoopRun r;
  run_loop(r, "historically[0:0.125]{ok}", ClockKind::Stamps,
           {R"({"time":0.25,"ok":false})", R"({"time":0.5,"ok":true})"},
           R"({"time":0.625,"property":"p","value":true})", {R"({"time":5,"ok":true})"});
  EXPECT_TRUE(r.seen_before_resume);
}

// --tick: with no deadline at all ({alive} holds and nothing can change),
// the fallback still ticks during a silence; without it no tick is made.
TEST(MonitorLoopClock, TickBoundTicksWithoutDeadlines) {
  LoopRun bounded, plain;
  const std::vector<std::string> before = {R"({"time":0.25,"alive":true})"};
  run_loop(bounded, "{alive}", ClockKind::Stamps, before, "never", {R"({"time":5,"alive":true})"}, 0.02);
  EXPECT_GE(bounded.ticks, 3u);  // the message's own instant, then a half-second silence ticked every 20 ms
  run_loop(plain, "{alive}", ClockKind::Stamps, before, "never", {R"({"time":5,"alive":true})"});
  EXPECT_EQ(plain.ticks, 1u);  // only the message's own instant (true at 0.25); nothing due after it
}

// A message stamped before the instant ticks reached is still checked, at
// that instant, and counted (stamps clock; the tick at 0.625 came first).
TEST(MonitorLoopClock, CountsMessagesLateToTheClock) {
  LoopRun r;
  run_loop(r, "once[0:0.125]{alive}", ClockKind::Stamps,
           {R"({"time":0.25,"alive":true})", R"({"time":0.5,"alive":false})"},
           R"({"time":0.625,"property":"p","value":false})", {R"({"time":0.6,"alive":true})"});
  EXPECT_TRUE(r.seen_before_resume);
  EXPECT_NE(r.stats.find(R"("late_to_clock":1)"), std::string::npos) << r.stats;
  EXPECT_NE(r.stats.find(R"("checked":3)"), std::string::npos) << r.stats;
}

// A scripted /clock publisher: once `start_after` is out (the data are in),
// publishes `times` as JSON Clock messages at once, much faster than real
// time.
class ClockSource final : public transport::Source {
 public:
  ClockSource(Collected& c, std::string start_after, std::vector<double> times)
      : c_(c), start_after_(std::move(start_after)), times_(std::move(times)) {}
  ~ClockSource() override { stop(); }
  bool may_block = false;  // as SilentSource's
  bool handler_may_block() const override { return may_block; }
  void start(transport::FrameHandler handler) override {
    thread_ = std::thread([this, handler] {
      {
        std::unique_lock lock(c_.mu);
        if (!c_.changed.wait_for(lock, 5s, [&] { return c_.has(start_after_) || stopping_; })) return;
        if (stopping_) return;
      }
      for (double t : times_) {
        transport::Frame f;
        const std::string payload = R"({"clock":)" + std::to_string(t) + "}";
        f.payload = payload;
        handler(f);
      }
      std::lock_guard lock(c_.mu);
      c_.clock_sent = true;
      c_.changed.notify_all();
    });
  }
  void stop() override {
    {
      std::lock_guard lock(c_.mu);
      stopping_ = true;
      c_.changed.notify_all();
    }
    if (thread_.joinable()) thread_.join();
  }

 private:
  Collected& c_;
  std::string start_after_;
  std::vector<double> times_;
  bool stopping_ = false;
  std::thread thread_;
};

// --clock ros: alive until 1.0, then silence while /clock runs from 0 to 10
// (at once: far faster than real time) and goes back to 2 (a reset). The
// fall of once[0:2]{alive} at 3.0 (by hand: alive holds on [0.5, 1.0), so
// the window [t-2, t] holds a true instant until t = 3.0) is published
// while the data source is still silent; /clock is no checked input.
void ros_clock_run(bool inline_handoff) {
  Collected collected;
  std::vector<std::unique_ptr<transport::Sink>> sinks;
  sinks.push_back(std::make_unique<CollectingSink>(collected));
  VerdictOutputs outputs(std::move(sinks), false);
  PipelineOptions po;
  po.model = engine::TimeModel::Dense;
  po.position_name = "seq";
  Pipeline pipeline({{"p", "once[0:2]{alive}"}}, po, [&](const engine::Verdict& v) { outputs.put(v); });
  msg::TypeRegistry registry;
  LoopOptions lo;
  lo.input = "test";
  lo.exit_on_eos = true;
  lo.clock = ClockKind::Ros;
  lo.ros_clock_type = &registry.resolve("rosgraph_msgs/msg/Clock");
  std::vector<double> times;
  for (int i = 0; i <= 20; ++i) times.push_back(i * 0.5);
  times.push_back(2.0);
  // The data's first verdict is out once the second message is taken.
  ClockSource clock(collected, R"({"time":0.5,"property":"p","value":true})", times);
  lo.ros_clock = &clock;
  MonitorLoop loop(pipeline, outputs, nullptr, lo);
  SilentSource data(collected, {R"({"time":0.5,"alive":true})", R"({"time":1,"alive":false})"},
                    R"({"time":3,"property":"p","value":false})", {R"({"time":11,"alive":true})"}, 5s);
  // The data ends after every /clock message (counted below), not while the
  // clock thread still sends: on a slow run (TSan under load) 16 of 22 were.
  data.after_clock = true;
  data.may_block = clock.may_block = inline_handoff;
  loop.run(data);
  EXPECT_TRUE(data.seen_before_resume) << "the fall at 3.0 was not published while only /clock moved";
  const std::string stats = loop.final_stats();
  EXPECT_NE(stats.find(R"("clock":"ros")"), std::string::npos) << stats;
  EXPECT_NE(stats.find(R"("checked":3)"), std::string::npos) << stats;  // /clock is not checked
  EXPECT_NE(stats.find(R"("received":3)"), std::string::npos) << stats;
  EXPECT_NE(stats.find(R"("clock_messages":22)"), std::string::npos) << stats;
  EXPECT_NE(stats.find(R"("clock_backwards":1)"), std::string::npos) << stats;
  EXPECT_NE(stats.find(inline_handoff ? R"("handoff":"inline")" : R"("handoff":"queue")"), std::string::npos) << stats;
}

TEST(MonitorLoopClock, RosClockTicksAsClockPassesDeadlines) { ros_clock_run(false); }
// Both sources' threads check, in turn, under the engine's lock.
TEST(MonitorLoopClock, RosClockTicksAsClockPassesDeadlinesInline) { ros_clock_run(true); }

}  // namespace
}  // namespace rvc::runtime
