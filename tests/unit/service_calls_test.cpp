// ServiceCalls (src/io/service_calls.hpp) on hand-computed traces of service
// events: answered, late, never answered, out-of-order responses, two clients
// with the same sequence numbers, both sides of one call, orphans, bad lines.
#include "io/service_calls.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

using rvc::io::ServiceCalls;

// One event line: type 0..3, time in ms, client id (one byte of the gid), sequence number.
std::string event(int type, int ms, int client, int seq, const std::string& request = "",
                  const std::string& response = "") {
  std::string gid = "[" + std::to_string(client);
  for (int i = 1; i < 16; ++i) gid += ",0";
  gid += "]";
  return "{\"info\":{\"event_type\":" + std::to_string(type) + ",\"stamp\":{\"sec\":" + std::to_string(ms / 1000) +
         ",\"nanosec\":" + std::to_string((ms % 1000) * 1000000) + "},\"client_gid\":" + gid +
         ",\"sequence_number\":" + std::to_string(seq) + "},\"request\":[" + request + "],\"response\":[" + response + "]}";
}

struct Trace {
  std::vector<std::string> out;
  ServiceCalls calls;
  explicit Trace(double timeout) : calls(timeout, [this](const std::string& s) { out.push_back(s); }) {}
  void feed(const std::string& line) {
    std::string error;
    ASSERT_TRUE(calls.feed(line, error)) << error << " in " << line;
  }
};

TEST(ServiceCalls, AnsweredLateAndNeverAnswered) {
  Trace r(0.5);
  r.feed(event(0, 1000, 1, 1, "{\"a\":1}"));                 // call 1 at 1.0
  r.feed(event(3, 1050, 1, 1, "", "{\"success\":true}"));    // answered after 50 ms
  ASSERT_EQ(r.out.size(), 1u);
  EXPECT_EQ(r.out[0],
            "{\"time\":1,\"request_time\":1,\"answered\":true,\"latency\":0.05,\"sequence_number\":1,"
            "\"request\":{\"a\":1},\"response\":{\"success\":true}}");
  r.feed(event(0, 2000, 1, 2));  // call 2 at 2.0: answered after 300 ms (late for a 100 ms property, within 0.5)
  r.feed(event(0, 2100, 1, 3));  // call 3 at 2.1: never answered
  r.feed(event(3, 2300, 1, 2, "", "{\"success\":false}"));
  ASSERT_EQ(r.out.size(), 2u);
  EXPECT_NE(r.out[1].find("\"time\":2,"), std::string::npos) << r.out[1];
  EXPECT_NE(r.out[1].find("\"answered\":true,\"latency\":0.3"), std::string::npos) << r.out[1];
  r.feed(event(0, 2700, 1, 4));  // time 2.7 passes call 3's deadline 2.6: made unanswered
  ASSERT_EQ(r.out.size(), 3u);
  EXPECT_EQ(r.out[2], "{\"time\":2.1,\"request_time\":2.1,\"answered\":false,\"latency\":0.5,\"sequence_number\":3}");
  r.calls.finish();
  EXPECT_EQ(r.calls.counts().pending, 1u);  // call 4: the input ended within its timeout
  EXPECT_EQ(r.calls.counts().answered, 2u);
  EXPECT_EQ(r.calls.counts().unanswered, 1u);
}

TEST(ServiceCalls, ResponsesOutOfOrderComeOutInRequestOrder) {
  Trace r(1.0);
  r.feed(event(0, 1000, 1, 1));
  r.feed(event(0, 1100, 1, 2));
  r.feed(event(3, 1200, 1, 2));  // call 2 answered first: held until call 1 is decided
  EXPECT_TRUE(r.out.empty());
  r.feed(event(3, 1400, 1, 1));
  ASSERT_EQ(r.out.size(), 2u);
  EXPECT_NE(r.out[0].find("\"time\":1,\"request_time\":1,\"answered\":true,\"latency\":0.4,"), std::string::npos);
  EXPECT_NE(r.out[1].find("\"time\":1.1,\"request_time\":1.1,\"answered\":true,\"latency\":0.1,"), std::string::npos);
  EXPECT_NE(r.out[1].find("\"sequence_number\":2"), std::string::npos);
}

