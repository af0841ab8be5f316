#include "transport/zenoh/rmw_zenoh_endpoint.hpp"

#include <chrono>
#include <random>
#include <set>
#include <stdexcept>
#include <thread>

#include "transport/zenoh/zenoh_endpoint.hpp"
#include "transport/zenoh/zenoh_session.hpp"

namespace rvc::transport {
namespace {

// A std_msgs/msg/String sample: CDR little-endian encapsulation, then the
// string as uint32 length (with its NUL) and bytes.
std::string string_cdr(std::string_view text) {
  std::string out("\x00\x01\x00\x00", 4);
  const uint32_t n = static_cast<uint32_t>(text.size() + 1);
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((n >> (8 * i)) & 0xff));
  out.append(text);
  out.push_back('\0');
  while (out.size() % 4 != 0) out.push_back('\0');  // as Fast-CDR pads the end
  return out;
}

std::string random_hex(std::size_t bytes) {
  std::random_device rd;
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (std::size_t i = 0; i < bytes; ++i) {
    const unsigned b = rd() & 0xff;
    s += digits[b >> 4];
    s += digits[b & 15];
  }
  return s;
}

// Publishes verdicts (JSON text) as std_msgs/msg/String in rmw_zenoh's format,
// announced in the graph as node "rvc" publishing the topic.
class RmwZenohSink : public Sink {
 public:
  RmwZenohSink(std::shared_ptr<ZenohSession> session, const std::string& topic, int domain, bool express)
      : pub_(session, rmw_zenoh::data_keyexpr(domain, topic, "std_msgs::msg::dds_::String_", rmw_zenoh::kStringTypeHash),
             express) {
    std::random_device rd;
    for (auto& b : gid_) b = static_cast<uint8_t>(rd());
    rmw_zenoh::Entity e;
    e.domain = domain;
    // rmw_zenoh names the session by its Zenoh id; a random node id keeps
    // two rvc sinks of one process apart.
    e.session_id = session->zid();
    e.node_id = random_hex(4);
    e.entity_id = e.node_id;
    e.kind = "NN";
    e.node = "rvc";
    node_ = std::make_unique<ZenohLivelinessToken>(session, rmw_zenoh::liveliness_key(e));
    e.entity_id = random_hex(4);
    e.kind = "MP";
    e.topic = rmw_zenoh::qualified_topic(topic);
    e.dds_type = "std_msgs::msg::dds_::String_";
    e.type_hash = std::string(rmw_zenoh::kStringTypeHash);
    e.qos = "::,10:,:,:,,";  // reliable, volatile, keep-last 10 (rmw_zenoh's compact QoS form, defaults elided)
    publisher_ = std::make_unique<ZenohLivelinessToken>(session, rmw_zenoh::liveliness_key(e));
  }
  void put(std::string_view payload, uint64_t seq) override {
    rmw_zenoh::Attachment a;
    a.seq = static_cast<int64_t>(seq);
    a.source_timestamp_ns = std::chrono::duration_cast<std::chrono::nanoseconds>(
                                std::chrono::system_clock::now().time_since_epoch())
                                .count();
    a.gid = gid_;
    const auto att = rmw_zenoh::encode_attachment(a);
    pub_.put(string_cdr(payload), std::string_view(reinterpret_cast<const char*>(att.data()), att.size()));
  }
  void put_eos(uint64_t) override {}  // rmw_zenoh has no end-of-stream marker
  bool wait_matched(size_t n, std::chrono::milliseconds timeout) override { return pub_.wait_matched(n, timeout); }
  void flush() override { pub_.flush(std::chrono::seconds(60)); }

 private:
  ZenohPublisher pub_;
  rmw_zenoh::Gid gid_{};
  std::unique_ptr<ZenohLivelinessToken> node_, publisher_;
};

}  // namespace

int rmw_zenoh_domain(const RmwZenohOptions& ropts) {
  return ropts.domain >= 0 ? ropts.domain : rmw_zenoh::domain_id_from_env();
}

