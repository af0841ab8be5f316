// Monitor groups (docs/fleet.md): the shard of a key, rendezvous owners, and
// a replica's feed taking a shard over mid-stream. Oracles: hand-computed
// shards, counting owners (only a departed member's shards move), and an
// uninterrupted Pipeline over the same messages.
#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "runtime/fleet/shard_map.hpp"
#include "runtime/fleet/sharded_feed.hpp"
#include "runtime/pipeline.hpp"

namespace rvc::runtime::fleet {
namespace {

TEST(ShardPattern, TakesTheKeysPrefixThePatternCovers) {
  ShardPattern p("fleet/*");
  EXPECT_EQ(p.shard_of("fleet/v07/vehicle/status/gear_status"), "fleet/v07");
  EXPECT_EQ(p.shard_of("fleet/v07"), "fleet/v07");
  EXPECT_EQ(p.shard_of("other/v07/x"), std::nullopt);
  EXPECT_EQ(p.shard_of("fleet"), std::nullopt);
  EXPECT_EQ(p.shard_of("fleet//x"), std::nullopt);
  ShardPattern q("site/*/fleet/*");
  EXPECT_EQ(q.shard_of("site/a/fleet/v1/odom"), "site/a/fleet/v1");
  EXPECT_EQ(q.shard_of("site/a/cars/v1/odom"), std::nullopt);
  EXPECT_THROW(ShardPattern("fleet/**"), std::invalid_argument);
  EXPECT_THROW(ShardPattern("fleet//*"), std::invalid_argument);
  EXPECT_THROW(ShardPattern(""), std::invalid_argument);
  EXPECT_THROW(ShardPattern("fleet/v*"), std::invalid_argument);
}

TEST(Rendezvous, OnlyTheDepartedMembersShardsMoveAndTheSpreadIsEven) {
  const std::vector<std::string> three = {"m1", "m2", "m3"}, two = {"m1", "m3"};
  std::map<std::string, int> load;
  int moved = 0;
  for (int i = 0; i < 3000; ++i) {
    const std::string shard = "fleet/v" + std::to_string(i);
    const std::string before = owner_of(shard, three), after = owner_of(shard, two);
    ++load[before];
    if (before != "m2") {
      EXPECT_EQ(before, after) << shard;  // a survivor keeps what it had
    }
    moved += before != after;
  }
  EXPECT_EQ(moved, load["m2"]);
  for (const auto& [m, n] : load) EXPECT_NEAR(n, 1000, 150) << m;
  EXPECT_EQ(owner_of("x", {}), "");
  // The same in every process: a fixed value, not std::hash.
  EXPECT_EQ(stable_hash("m1", "fleet/v0"), stable_hash("m1", "fleet/v0"));
  EXPECT_NE(stable_hash("m1", "fleet/v0"), stable_hash("m1f", "leet/v0"));
}

class LinesSink : public transport::Sink {
 public:
  explicit LinesSink(std::vector<std::string>& lines) : lines_(lines) {}
  void put(std::string_view payload, uint64_t) override { lines_.emplace_back(payload); }
  void put_eos(uint64_t) override {}

