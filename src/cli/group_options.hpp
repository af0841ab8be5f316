// rvc monitor --group NAME --shard-by PATTERN (docs/fleet.md): replicas of a
// monitor share a fleet's key space. Each announces itself with a Zenoh
// liveliness token @rvc/group/NAME/<member>, follows the others' tokens
// (runtime/fleet/group_members.hpp) and checks only the shards it owns
// (runtime/fleet/sharded_feed.hpp).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "runtime/fleet/group_members.hpp"
#include "runtime/fleet/sharded_feed.hpp"
#include "transport/endpoint.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {

struct GroupFlags {
  std::string name;        // --group
  std::string shard_by;    // --shard-by
  std::string member;      // --member (default: the Zenoh session id)
  size_t replay_window = 16384;
  double handover_overlap = 3;
  std::string subscribe = "all";  // --shard-subscribe all|owned

  void add_to(CLI::App& app);
  bool given() const { return !name.empty(); }
  // Usage problems of a group run (inputs not zenoh: keys with the shard's
  // wildcard, --shard-by missing): the message, or "".
  std::string refuse(const std::vector<std::string>& uris) const;
  // Joins the group: the token, the member set. Throws on a Zenoh failure.
  void join(const transport::TransportOptions& transports);
  runtime::fleet::GroupMembers& members() { return *members_; }
  bool subscribe_owned() const { return given() && subscribe == "owned"; }
  // --shard-subscribe owned: the source of one zenoh: input, subscribed per
  // owned and backed-up shard (transport/zenoh/zenoh_shard_subscriptions.hpp).
  // Throws std::invalid_argument when its key cannot be narrowed per shard.
  std::unique_ptr<transport::Source> owned_source(const std::string& uri);
  runtime::fleet::ShardedOptions sharded_options() const;
  // The properties of one shard's instance: "<shard>/<name>".
  static std::vector<engine::PropertySpec> shard_properties(const std::vector<engine::PropertySpec>& properties,
                                                            const std::string& shard);
  // An orderly end: the token goes at once. `at_end_of_stream`: every
  // publisher ended and this replica checked all it owns: it says "bye"
  // first, so the others keep its shards as they are instead of taking them over.
  void leave(bool at_end_of_stream);

 private:
  std::unique_ptr<runtime::fleet::GroupMembers> members_;
  std::shared_ptr<void> session_, token_, watch_, byes_;
  std::shared_ptr<void> shard_subs_;  // --shard-subscribe owned
};

}  // namespace rvc::cli