std::unique_ptr<Source> make_rmw_zenoh_source(const std::string& topic, const ZenohOptions& opts,
                                              const RmwZenohOptions& ropts) {
  std::string dds_type = "*";
  if (!ropts.ros_type.empty()) {
    auto t = rmw_zenoh::dds_type_of(ropts.ros_type);
    if (!t) throw std::invalid_argument("rmw_zenoh: type '" + ropts.ros_type + "' is not pkg/msg/Name");
    dds_type = *t;
  }
  // Any type hash: rvc decodes by the definition it has, it does not compute REP-2016 hashes.
  return std::make_unique<ZenohSource>(ZenohSession::shared(opts),
                                       rmw_zenoh::data_keyexpr(rmw_zenoh_domain(ropts), topic, dds_type, "*"),
                                       ZenohAttachmentFormat::RmwZenoh);
}

std::unique_ptr<Sink> make_rmw_zenoh_sink(const std::string& topic, const ZenohOptions& opts,
                                          const RmwZenohOptions& ropts) {
  auto sink = std::make_unique<RmwZenohSink>(ZenohSession::shared(opts), topic, rmw_zenoh_domain(ropts), opts.express);
  return sink;
}

std::vector<rmw_zenoh::Entity> rmw_zenoh_graph(const ZenohOptions& opts, int domain, std::chrono::milliseconds wait,
                                               std::size_t* skipped) {
  auto session = ZenohSession::shared(opts);
  const auto deadline = std::chrono::steady_clock::now() + wait;
  const std::string key = rmw_zenoh::graph_keyexpr(domain);
  const auto step = std::chrono::milliseconds(250);
  std::set<std::string> keys;
  bool found_before = false;
  while (true) {
    for (auto& k : session->liveliness_get(key, step)) keys.insert(std::move(k));
    // Found something: one more round collects the answers of peers met late.
    if (!keys.empty() && found_before) break;
    found_before = !keys.empty();
    if (std::chrono::steady_clock::now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  std::vector<rmw_zenoh::Entity> out;
  std::size_t bad = 0;
  for (const auto& k : keys) {
    if (auto e = rmw_zenoh::parse_liveliness(k))
      out.push_back(std::move(*e));
    else
      ++bad;
  }
  if (skipped) *skipped = bad;
  return out;
}

std::string rmw_zenoh_topic_type(const std::string& topic, const ZenohOptions& opts, const RmwZenohOptions& ropts,
                                 std::chrono::milliseconds wait, std::shared_ptr<void>* keep_session) {
  const std::string name = rmw_zenoh::qualified_topic(topic);
  if (keep_session) *keep_session = ZenohSession::shared(opts);
  const int domain = rmw_zenoh_domain(ropts);
  std::set<std::string> from_publishers, from_subscriptions;
  const auto deadline = std::chrono::steady_clock::now() + wait;
  // The graph may hold other topics before this one's publisher appears.
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    for (const auto& e : rmw_zenoh_graph(opts, domain, std::max(left, std::chrono::milliseconds(0)))) {
      if (e.topic != name) continue;
      const std::string t = rmw_zenoh::ros_type_of(e.dds_type).value_or(e.dds_type);
      if (e.is_publisher()) from_publishers.insert(t);
      if (e.is_subscription()) from_subscriptions.insert(t);
    }
    if (!from_publishers.empty() || std::chrono::steady_clock::now() >= deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const auto& types = from_publishers.empty() ? from_subscriptions : from_publishers;
  auto listed = [&] {
    std::string s;
    for (const auto& t : types) s += (s.empty() ? "" : ", ") + t;
    return s;
  };
  if (types.empty())
    throw std::invalid_argument("rmw_zenoh:" + name + ": no publisher or subscription of this topic announced in the " +
                                "ROS 2 graph (domain " + std::to_string(domain) + ") within " +
                                std::to_string(wait.count()) + " ms: give --type, or check ROS_DOMAIN_ID and how rvc " +
                                "meets the system (--connect tcp/127.0.0.1:7447 for rmw_zenoh's router)");
  if (types.size() > 1)
    throw std::invalid_argument("rmw_zenoh:" + name + ": the graph announces several types (" + listed() +
                                "): choose one with --type");
  if (!rmw_zenoh::dds_type_of(*types.begin()))
    throw std::invalid_argument("rmw_zenoh:" + name + ": the graph announces type '" + *types.begin() +
                                "', which is not a ROS 2 message type pkg::msg::dds_::Name_");
  return *types.begin();
}

}  // namespace rvc::transport