 private:
  std::vector<std::string>& lines_;
};

PipelineOptions discrete() {
  PipelineOptions o;
  o.model = engine::TimeModel::Discrete;
  return o;
}

// Two shards' messages through a replica that owns neither until the owner
// leaves: the replay rebuilds the state, so the verdicts after the takeover
// are the uninterrupted monitor's (a bounded window that looks 3 steps back
// and an unbounded `once`, over the whole history kept).
TEST(ShardedFeed, TakeoverReplaysTheWindowAndGoesOnAsAnUninterruptedMonitor) {
  const std::vector<engine::PropertySpec> props = {{"near", "once[0:3]{alarm}"}, {"ever", "once{alarm}"}};
  // Who owns fleet/a and fleet/b with both members, and without "other".
  GroupMembers members("self");
  members.update("other", true);
  std::vector<std::string> lines;
  std::vector<std::unique_ptr<transport::Sink>> sinks;
  sinks.push_back(std::make_unique<LinesSink>(lines));
  VerdictOutputs outputs(std::move(sinks), true);
  ShardedOptions opts;
  opts.group = "g";
  opts.handover_overlap = 0;  // nothing arrived "recently": only verdicts after the takeover
  ShardedFeed feed(
      ShardPattern("fleet/*"), members,
      [&](const std::string& shard, engine::VerdictCallback cb) {
        std::vector<engine::PropertySpec> named = props;
        for (auto& p : named) p.name = shard + "/" + p.name;
        return std::make_unique<Pipeline>(named, discrete(), std::move(cb));
      },
      outputs, opts);
  // Find a shard "other" owns with both members.
  std::string theirs;
  for (int i = 0; theirs.empty(); ++i)
    if (owner_of("fleet/v" + std::to_string(i), {"other", "self"}) == "other") theirs = "fleet/v" + std::to_string(i);
  const std::string key = theirs + "/sensor";
  const std::vector<std::string> msgs = {R"({"alarm":false})", R"({"alarm":true})",  R"({"alarm":false})",
                                         R"({"alarm":false})", R"({"alarm":false})", R"({"alarm":false})",
                                         R"({"alarm":false})", R"({"alarm":true})",  R"({"alarm":false})"};
  for (size_t i = 0; i < 5; ++i) feed.feed_keyed(0, key, msgs[i], i + 1);
  EXPECT_TRUE(lines.empty());
  members.update("other", false);  // the owner died
  for (size_t i = 5; i < msgs.size(); ++i) feed.feed_keyed(0, key, msgs[i], i + 1);

  // The uninterrupted monitor's verdicts from message 6 on (steps 5..).
  std::vector<std::string> expected;
  {
    std::vector<std::unique_ptr<transport::Sink>> s;
    std::vector<std::string> all;
    s.push_back(std::make_unique<LinesSink>(all));
    VerdictOutputs out(std::move(s), true);
    std::vector<engine::PropertySpec> named = props;
    for (auto& p : named) p.name = theirs + "/" + p.name;
    Pipeline one(named, discrete(), [&](const engine::Verdict& v) { out.put(v); });
    for (size_t i = 0; i < msgs.size(); ++i) one.feed(msgs[i], i + 1);
    for (const auto& l : all)
      if (l.find("\"time\":5") != std::string::npos || l.find("\"time\":6") != std::string::npos ||
          l.find("\"time\":7") != std::string::npos || l.find("\"time\":8") != std::string::npos)
        expected.push_back(l);
  }
  // Hand-computed: near goes false at step 5 (the alarm of step 1 is 4 steps
  // back), true at 7; `ever` stays true (the alarm of step 1, before the takeover).
  ASSERT_EQ(expected.size(), 2u);
  EXPECT_EQ(lines, expected);
  io::JsonObject c;
  feed.add_dropped(c);
  EXPECT_EQ(c.str(), R"({"not owned":5})");
  EXPECT_EQ(feed.received(), 9u);
  EXPECT_EQ(feed.stats().accepted, 4u);  // live: the replayed 5 are not counted again
  EXPECT_EQ(feed.handovers(), 1u);
}


// A member joins (scale-up): the shards it now owns are handed on, their
// live counts stay counted once, and messages of those shards are dropped
// as "not owned" from then on.
TEST(ShardedFeed, AJoiningMemberTakesItsShardsAndTheCountsStayWhole) {
  GroupMembers members("self");
  std::vector<std::string> lines;
  std::vector<std::unique_ptr<transport::Sink>> sinks;
  sinks.push_back(std::make_unique<LinesSink>(lines));
  VerdictOutputs outputs(std::move(sinks), true);
  ShardedFeed feed(
      ShardPattern("fleet/*"), members,
      [&](const std::string& shard, engine::VerdictCallback cb) {
        return std::make_unique<Pipeline>(std::vector<engine::PropertySpec>{{shard + "/p", "{ok}"}}, discrete(),
                                          std::move(cb));
      },
      outputs, ShardedOptions{});
  const int n = 40;
  for (int i = 0; i < n; ++i) feed.feed_keyed(0, "fleet/v" + std::to_string(i) + "/x", R"({"ok":true})", 1);
  EXPECT_EQ(feed.owned(), size_t(n));
  members.update("new", true);
  int theirs = 0;
  for (int i = 0; i < n; ++i) {
    const std::string shard = "fleet/v" + std::to_string(i);
    theirs += owner_of(shard, {"new", "self"}) == "new";
    feed.feed_keyed(0, shard + "/x", R"({"ok":true})", 2);
  }
  ASSERT_GT(theirs, 0);
  EXPECT_EQ(feed.owned(), size_t(n - theirs));
  EXPECT_EQ(feed.received(), size_t(2 * n));
  EXPECT_EQ(feed.stats().accepted, size_t(2 * n - theirs));  // the handed-on instances' checks still count
  io::JsonObject c;
  feed.add_dropped(c);
  EXPECT_EQ(c.str(), "{\"not owned\":" + std::to_string(theirs) + "}");
  EXPECT_EQ(lines.size(), size_t(n));  // one first verdict per shard, none again
}


// A replica that started after the vehicle (its first sequence number is
// past 1) does not have the shard's history: a takeover says so.
TEST(ShardedFeed, ATakeoverOfAShardSeenFromMidStreamIsReportedPartial) {
  GroupMembers members("self");
  members.update("other", true);
  std::vector<std::string> lines;
  std::vector<std::unique_ptr<transport::Sink>> sinks;
  sinks.push_back(std::make_unique<LinesSink>(lines));
  VerdictOutputs outputs(std::move(sinks), true);
  ShardedFeed feed(
      ShardPattern("fleet/*"), members,
      [&](const std::string& shard, engine::VerdictCallback cb) {
        return std::make_unique<Pipeline>(std::vector<engine::PropertySpec>{{shard + "/p", "{ok}"}}, discrete(),
                                          std::move(cb));
      },
      outputs, ShardedOptions{});
  std::string late, early;
  for (int i = 0; late.empty() || early.empty(); ++i) {
    const std::string shard = "fleet/v" + std::to_string(i);
    if (owner_of(shard, {"other", "self"}) != "other") continue;
    (late.empty() ? late : early) = shard;
  }
  feed.feed_keyed(0, late + "/x", R"({"ok":true})", 7);   // its publisher had sent 6 before
  feed.feed_keyed(0, early + "/x", R"({"ok":true})", 1);
  members.update("other", false);
  feed.follow_members();
  io::JsonObject g;
  feed.add_stats(g);
  EXPECT_NE(g.str().find("\"partial_replays\":1}"), std::string::npos) << g.str();
  EXPECT_EQ(feed.owned(), 2u);
}

// --shard-subscribe owned: a shard's backup is its second rendezvous choice,
// i.e. exactly the member that owns it once the owner leaves.
TEST(Rendezvous, TheBackupIsTheOwnerOnceTheOwnerLeaves) {
  const std::vector<std::string> members = {"a", "b", "c", "d"};
  for (int i = 0; i < 300; ++i) {
    const std::string shard = "fleet/v" + std::to_string(i);
    const auto firsts = owners_of(shard, members, 2);
    ASSERT_EQ(firsts.size(), 2u);
    EXPECT_EQ(firsts[0], owner_of(shard, members));
    std::vector<std::string> rest;
    for (const auto& m : members)
      if (m != firsts[0]) rest.push_back(m);
    EXPECT_EQ(owner_of(shard, rest), firsts[1]) << shard;
  }
  EXPECT_EQ(owners_of("fleet/v1", {"only"}, 2), std::vector<std::string>{"only"});
}

TEST(ShardPattern, NarrowsAnInputKeyToOneShard) {
  const ShardPattern p("fleet/*");
  EXPECT_EQ(p.narrow("fleet/*/vehicle/status/gear", "fleet/v07"), "fleet/v07/vehicle/status/gear");
  EXPECT_EQ(p.narrow("*/*/x", "fleet/v07"), "fleet/v07/x");
  EXPECT_EQ(p.narrow("fleet/*", "fleet/v07"), "fleet/v07");
  EXPECT_FALSE(p.narrow("fleet/**", "fleet/v07"));        // '**' spans shards
  EXPECT_FALSE(p.narrow("fleet/v07/x", "fleet/v07"));     // one vehicle's key, not one per shard
  EXPECT_FALSE(p.narrow("cars/*/x", "fleet/v07"));        // another prefix
  EXPECT_FALSE(p.narrow("fleet", "fleet/v07"));           // too short
  EXPECT_FALSE(p.narrow("fleet/v$*/x", "fleet/v07"));
}

// With subscribe_owned a replica keeps windows for the shards it backs up
// only: the owner's departure then replays them whole, while a shard it
// neither owned nor backed up (it got a few samples in flight) is partial.
TEST(ShardedFeed, OwnedSubscriptionsKeepWindowsForBackedUpShardsOnly) {
  GroupMembers members("self");
  members.update("a", true);
  members.update("b", true);
  std::vector<std::string> lines;
  std::vector<std::unique_ptr<transport::Sink>> sinks;
  sinks.push_back(std::make_unique<LinesSink>(lines));
  VerdictOutputs outputs(std::move(sinks), true);
  ShardedOptions opts;
  opts.subscribe_owned = true;
  ShardedFeed feed(
      ShardPattern("fleet/*"), members,
      [&](const std::string& shard, engine::VerdictCallback cb) {
        return std::make_unique<Pipeline>(std::vector<engine::PropertySpec>{{shard + "/p", "{ok}"}}, discrete(),
                                          std::move(cb));
      },
      outputs, opts);
  // backed: owner a, then self; third: owner a, then b, then self.
  std::string backed, third;
  for (int i = 0; backed.empty() || third.empty(); ++i) {
    const std::string shard = "fleet/v" + std::to_string(i);
    const auto r = owners_of(shard, {"a", "b", "self"}, 3);
    if (r[0] != "a") continue;
    (r[1] == "self" ? backed : third) = shard;
  }
  for (uint64_t seq = 1; seq <= 3; ++seq) {
    feed.feed_keyed(0, backed + "/x", R"({"ok":true})", seq);
    feed.feed_keyed(0, third + "/x", R"({"ok":true})", seq);
  }
  members.update("a", false);  // backed -> self (its window: 3 messages); third -> b, self its new backup
  feed.follow_members();
  io::JsonObject g;
  feed.add_stats(g);
  EXPECT_NE(g.str().find("\"owned\":1,\"handovers\":1,\"replayed\":3,"), std::string::npos) << g.str();
  EXPECT_NE(g.str().find("\"partial_replays\":0}"), std::string::npos) << g.str();
  feed.feed_keyed(0, third + "/x", R"({"ok":true})", 4);  // now backed up: kept from here on
  members.update("b", false);
  feed.follow_members();
  io::JsonObject g2;
  feed.add_stats(g2);
  EXPECT_NE(g2.str().find("\"replayed\":4,"), std::string::npos) << g2.str();  // 3 + the one kept since
  EXPECT_NE(g2.str().find("\"partial_replays\":1}"), std::string::npos) << g2.str();
  io::JsonObject c;
  feed.add_dropped(c);
  EXPECT_EQ(c.str(), "{\"not owned\":7}");  // 3 + 3 before the change, 1 after
  EXPECT_EQ(feed.received(), 7u);
}

}  // namespace
}  // namespace rvc::runtime::fleet
