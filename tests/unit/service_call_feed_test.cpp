// ServiceCallFeed (--calls): service events paired into calls inside the run.
// Hand-computed: the next deadline is the open request's stamp + timeout, a
// tick there makes the call answered:false with no further event, and every
// event is counted once (paired, rejected, or dropped by reason).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "runtime/service_call_feed.hpp"

namespace rvc::runtime {
namespace {

std::string event(int type, int sec, int nanosec, int client, int seq) {
  return "{\"info\":{\"event_type\":" + std::to_string(type) + ",\"stamp\":{\"sec\":" + std::to_string(sec) +
         ",\"nanosec\":" + std::to_string(nanosec) + "},\"client_gid\":[" + std::to_string(client) +
         "],\"sequence_number\":" + std::to_string(seq) + "},\"request\":[],\"response\":[]}";
}

TEST(ServiceCallFeed, TheClockMakesAnUnansweredCallAtItsDeadline) {
  std::vector<std::pair<double, bool>> verdicts;
  PipelineOptions o;  // discrete: the calls' clock still runs
  Pipeline inner({{"p1", "{answered}"}}, o, [&](const engine::Verdict& v) { verdicts.emplace_back(v.time, v.value); });
  ServiceCallFeed feed(inner, nullptr, 0.5);
  EXPECT_EQ(feed.next_deadline(), std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isnan(feed.last_stamp()));
  feed.feed_input(0, event(0, 10, 0, 1, 1), 1);
  feed.feed_input(0, event(3, 10, 100000000, 1, 1), 2);  // answered after 0.1 s: made at once
  ASSERT_EQ(verdicts.size(), 1u);
  EXPECT_TRUE(verdicts[0].second);
  feed.feed_input(0, event(0, 11, 0, 2, 1), 3);  // never answered
  EXPECT_DOUBLE_EQ(feed.last_stamp(), 11.0);
  EXPECT_DOUBLE_EQ(feed.next_deadline(), 11.5);
  feed.tick(11.4);
  EXPECT_EQ(verdicts.size(), 1u);  // before the deadline: not decided
  feed.tick(11.5);
  ASSERT_EQ(verdicts.size(), 2u);
  EXPECT_FALSE(verdicts[1].second);
  EXPECT_EQ(feed.next_deadline(), std::numeric_limits<double>::infinity());
  testing::internal::CaptureStderr();
  feed.feed_input(0, "{\"data\":1}", 4);                  // rejected
  feed.feed_input(0, event(3, 11, 600000000, 2, 1), 5);   // after its deadline: an orphan
  feed.feed_input(0, event(2, 10, 90000000, 1, 1), 6);    // the server's response of call (1, 1): duplicate
  feed.feed_input(0, event(0, 12, 0, 1, 2), 7);           // pending at the end
  feed.end_of_input();
  feed.finish_report();
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("service event 4: no field 'info'"), std::string::npos) << err;
  EXPECT_EQ(feed.received(), 7u);
  EXPECT_EQ(feed.paired(), 3u);
  EXPECT_EQ(feed.stats().accepted, 2u);
  EXPECT_EQ(feed.stats().rejected, 1u);
  io::JsonObject dropped;
  feed.add_dropped(dropped);
  EXPECT_EQ(dropped.str(), "{\"duplicate\":1,\"orphan\":1,\"pending\":1}");
  EXPECT_EQ(feed.paired() + feed.stats().rejected + 3, feed.received());
}

}  // namespace
}  // namespace rvc::runtime
