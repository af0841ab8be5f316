// The feed of a monitor group replica (`rvc monitor --group NAME --shard-by
// 'fleet/*'`, docs/fleet.md): every sample of the fleet's key space arrives
// here; its shard (runtime/fleet/shard_map.hpp) decides whether this replica
// checks it. One monitor instance (a Pipeline or SyncedPipeline, the same a
// single-vehicle monitor would run, its properties named "<shard>/<name>")
// per owned shard; samples of other shards are dropped ("not owned") after
// a copy goes into that shard's replay window.
//
// Failover: when the member set changes, shards whose owner is now this
// replica get a fresh instance that first replays the shard's window in
// arrival order. Verdicts of the replay are withheld, except for messages
// that arrived within `handover_overlap` seconds of the change: those the
// old owner may not have checked before it died, so they are published
// again, marked "handover" (at least once: a verdict the old owner did
// publish comes twice, equal). The new instance's verdicts equal an
// uninterrupted monitor's when the window holds every message the
// properties' verdicts depend on: the shard's whole history (the default
// window is large), or, for properties of bounded horizon over fields
// every topic refreshes, the last horizon's messages.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "runtime/feed.hpp"
#include "runtime/fleet/group_members.hpp"
#include "runtime/fleet/shard_map.hpp"
#include "runtime/verdict_outputs.hpp"

namespace rvc::runtime::fleet {

struct ShardedOptions {
  std::string group;                 // the group's name (messages, counters)
  size_t replay_window = 16384;      // messages kept per shard this replica does not own
  double handover_overlap = 3;       // seconds: replayed messages this recent get their verdicts published
  // --shard-subscribe owned: only the shards this replica owns or backs up
  // (second rendezvous choice) arrive; windows are kept for the backed-up
  // ones only, and a shard it stops backing up loses its window (it is not
  // received any more: taken later, its replay is partial).
  bool subscribe_owned = false;
  // Called on the engine thread at each handover (the results database
  // records it): the JSON object describing it.
  std::function<void(const std::string& json)> on_handover;
};

// Builds one shard's monitor instance; its verdicts go to `on_verdict`.
using InstanceFactory = std::function<std::unique_ptr<Feed>(const std::string& shard, engine::VerdictCallback on_verdict)>;

class ShardedFeed final : public Feed {
 public:
  ShardedFeed(ShardPattern pattern, GroupMembers& members, InstanceFactory factory, VerdictOutputs& outputs,
              ShardedOptions options);
  ~ShardedFeed() override;

  void feed_input(uint32_t input, std::string_view payload, uint64_t position) override;
  void feed_keyed(uint32_t input, std::string_view key, std::string_view payload, uint64_t position) override;
  void warn(const io::LineError& warning) override;
  void idle() override;
  void end_of_input() override;
  void input_ended(uint32_t input) override;
  uint64_t received() const override { return received_; }
  void add_dropped(io::JsonObject& out) const override;
  uint64_t lost() const override;
  const PipelineStats& stats() const override;
  uint64_t violations() const override;
  void finish_report() override;
  void add_stats(io::JsonObject& out) const override;

  // Re-reads the member set if it changed (also done on every message).
  void follow_members();
  size_t owned() const;
  uint64_t handovers() const { return handovers_; }

 private:
  struct Buffered {
    uint32_t input;
    uint64_t position;
    std::chrono::steady_clock::time_point arrival;
    std::string payload;
  };
  struct Shard {
    std::string key;
    std::unique_ptr<Feed> instance;  // null: another replica owns it
    std::deque<Buffered> window;     // while not owned: the latest messages
    bool backup = false;             // subscribe_owned: this replica is its second choice (keeps its window)
    bool evicted = false;            // the window lacks the shard's oldest messages: the replay starts mid-history
    bool started = false;            // its first message came: owned or not, it is known
    bool partial = false;            // its instance began mid-history: its verdicts are marked "partial"
    uint64_t inputs_seen = 0;        // inputs (bit i, the first 64) whose first message this replica has had
    PipelineStats replay;            // of the instance's stats, what its replays counted
    uint64_t replay_received = 0;
    uint64_t replay_lost = 0;        // of the instance's lost(), the replay's
  };
  Shard& shard(std::string_view key);
  void take(Shard& s, std::chrono::steady_clock::time_point changed_at);
  void release(Shard& s);
  void on_verdict(const Shard& s, const engine::Verdict& v);
  void retire(Shard& s);
  bool keeps_window(Shard& s);

  ShardPattern pattern_;
  GroupMembers& members_;
  InstanceFactory factory_;
  VerdictOutputs& outputs_;
  ShardedOptions options_;
  std::unordered_map<std::string, std::unique_ptr<Shard>> shards_;
  std::vector<std::string> member_list_;
  uint64_t generation_ = UINT64_MAX;
  uint64_t received_ = 0, not_owned_ = 0, no_shard_ = 0, window_evicted_ = 0;
  uint64_t handovers_ = 0, replayed_ = 0, partial_replays_ = 0, replayed_verdicts_ = 0, withheld_verdicts_ = 0;
  PipelineStats retired_;       // of instances released to another replica (live part)
  uint64_t retired_violations_ = 0, retired_lost_ = 0;
  bool withhold_ = false;       // replaying the part of a window the old owner checked
  bool mark_handover_ = false;  // replaying the overlap: verdicts marked "handover"
  bool ended_ = false;
  std::chrono::steady_clock::time_point last_idle_{};
  mutable PipelineStats stats_;
};

}  // namespace rvc::runtime::fleet
