// `rvc monitor --group NAME --shard-by 'fleet/*' --shard-subscribe owned`
// (docs/fleet.md): instead of one subscriber per input on the whole key
// space, a replica subscribes per shard, for the shards it owns and those it
// is the backup of (the second rendezvous choice: it takes them over if the
// owner leaves, so it keeps their replay window). Shards are discovered by
// liveliness tokens on the shard pattern itself (a vehicle, or its bridge,
// declares `fleet/v07` before it publishes), so no sample of a shard this
// replica neither owns nor backs up reaches it.
//
// A worker thread reconciles the subscriptions whenever the member set (polled
// every 50 ms) or the set of known shards changes: declaring or undeclaring a
// Zenoh subscriber is not done on a Zenoh callback thread.
#pragma once

#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "runtime/fleet/group_members.hpp"
#include "runtime/fleet/shard_map.hpp"
#include "transport/endpoint.hpp"
#include "transport/zenoh/zenoh_liveliness.hpp"
#include "transport/zenoh/zenoh_session.hpp"

namespace rvc::transport {

class ZenohShardSubscriptions {
 public:
  ZenohShardSubscriptions(std::shared_ptr<ZenohSession> session, runtime::fleet::ShardPattern pattern,
                          runtime::fleet::GroupMembers& members, std::string group);
  ~ZenohShardSubscriptions();
  ZenohShardSubscriptions(const ZenohShardSubscriptions&) = delete;
  ZenohShardSubscriptions& operator=(const ZenohShardSubscriptions&) = delete;

  // A Source for one input (its key expression with the shard's wildcard):
  // started, it receives that input's samples of every subscribed shard.
  // Throws std::invalid_argument when the key cannot be narrowed per shard.
  std::unique_ptr<Source> source(const std::string& keyexpr);
  // Stops every subscription (and the worker).
  void close();

  struct Input {
    std::string keyexpr;
    FrameHandler handler;  // set by start(); samples go here (serialised by mutex)
    std::shared_ptr<std::mutex> mutex = std::make_shared<std::mutex>();
    // Set (under `mutex`) by stop(): a subscriber declared as the input
    // stopped calls the handler no more.
    std::shared_ptr<bool> closed = std::make_shared<bool>(false);
    std::map<std::string, std::unique_ptr<ZenohSubscriber>> subs;  // shard -> its subscriber
  };
  void started(Input* input, FrameHandler handler);
  void stopped(Input* input);

 private:
  void run();
  void reconcile();

  std::shared_ptr<ZenohSession> session_;
  runtime::fleet::ShardPattern pattern_;
  runtime::fleet::GroupMembers& members_;
  std::string group_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::set<std::string> shards_;  // known by their tokens (never forgotten: a vehicle's last samples)
  bool dirty_ = true, stop_ = false;
  std::vector<std::unique_ptr<Input>> inputs_;
  std::unique_ptr<ZenohLivelinessSubscriber> discovery_;
  std::thread worker_;
};

}  // namespace rvc::transport
