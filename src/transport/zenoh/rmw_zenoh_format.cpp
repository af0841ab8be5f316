#include "transport/zenoh/rmw_zenoh_format.hpp"

#include <algorithm>
#include <cstdlib>
#include <map>
#include <set>
#include <stdexcept>

namespace rvc::transport::rmw_zenoh {
namespace {

std::vector<std::string_view> split(std::string_view s, char sep) {
  std::vector<std::string_view> parts;
  size_t start = 0;
  for (size_t i; (i = s.find(sep, start)) != std::string_view::npos; start = i + 1) parts.push_back(s.substr(start, i - start));
  parts.push_back(s.substr(start));
  return parts;
}

std::optional<int> parse_domain(std::string_view s) {
  if (s.empty() || s.size() > 3) return std::nullopt;
  int v = 0;
  for (char c : s) {
    if (c < '0' || c > '9') return std::nullopt;
    v = v * 10 + (c - '0');
  }
  return v;
}

void set(std::string* error, std::string text) {
  if (error) *error = std::move(text);
}

std::uint64_t read_le64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<std::uint64_t>(p[i]) << (8 * i);
  return v;
}

}  // namespace

std::optional<Attachment> decode_attachment(const std::uint8_t* data, std::size_t len, std::string* error) {
  if (data == nullptr || len == 0) {
    set(error, "no attachment");
    return std::nullopt;
  }
  if (len < kAttachmentSize) {
    set(error, "attachment of " + std::to_string(len) + " bytes, rmw_zenoh's has " + std::to_string(kAttachmentSize));
    return std::nullopt;
  }
  // The GID is a byte sequence whose length Zenoh's serializer writes as a
  // variable-length integer: 16 takes one byte.
  if (data[16] != kGidSize) {
    set(error, "attachment byte 16 (GID length) is " + std::to_string(data[16]) + ", not 16");
    return std::nullopt;
  }
  Attachment a;
  a.seq = static_cast<std::int64_t>(read_le64(data));
  a.source_timestamp_ns = static_cast<std::int64_t>(read_le64(data + 8));
  std::copy(data + 17, data + 17 + kGidSize, a.gid.begin());
  return a;
}

std::array<std::uint8_t, kAttachmentSize> encode_attachment(const Attachment& a) {
  std::array<std::uint8_t, kAttachmentSize> out{};
  for (int i = 0; i < 8; ++i) {
    out[i] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(a.seq) >> (8 * i));
    out[8 + i] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(a.source_timestamp_ns) >> (8 * i));
  }
  out[16] = kGidSize;
  std::copy(a.gid.begin(), a.gid.end(), out.begin() + 17);
  return out;
}

std::uint64_t publisher_id(const Gid& gid) {
  // FNV-1a over the 16 bytes: distinct GIDs get distinct ids in practice.
  std::uint64_t h = 1469598103934665603ull;
  for (auto b : gid) h = (h ^ b) * 1099511628211ull;
  return h == 0 ? 1 : h;
}

std::string mangle(std::string_view name) {
  if (name.empty()) return "%";
  std::string out(name);
  std::replace(out.begin(), out.end(), '/', '%');
  return out;
}

std::string demangle(std::string_view mangled) {
  if (mangled == "%") return "";
  std::string out(mangled);
  std::replace(out.begin(), out.end(), '%', '/');
  return out;
}

std::optional<std::string> ros_type_of(std::string_view dds_type) {
  auto parts = split(dds_type, ':');  // pkg :: msg :: dds_ :: Name_ -> 7 parts, the odd ones empty
  if (parts.size() != 7 || !parts[1].empty() || !parts[3].empty() || !parts[5].empty()) return std::nullopt;
  const auto pkg = parts[0], kind = parts[2], dds = parts[4], name = parts[6];
  if (pkg.empty() || kind.empty() || dds != "dds_" || name.size() < 2 || name.back() != '_') return std::nullopt;
  return std::string(pkg) + "/" + std::string(kind) + "/" + std::string(name.substr(0, name.size() - 1));
}

std::optional<std::string> dds_type_of(std::string_view ros_type) {
  auto parts = split(ros_type, '/');
  if (parts.size() != 3 || parts[0].empty() || parts[1].empty() || parts[2].empty()) return std::nullopt;
  return std::string(parts[0]) + "::" + std::string(parts[1]) + "::dds_::" + std::string(parts[2]) + "_";
}

std::string qualified_topic(std::string_view topic) {
  if (topic.empty() || topic == "/") throw std::invalid_argument("rmw_zenoh: empty topic name");
  std::string t = topic.front() == '/' ? std::string(topic) : "/" + std::string(topic);
  for (auto chunk : split(std::string_view(t).substr(1), '/')) {
    if (chunk.empty()) throw std::invalid_argument("rmw_zenoh: topic '" + std::string(topic) + "' has an empty name part");
    if (chunk.find_first_of("*$?#%") != std::string_view::npos)
      throw std::invalid_argument("rmw_zenoh: topic '" + std::string(topic) +
                                  "' has a character ROS 2 names cannot hold (* $ ? # %)");
  }
  return t;
}