TEST(ServiceCalls, TwoClientsWithTheSameSequenceNumbersAreTwoCalls) {
  Trace r(1.0);
  r.feed(event(0, 1000, 1, 1, "{\"c\":1}"));
  r.feed(event(0, 1010, 2, 1, "{\"c\":2}"));
  r.feed(event(3, 1030, 2, 1, "", "{\"r\":2}"));
  r.feed(event(3, 1060, 1, 1, "", "{\"r\":1}"));
  ASSERT_EQ(r.out.size(), 2u);
  EXPECT_NE(r.out[0].find("\"request\":{\"c\":1},\"response\":{\"r\":1}"), std::string::npos) << r.out[0];
  EXPECT_NE(r.out[0].find("\"latency\":0.06"), std::string::npos) << r.out[0];
  EXPECT_NE(r.out[1].find("\"request\":{\"c\":2},\"response\":{\"r\":2}"), std::string::npos) << r.out[1];
  EXPECT_NE(r.out[1].find("\"latency\":0.02"), std::string::npos) << r.out[1];
}

TEST(ServiceCalls, BothSidesOfOneCallAreOneCall) {
  // client and server both introspect: REQUEST_SENT, REQUEST_RECEIVED, RESPONSE_SENT, RESPONSE_RECEIVED
  Trace r(1.0);
  r.feed(event(0, 1000, 1, 7));
  r.feed(event(1, 1001, 1, 7));
  r.feed(event(2, 1020, 1, 7));
  r.feed(event(3, 1021, 1, 7));
  ASSERT_EQ(r.out.size(), 1u);
  EXPECT_NE(r.out[0].find("\"latency\":0.02"), std::string::npos) << r.out[0];  // first request to first response
  EXPECT_EQ(r.calls.counts().duplicates, 2u);
  EXPECT_EQ(r.calls.counts().requests, 1u);
}

TEST(ServiceCalls, ResponsesWithoutARequestAndAfterTheDeadlineAreOrphans) {
  Trace r(0.5);
  r.feed(event(3, 1000, 1, 1));  // its request was before the recording
  r.feed(event(0, 2000, 1, 2));
  r.feed(event(3, 2600, 1, 2));  // after the 0.5 s deadline: the call is unanswered, this response an orphan
  ASSERT_EQ(r.out.size(), 1u);
  EXPECT_NE(r.out[0].find("\"answered\":false"), std::string::npos);
  EXPECT_EQ(r.calls.counts().orphans, 2u);
}

TEST(ServiceCalls, AStragglerRequestKeepsTimesIncreasing) {
  Trace r(1.0);
  r.feed(event(0, 2000, 1, 1));
  r.feed(event(3, 2010, 1, 1));
  r.feed(event(0, 1500, 2, 1));  // recorded after a call made at 2.0, stamped before it
  r.feed(event(3, 2020, 2, 1));
  ASSERT_EQ(r.out.size(), 2u);
  EXPECT_NE(r.out[1].find("\"time\":2.000000001,\"request_time\":1.5"), std::string::npos) << r.out[1];
}

TEST(ServiceCalls, AClockWithoutEventsMakesUnansweredCalls) {
  Trace r(0.25);
  r.feed(event(0, 1000, 1, 1));
  EXPECT_EQ(r.calls.next_deadline(), 1.25);
  r.calls.advance(1.2);
  EXPECT_TRUE(r.out.empty());
  r.calls.advance(1.25);
  ASSERT_EQ(r.out.size(), 1u);
  EXPECT_NE(r.out[0].find("\"answered\":false,\"latency\":0.25"), std::string::npos);
}

TEST(ServiceCalls, LinesThatAreNoEventAreRejectedByName) {
  Trace r(1.0);
  std::string error;
  EXPECT_FALSE(r.calls.feed("{\"data\":1}", error));
  EXPECT_NE(error.find("no field 'info'"), std::string::npos) << error;
  EXPECT_FALSE(r.calls.feed("{\"info\":{\"event_type\":9}}", error));
  EXPECT_NE(error.find("event_type"), std::string::npos) << error;
  EXPECT_FALSE(r.calls.feed("{nope", error));
  EXPECT_EQ(r.calls.counts().rejected, 3u);
}

}  // namespace

// A straggler request stamped before the clock's time, already past its
// deadline: made unanswered at once (before, only when a later event or tick
// moved the clock again), so next_deadline() never lies in the past.
TEST(ServiceCalls, AStragglerPastItsDeadlineIsMadeAtOnce) {
  Trace r(0.5);
  r.feed(event(0, 1000, 1, 1));
  r.feed(event(3, 1100, 1, 1));  // call 1 answered
  r.feed(event(0, 3000, 2, 1));  // call 2 at 3.0: the clock is at 3.0
  ASSERT_EQ(r.out.size(), 1u);
  r.feed(event(0, 2000, 3, 1));  // stamped 2.0: its deadline 2.5 has passed
  ASSERT_EQ(r.out.size(), 2u);
  EXPECT_NE(r.out[1].find("\"request_time\":2,\"answered\":false"), std::string::npos) << r.out[1];
  EXPECT_EQ(r.calls.next_deadline(), 3.5);  // call 2's
}
