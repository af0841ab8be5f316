#include "cli/group_options.hpp"

#include <cstdio>
#include <stdexcept>
#include <thread>

#include "cli/option_ranges.hpp"
#ifdef RVC_HAVE_ZENOH
#include "transport/zenoh/zenoh_liveliness.hpp"
#include "transport/zenoh/zenoh_shard_subscriptions.hpp"
#include "transport/zenoh/zenoh_session.hpp"
#endif

namespace rvc::cli {
namespace {

// The key expression of a zenoh: URI (options after '?' are not part of it).
std::string key_of(const std::string& uri) {
  std::string key = uri.substr(uri.find(':') + 1);
  return key.substr(0, key.find('?'));
}

}  // namespace

void GroupFlags::add_to(CLI::App& app) {
  app.add_option("--group", name,
                 "Monitor group (docs/fleet.md): replicas with the same NAME share the input's key space, each "
                 "checking the shards it owns (Zenoh inputs; needs --shard-by)");
  app.add_option("--shard-by", shard_by,
                 "With --group: the key prefix that makes a shard, e.g. 'fleet/*' (one monitor instance per vehicle "
                 "fleet/<id>); '*' is one chunk");
  app.add_option("--member", member, "With --group: this replica's id in the group (default: its Zenoh session id)");
  app.add_option("--replay-window", replay_window,
                 "With --group: messages kept per shard this replica does not own, replayed when it takes the shard "
                 "over (0: none)")
      ->check(in_range(0, 1e9))
      ->capture_default_str();
  app.add_option("--handover-overlap", handover_overlap,
                 "With --group: on a takeover, the verdicts of replayed messages that arrived this many seconds before "
                 "the change are published again, marked \"handover\"")
      ->check(in_range(0, kMaxSeconds, "seconds"))
      ->capture_default_str();
  app.add_option("--shard-subscribe", subscribe,
                 "With --group: 'all' subscribes to the whole key space and drops the shards others own; 'owned' "
                 "subscribes per shard to those this replica owns or backs up (shards found by the vehicles' "
                 "liveliness tokens on the --shard-by key; docs/fleet.md)")
      ->check(CLI::IsMember({"all", "owned"}))
      ->capture_default_str();
}

std::string GroupFlags::refuse(const std::vector<std::string>& uris) const {
  if (shard_by.empty()) return "--group needs --shard-by (the key prefix of a shard, e.g. 'fleet/*')";
  try {
    runtime::fleet::ShardPattern pattern(shard_by);
  } catch (const std::exception& e) {
    return e.what();
  }
  for (const auto& uri : uris)
    if (transport::scheme_of(uri) != "zenoh")
      return "--group shards Zenoh keys: '" + uri + "' is not a zenoh: input";
  if (subscribe == "owned") {
    const runtime::fleet::ShardPattern pattern(shard_by);
    for (const auto& uri : uris)
      if (!pattern.narrow(key_of(uri), shard_by))
        return "--shard-subscribe owned: the key of '" + uri + "' must begin with --shard-by '" + shard_by +
               "' ('*' where it has '*', its literals where it has literals) to be subscribed per shard";
  }
  return "";
}

runtime::fleet::ShardedOptions GroupFlags::sharded_options() const {
  runtime::fleet::ShardedOptions o;
  o.group = name;
  o.replay_window = replay_window;
  o.handover_overlap = handover_overlap;
  o.subscribe_owned = subscribe_owned();
  return o;
}

std::vector<engine::PropertySpec> GroupFlags::shard_properties(const std::vector<engine::PropertySpec>& properties,
                                                               const std::string& shard) {
  std::vector<engine::PropertySpec> out = properties;
  for (auto& p : out) p.name = shard + "/" + p.name;
  return out;
}

#ifdef RVC_HAVE_ZENOH
void GroupFlags::join(const transport::TransportOptions& transports) {
  auto session = transport::ZenohSession::shared(transports.zenoh);
  if (member.empty()) member = session->zid();
  if (member.find_first_of("/*$?#@") != std::string::npos || member.empty())
    throw std::invalid_argument("--member '" + member + "': one key chunk (no '/', '*', '$', '?', '#', '@')");
  members_ = std::make_unique<runtime::fleet::GroupMembers>(member);
  const std::string prefix = "@rvc/group/" + name + "/";
  auto* members = members_.get();
  watch_ = std::make_shared<transport::ZenohLivelinessSubscriber>(
      session, prefix + "*", true, [members, prefix](std::string_view key, bool alive) {
        if (key.size() > prefix.size() && key.substr(0, prefix.size()) == prefix)
          members->update(key.substr(prefix.size()), alive);
      });
  byes_ = std::make_shared<transport::ZenohSubscriber>(
      session, prefix + "*/bye",
      [members, prefix](const transport::ZenohSample& sample) {
        std::string_view key = sample.key.substr(prefix.size());
        members->retire(key.substr(0, key.find('/')));
      },
      false);
  token_ = std::make_shared<transport::ZenohLivelinessToken>(session, prefix + member);
  session_ = session;
  if (subscribe_owned())
    shard_subs_ = std::make_shared<transport::ZenohShardSubscriptions>(
        session, runtime::fleet::ShardPattern(shard_by), *members_, name);
  std::fprintf(stderr, "rvc monitor: group %s: member %s (token %s%s), shards by '%s'\n", name.c_str(),
               member.c_str(), prefix.c_str(), member.c_str(), shard_by.c_str());
}

std::unique_ptr<transport::Source> GroupFlags::owned_source(const std::string& uri) {
  return std::static_pointer_cast<transport::ZenohShardSubscriptions>(shard_subs_)->source(key_of(uri));
}
#else
void GroupFlags::join(const transport::TransportOptions&) {
  throw std::invalid_argument("--group needs Zenoh: this rvc was built without it");
}
std::unique_ptr<transport::Source> GroupFlags::owned_source(const std::string&) {
  throw std::invalid_argument("--group needs Zenoh: this rvc was built without it");
}
#endif

void GroupFlags::leave(bool at_end_of_stream) {
#ifdef RVC_HAVE_ZENOH
  if (at_end_of_stream && session_) {
    try {
      transport::ZenohPublisher bye(std::static_pointer_cast<transport::ZenohSession>(session_),
                                    "@rvc/group/" + name + "/" + member + "/bye");
      bye.put("{\"reason\":\"end of stream\"}");
      // Before the token goes: the others must read the bye first.
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rvc: group %s: could not say bye: %s\n", name.c_str(), e.what());
    }
  }
  if (shard_subs_) std::static_pointer_cast<transport::ZenohShardSubscriptions>(shard_subs_)->close();
#else
  (void)at_end_of_stream;  // without Zenoh no group starts (no session, no per-shard subscriptions)
#endif
  byes_.reset();
  token_.reset();
  watch_.reset();
  session_.reset();
}

}  // namespace rvc::cli
