// The wire conventions of rmw_zenoh_cpp, ROS 2's Zenoh middleware (Jazzy and
// later; Tier 1 in Kilted), as its design document (ros2/rmw_zenoh
// docs/design.md, rmw_zenoh 0.2+ on Zenoh 1.x) describes them. Pure
// functions: no Zenoh here, so the unit tests and a build without the Rust
// crate use them too. docs/zenoh.md, "ROS 2 over rmw_zenoh", has the tables.
//
//  data key      <domain>/<topic without the leading '/'>/<DDS type name>/<type hash>
//                0/vehicle/status/gear_status/pkg::msg::dds_::Name_/RIHS01_<64 hex>
//  attachment    int64 seq LE | int64 source timestamp (ns since epoch) LE |
//                GID length (one byte, 16) | 16 GID bytes     = 33 bytes
//  liveliness    @ros2_lv/<domain>/<session id>/<node id>/<entity id>/<kind>/
//                <enclave>/<namespace>/<node name>[/<topic>/<type>/<hash>/<qos>]
//                kind NN (node: no topic part), MP, MS, SS, SC; names mangled
//                ('/' -> '%', empty -> "%").
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rvc::transport::rmw_zenoh {

inline constexpr std::size_t kGidSize = 16;
inline constexpr std::size_t kAttachmentSize = 8 + 8 + 1 + kGidSize;
inline constexpr std::string_view kLivelinessPrefix = "@ros2_lv";
// REP-2016 type hash of std_msgs/msg/String (what rvc publishes verdicts as),
// the value rmw_zenoh's design document shows for the chatter demo.
inline constexpr std::string_view kStringTypeHash =
    "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18";

using Gid = std::array<std::uint8_t, kGidSize>;

struct Attachment {
  std::int64_t seq = 0;                  // per publisher, 1-based
  std::int64_t source_timestamp_ns = 0;  // publisher's clock, ns since the UNIX epoch
  Gid gid{};                             // the publisher's GID
};

// The 33-byte attachment; nullopt (with `error` set) for anything else: a
// sample without it cannot be accounted for.
std::optional<Attachment> decode_attachment(const std::uint8_t* data, std::size_t len, std::string* error = nullptr);
std::array<std::uint8_t, kAttachmentSize> encode_attachment(const Attachment& a);
// The GID folded into rvc's 64-bit publisher id (SeqCounters): never 0,
// which means "unknown".
std::uint64_t publisher_id(const Gid& gid);

// '/' -> '%'; an empty name is "%" (liveliness chunks cannot be empty).
std::string mangle(std::string_view name);
std::string demangle(std::string_view mangled);

// "pkg::msg::dds_::Name_" -> "pkg/msg/Name" (also srv); nullopt if not that form.
std::optional<std::string> ros_type_of(std::string_view dds_type);
// "pkg/msg/Name" -> "pkg::msg::dds_::Name_"; nullopt if not pkg/msg/Name.
std::optional<std::string> dds_type_of(std::string_view ros_type);

// A fully qualified topic name: "/a/b" (a relative "a/b" gets its '/').
// Throws std::invalid_argument for an empty name, empty or wildcard chunks.
std::string qualified_topic(std::string_view topic);
// The data key expression; type and hash "*" match any.
std::string data_keyexpr(int domain, std::string_view topic, std::string_view dds_type = "*",
                         std::string_view type_hash = "*");
// The liveliness key expression that lists every entity of a domain.
std::string graph_keyexpr(int domain);

struct DataKey {
  int domain = 0;
  std::string topic;  // "/a/b"
  std::string dds_type, type_hash;
};
std::optional<DataKey> parse_data_key(std::string_view key);

struct Entity {
  int domain = 0;
  std::string session_id, node_id, entity_id;
  std::string kind;  // NN, MP, MS, SS, SC
  std::string enclave, name_space, node;  // demangled; "" when unset
  std::string topic;                      // demangled "/a/b"; empty for a node
  std::string dds_type, type_hash, qos;   // empty for a node
  bool is_node() const { return kind == "NN"; }
  bool is_publisher() const { return kind == "MP"; }
  bool is_subscription() const { return kind == "MS"; }
};
// Parses a liveliness token key; nullopt (with `error`) for keys of another
// layout, so a graph listing skips what it does not understand.
std::optional<Entity> parse_liveliness(std::string_view key, std::string* error = nullptr);
std::string liveliness_key(const Entity& e);

// ROS_DOMAIN_ID as rmw_zenoh reads it: unset or empty = 0. Throws
// std::invalid_argument for anything but a number 0..232.
int domain_id_from_env();

// What `rvc topics` prints: every topic with its types and endpoint counts.
struct TopicInfo {
  std::string topic;
  std::vector<std::string> types;  // ROS names (pkg/msg/Name), sorted, distinct
  std::size_t publishers = 0, subscriptions = 0;
};
// Topics of message publishers and subscriptions (services are not topics),
// sorted by name. A DDS type name that is not pkg::msg::dds_::Name_ is kept as is.
std::vector<TopicInfo> graph_topics(const std::vector<Entity>& entities);

}  // namespace rvc::transport::rmw_zenoh
