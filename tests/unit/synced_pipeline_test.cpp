// SyncedPipeline: several named inputs -> a policy -> one checker. The oracle
// is the plain Pipeline on the stream the policy should have produced,
// written out by hand here: every merge event as one JSON object holding
// each input's latest message, in stamp order. Equal verdicts mean the
// per-input decoders, the atom routing and the stepping agree with the
// single-stream path the rest of the suite already checks against Reelay.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "runtime/pipeline.hpp"
#include "runtime/synced_pipeline.hpp"
#include "spec/spec_error.hpp"

namespace rvc::runtime {
namespace {

struct Message {
  uint32_t input;
  double stamp;
  std::string json;  // the input's own message, with its "time"
};

using Verdicts = std::vector<std::pair<double, bool>>;

const std::vector<engine::PropertySpec> kProperties = {
    {"p1", "historically({a.x} -> once[0:3]{b.y > 2})"},
    {"p2", "{b.y <= 1} since {a.x}"},
    {"p3", "once[1:2]({a.x} and {b.y > 4})"},
};

// Random messages of two inputs: a {x: bool}, b {y: number}; stamps distinct
// over both, increasing per input; arrival interleaves the inputs at random.
std::vector<Message> random_trace(std::mt19937& rng, size_t n) {
  std::vector<Message> by_stamp;
  double t = 0;
  for (size_t i = 0; i < n; ++i) {
    t += 1 + static_cast<int>(rng() % 3);
    const uint32_t input = rng() % 2;
    std::string body = input == 0 ? std::string("\"x\": ") + (rng() % 2 ? "true" : "false")
                                  : "\"y\": " + std::to_string(static_cast<int>(rng() % 7));
    by_stamp.push_back({input, t, "{" + body + ", \"time\": " + std::to_string(static_cast<int>(t)) + "}"});
  }
  // Arrival: each input in its own order, the two interleaved at random.
  std::vector<Message> a, b, arrival;
  for (const auto& m : by_stamp) (m.input == 0 ? a : b).push_back(m);
  size_t i = 0, j = 0;
  while (i < a.size() || j < b.size()) {
    if (j == b.size() || (i < a.size() && rng() % 2)) arrival.push_back(a[i++]);
    else arrival.push_back(b[j++]);
  }
  return arrival;
}

Verdicts synced(const std::vector<Message>& arrival, engine::TimeModel model, double max_delay) {
  Verdicts out;
  PipelineOptions po;
  po.model = model;
  po.emit_all = true;
  SyncOptions so;
  so.policy = sync::PolicyKind::Merge;
  so.policy_options.max_delay = max_delay;
  SyncedPipeline p(kProperties, po, {{"a", "test:a", nullptr, ""}, {"b", "test:b", nullptr, ""}}, so,
                   [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  uint64_t position = 0;
  for (const auto& m : arrival) p.feed_at(m.input, m.json, ++position, 0);
  p.end_of_input();
  EXPECT_EQ(p.stats().rejected, 0u);
  return out;
}

// The oracle: the merged stream as one JSON stream, through Pipeline.
Verdicts merged_by_hand(std::vector<Message> messages, engine::TimeModel model) {
  std::stable_sort(messages.begin(), messages.end(),
                   [](const Message& l, const Message& r) { return l.stamp < r.stamp; });
  Verdicts out;
  PipelineOptions po;
  po.model = model;
  po.emit_all = true;
  Pipeline p(kProperties, po, [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
  std::string last[2];
  uint64_t position = 0;
  for (const auto& m : messages) {
    last[m.input] = m.json;
    std::string event = "{\"time\": " + std::to_string(static_cast<int>(m.stamp));
    if (!last[0].empty()) event += ", \"a\": " + last[0];
    if (!last[1].empty()) event += ", \"b\": " + last[1];
    p.feed(event + "}", ++position);
  }
  return out;
}

TEST(SyncedPipeline, MergeEqualsTheHandMergedStream) {
  std::mt19937 rng(12);
  for (int round = 0; round < 200; ++round) {
    const auto trace = random_trace(rng, 1 + rng() % 40);
    for (auto model : {engine::TimeModel::Discrete, engine::TimeModel::Dense}) {
      // A delay longer than any reordering: nothing is late, all in stamp order.
      const Verdicts got = synced(trace, model, 1000);
      const Verdicts want = merged_by_hand(trace, model);
      ASSERT_EQ(got, want) << "round " << round << (model == engine::TimeModel::Dense ? " dense" : " discrete");
    }
  }
}

TEST(SyncedPipeline, LateMessagesAreDroppedAndCounted) {
  // No delay allowed: a at 1 goes out when a at 3 comes (1 < 3 - 0), a at 3
  // when a at 5 comes; b's message at 2 then arrives behind the watermark.
  std::vector<Message> arrival = {
      {0, 1, R"({"x": true, "time": 1})"},
      {0, 3, R"({"x": true, "time": 3})"},
      {0, 5, R"({"x": false, "time": 5})"},
      {1, 2, R"({"y": 3, "time": 2})"},
      {1, 6, R"({"y": 3, "time": 6})"},
  };
  PipelineOptions po;
  po.emit_all = true;
  SyncOptions so;
  SyncedPipeline p(kProperties, po, {{"a", "test:a", nullptr, ""}, {"b", "test:b", nullptr, ""}}, so,
                   [](const engine::Verdict&) {});
  uint64_t position = 0;
  for (const auto& m : arrival) p.feed_at(m.input, m.json, ++position, 0);
  p.end_of_input();
  EXPECT_EQ(p.sets(), 4u);
  EXPECT_EQ(p.counters(1).released[static_cast<size_t>(sync::Release::Late)], 1u);
  EXPECT_EQ(p.counters(1).used, 1u);
  EXPECT_EQ(p.counters(0).used, 3u);
}

TEST(SyncedPipeline, SetsArePublishedAsOneJsonObject) {
  std::vector<std::string> sets;
  PipelineOptions po;
  po.parse_only = true;
  SyncOptions so;
  so.policy = sync::PolicyKind::Exact;
  SyncedPipeline p({}, po, {{"a", "test:a", nullptr, ""}, {"b", "test:b", nullptr, ""}}, so,
                   [](const engine::Verdict&) {}, [&](std::string_view json, double) { sets.emplace_back(json); });
  p.feed_at(0, R"({"x": true, "time": 1})", 1, 0);
  p.feed_at(1, R"({"y": 2, "time": 3})", 1, 0);
  p.feed_at(0, R"({"x": false, "time": 3})", 2, 0);
  p.end_of_input();
  ASSERT_EQ(sets.size(), 1u);
  EXPECT_EQ(sets[0], R"({"time":3,"a":{"x": false, "time": 3},"b":{"y": 2, "time": 3}})");
  EXPECT_EQ(p.counters(0).released[static_cast<size_t>(sync::Release::Unmatched)], 1u);
}

TEST(SyncedPipeline, FieldsMustNameAnInput) {
  PipelineOptions po;
  SyncOptions so;
  auto make = [&](const std::string& spec) {
    SyncedPipeline p({{"p", spec}}, po, {{"gear", "x", nullptr, ""}, {"steer", "y", nullptr, ""}}, so,
                     [](const engine::Verdict&) {});
  };
  try {
    make("historically({gear.report} -> {speed > 3})");
    FAIL() << "a field of no input was accepted";
  } catch (const spec::SpecError& e) {
    EXPECT_NE(std::string(e.what()).find("'speed' names no input"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("gear, steer"), std::string::npos) << e.what();
    EXPECT_EQ(e.column(), 32);  // the field's name
  }
  try {
    make("{steer}");
    FAIL() << "an input as a field was accepted";
  } catch (const spec::SpecError& e) {
    EXPECT_NE(std::string(e.what()).find("'steer' is an input"), std::string::npos) << e.what();
  }
  EXPECT_THROW(SyncedPipeline({}, po, {{"a", "x", nullptr, ""}, {"a", "y", nullptr, ""}}, so,
                              [](const engine::Verdict&) {}),
               std::invalid_argument);
  EXPECT_THROW(SyncedPipeline({}, po, {{"time", "x", nullptr, ""}}, so, [](const engine::Verdict&) {}),
               std::invalid_argument);
  EXPECT_THROW(SyncedPipeline({}, po, {{"a-b", "x", nullptr, ""}}, so, [](const engine::Verdict&) {}),
               std::invalid_argument);
}

TEST(SyncedPipeline, ABadMessageIsRejectedWithItsInputAndLosesNothingElse) {
  PipelineOptions po;
  po.emit_all = true;
  po.position_name = "seq";
  SyncOptions so;
  Verdicts out;
  testing::internal::CaptureStderr();
  {
    SyncedPipeline p({{"p", "{a.x}"}}, po, {{"a", "x", nullptr, ""}, {"b", "y", nullptr, ""}}, so,
                     [&](const engine::Verdict& v) { out.emplace_back(v.time, v.value); });
    p.feed_at(0, R"({"x": true, "time": 1})", 1, 0);
    p.feed_at(0, R"({"x": true, "time": )", 2, 0);
    p.feed_at(1, R"({"y": 1})", 1, 0);  // no time
    p.feed_at(0, R"({"x": false, "time": 2})", 3, 0);
    p.end_of_input();
    EXPECT_EQ(p.stats().rejected, 2u);
    EXPECT_EQ(p.stats().accepted, 2u);
  }
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("input a seq 2"), std::string::npos) << err;
  EXPECT_NE(err.find("input b seq 1"), std::string::npos) << err;
  EXPECT_EQ(out, (Verdicts{{0, true}, {1, false}}));
}

}  // namespace
}  // namespace rvc::runtime
