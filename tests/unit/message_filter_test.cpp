// The filter in front of the monitor (src/runtime/message_filter.cpp) and
// the enforcer's --on-violation syntax: hand-written cases, including the
// ones Zenoh's key-expression rules make easy to get wrong ('**' matching
// no chunk at all, '*' never crossing a '/').
#include <gtest/gtest.h>

#include "runtime/enforcer.hpp"
#include "runtime/message_filter.hpp"

namespace rvc::runtime {
namespace {

TEST(KeyMatches, ChunksAndWildcards) {
  EXPECT_TRUE(key_matches("vehicle/status", "vehicle/status"));
  EXPECT_FALSE(key_matches("vehicle/status", "vehicle/status/x"));
  EXPECT_TRUE(key_matches("vehicle/*", "vehicle/status"));
  EXPECT_FALSE(key_matches("vehicle/*", "vehicle/a/b"));
  EXPECT_FALSE(key_matches("vehicle/*", "vehicle"));
  EXPECT_TRUE(key_matches("vehicle/**", "vehicle"));
  EXPECT_TRUE(key_matches("vehicle/**", "vehicle/a/b/c"));
  EXPECT_TRUE(key_matches("**/status", "a/b/status"));
  EXPECT_TRUE(key_matches("**/status", "status"));
  EXPECT_TRUE(key_matches("a/**/z", "a/z"));
  EXPECT_TRUE(key_matches("a/**/z", "a/b/c/z"));
  EXPECT_FALSE(key_matches("a/**/z", "a/b/c/y"));
  EXPECT_TRUE(key_matches("**", "anything/at/all"));
  EXPECT_TRUE(key_matches("/chatter", "chatter"));  // DDS topic names carry a leading '/'
  EXPECT_FALSE(key_matches("vehicle/sta", "vehicle/status"));
}

TEST(MessageFilter, DenyWinsOverAllow) {
  MessageFilter f({{"vehicle/**"}, {"vehicle/debug/**"}, {}});
  EXPECT_TRUE(f.active());
  EXPECT_TRUE(f.admits("vehicle/status"));
  EXPECT_FALSE(f.admits("vehicle/debug/cpu"));
  EXPECT_FALSE(f.admits("other/status"));
  MessageFilter deny_only({{}, {"*/debug"}, {}});
  EXPECT_TRUE(deny_only.admits("x/status"));
  EXPECT_FALSE(deny_only.admits("x/debug"));
  EXPECT_FALSE(MessageFilter({}).active());
  EXPECT_THROW(MessageFilter({{""}, {}, {}}), std::invalid_argument);
  EXPECT_THROW(MessageFilter({{}, {}, {"a..b"}}), std::invalid_argument);
}

TEST(MessageFilter, ProjectsDottedPathsInTheOrderGiven) {
  MessageFilter f({{}, {}, {"time", "pose.x", "speed", "pose.y", "missing", "time.x"}});
  std::string out;
  ASSERT_TRUE(f.project(R"({"speed":3.5,"noise":[1,2],"time":7,"pose":{"x":1,"y":2,"z":3},"mode":"a"})", out));
  EXPECT_EQ(out, R"({"time":7,"pose":{"x":1,"y":2},"speed":3.5})");
  ASSERT_TRUE(f.project(R"({"other":1})", out));
  EXPECT_EQ(out, "{}");
  EXPECT_FALSE(f.project("[1,2]", out));
  EXPECT_FALSE(f.project("{broken", out));
}

TEST(EnforceAction, Syntax) {
  EnforceAction a = parse_enforce_action(R"(p1=zenoh:vehicle/hazard:{"on":true})");
  EXPECT_EQ(a.property, "p1");
  EXPECT_EQ(a.uri, "zenoh:vehicle/hazard");
  EXPECT_EQ(a.payload, R"({"on":true})");
  a = parse_enforce_action("stop=dds:/emergency_stop:");
  EXPECT_EQ(a.uri, "dds:/emergency_stop");
  EXPECT_EQ(a.payload, "");
  EXPECT_THROW(parse_enforce_action("p1"), std::invalid_argument);
  EXPECT_THROW(parse_enforce_action("=zenoh:a:b"), std::invalid_argument);
  EXPECT_THROW(parse_enforce_action("p1=zenoh:a"), std::invalid_argument);
  EXPECT_THROW(parse_enforce_action("p1=zenoh::x"), std::invalid_argument);
  EXPECT_THROW(parse_enforce_action("p1=http:x:y"), std::invalid_argument);
}

}  // namespace
}  // namespace rvc::runtime