std::string data_keyexpr(int domain, std::string_view topic, std::string_view dds_type, std::string_view type_hash) {
  return std::to_string(domain) + qualified_topic(topic) + "/" + std::string(dds_type) + "/" + std::string(type_hash);
}

std::string graph_keyexpr(int domain) { return std::string(kLivelinessPrefix) + "/" + std::to_string(domain) + "/**"; }

std::optional<DataKey> parse_data_key(std::string_view key) {
  auto parts = split(key, '/');
  if (parts.size() < 4) return std::nullopt;
  auto domain = parse_domain(parts[0]);
  if (!domain) return std::nullopt;
  DataKey k;
  k.domain = *domain;
  k.dds_type = parts[parts.size() - 2];
  k.type_hash = parts.back();
  for (size_t i = 1; i + 2 < parts.size(); ++i) k.topic += "/" + std::string(parts[i]);
  return k;
}

std::optional<Entity> parse_liveliness(std::string_view key, std::string* error) {
  auto parts = split(key, '/');
  if (parts.empty() || parts[0] != kLivelinessPrefix) {
    set(error, "not under " + std::string(kLivelinessPrefix));
    return std::nullopt;
  }
  if (parts.size() != 9 && parts.size() != 13) {
    set(error, std::to_string(parts.size()) + " chunks, not 9 (node) or 13 (topic or service entity)");
    return std::nullopt;
  }
  Entity e;
  auto domain = parse_domain(parts[1]);
  if (!domain) {
    set(error, "domain id '" + std::string(parts[1]) + "' is not a number");
    return std::nullopt;
  }
  e.domain = *domain;
  e.session_id = parts[2];
  e.node_id = parts[3];
  e.entity_id = parts[4];
  e.kind = parts[5];
  static const std::set<std::string, std::less<>> kinds{"NN", "MP", "MS", "SS", "SC"};
  if (!kinds.count(e.kind)) {
    set(error, "entity kind '" + e.kind + "' is none of NN, MP, MS, SS, SC");
    return std::nullopt;
  }
  if ((parts.size() == 9) != e.is_node()) {
    set(error, "a " + e.kind + " token has " + std::to_string(parts.size()) + " chunks");
    return std::nullopt;
  }
  e.enclave = demangle(parts[6]);
  e.name_space = demangle(parts[7]);
  e.node = parts[8];
  if (!e.is_node()) {
    e.topic = demangle(parts[9]);
    e.dds_type = parts[10];
    e.type_hash = parts[11];
    e.qos = parts[12];
  }
  return e;
}

std::string liveliness_key(const Entity& e) {
  std::string k = std::string(kLivelinessPrefix) + "/" + std::to_string(e.domain) + "/" + e.session_id + "/" + e.node_id +
                  "/" + e.entity_id + "/" + e.kind + "/" + mangle(e.enclave) + "/" + mangle(e.name_space) + "/" + e.node;
  if (!e.is_node()) k += "/" + mangle(e.topic) + "/" + e.dds_type + "/" + e.type_hash + "/" + e.qos;
  return k;
}

int domain_id_from_env() {
  const char* v = std::getenv("ROS_DOMAIN_ID");
  if (v == nullptr || *v == '\0') return 0;
  auto d = parse_domain(v);
  if (!d || *d > 232) throw std::invalid_argument(std::string("ROS_DOMAIN_ID '") + v + "' is not a domain id (0..232)");
  return *d;
}

std::vector<TopicInfo> graph_topics(const std::vector<Entity>& entities) {
  std::map<std::string, TopicInfo> by_topic;
  std::map<std::string, std::set<std::string>> types;
  // One entity may be seen twice (two answers to one query): count each once.
  std::set<std::string> seen;
  for (const auto& e : entities) {
    if (!e.is_publisher() && !e.is_subscription()) continue;
    if (!seen.insert(e.session_id + "/" + e.node_id + "/" + e.entity_id).second) continue;
    auto& t = by_topic[e.topic];
    t.topic = e.topic;
    (e.is_publisher() ? t.publishers : t.subscriptions)++;
    types[e.topic].insert(ros_type_of(e.dds_type).value_or(e.dds_type));
  }
  std::vector<TopicInfo> out;
  for (auto& [name, t] : by_topic) {
    t.types.assign(types[name].begin(), types[name].end());
    out.push_back(std::move(t));
  }
  return out;
}

}  // namespace rvc::transport::rmw_zenoh
