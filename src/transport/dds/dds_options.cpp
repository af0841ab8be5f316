#include "transport/dds/dds_options.hpp"


#include <algorithm>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <limits>
#include <stdexcept>

namespace rvc::transport {
namespace dds {
namespace {

constexpr int kMaxDomain = 232;  // 7400 + 250 * domain + offsets must stay below 65536
constexpr const char* kQosItems =
    "reliable, best-effort, keep-all, keep-last=N, volatile, transient-local, max-blocking=DURATION, "
    "or a ROS 2 profile: ros2-default (reliable, keep-last=10, volatile), sensor-data (best-effort, keep-last=5, "
    "volatile)";

std::string trim_lower(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  std::string out(s);
  for (char& c : out) {
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (c == '_') c = '-';
  }
  return out;
}

bool parse_u64(std::string_view s, uint64_t& out) {
  if (s.empty()) return false;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size();
}

std::chrono::milliseconds parse_duration(std::string_view v, const std::string& item) {
  if (v == "inf" || v == "infinite" || v == "infinity") return std::chrono::milliseconds(-1);
  size_t i = 0;
  while (i < v.size() && std::isdigit(static_cast<unsigned char>(v[i]))) ++i;
  uint64_t n = 0;
  if (!parse_u64(v.substr(0, i), n))
    throw std::invalid_argument("--qos: '" + item + "': expected a duration such as 500ms, 30s, 2m or inf");
  std::string_view unit = v.substr(i);
  uint64_t ms;
  if (unit == "ms") ms = n;
  else if (unit == "s") ms = n * 1000;
  else if (unit == "m" || unit == "min") ms = n * 60000;
  else
    throw std::invalid_argument("--qos: '" + item + "': duration needs a unit (ms, s, m) or 'inf'");
  if (n > 1000000000ULL) throw std::invalid_argument("--qos: '" + item + "': duration too large");
  return std::chrono::milliseconds(static_cast<int64_t>(ms));
}

std::string xml_escape(std::string_view s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

bool looks_like_ipv4(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)) || c == '.'; });
}

bool is_loopback_interface(std::string_view iface) {
  return iface == "lo" || iface == "lo0" || iface.substr(0, 4) == "127." || iface == "::1";
}


// ROS 2's named profiles (rmw_qos_profile_default, rmw_qos_profile_sensor_data),
// for subscribing to ROS 2 publishers as they are usually set up.
std::string expand_profiles(std::string_view text) {
  std::string out;
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t comma = text.find(',', pos);
    if (comma == std::string_view::npos) comma = text.size();
    std::string item(text.substr(pos, comma - pos));
    const std::string key = trim_lower(item);
    if (key == "ros2-default") item = "reliable,keep-last=10,volatile";
    else if (key == "sensor-data") item = "best-effort,keep-last=5,volatile";
    out += (out.empty() && pos == 0 ? "" : ",") + item;
    if (comma == text.size()) break;
    pos = comma + 1;
  }
  return out;
}

}  // namespace

QosSpec parse_qos(std::string_view original) {
  const std::string expanded = expand_profiles(original);
  const std::string_view text = expanded;
  QosSpec q;
  bool set_rel = false, set_hist = false, set_dur = false, set_block = false;
  const std::string whole(original);
  auto conflict = [&](bool already, const std::string& item, const char* what) {
    if (already)
      throw std::invalid_argument("--qos: '" + item + "' contradicts an earlier " + what + " item in '" + whole + "'");
  };
  size_t pos = 0;
  if (trim_lower(text).empty()) return q;
  while (pos <= text.size()) {
    size_t comma = text.find(',', pos);
    if (comma == std::string_view::npos) comma = text.size();
    const std::string item = trim_lower(text.substr(pos, comma - pos));
    pos = comma + 1;
    if (item.empty()) throw std::invalid_argument("--qos: empty item in '" + whole + "'");
    const size_t eq = item.find('=');
    const std::string key = item.substr(0, eq);
    const std::string val = eq == std::string::npos ? "" : item.substr(eq + 1);
    if (key == "reliable" && eq == std::string::npos) {
      conflict(set_rel && !q.reliable, item, "reliability");
      set_rel = true, q.reliable = true;
    } else if ((key == "best-effort" || key == "besteffort") && eq == std::string::npos) {
      conflict(set_rel && q.reliable, item, "reliability");
      set_rel = true, q.reliable = false;
    } else if (key == "keep-all" && eq == std::string::npos) {
      conflict(set_hist && q.keep_last != 0, item, "history");
      set_hist = true, q.keep_last = 0;
    } else if (key == "keep-last") {
      uint64_t n = 0;
      if (!parse_u64(val, n) || n == 0 || n > static_cast<uint64_t>(std::numeric_limits<int32_t>::max()))
        throw std::invalid_argument("--qos: '" + item + "': keep-last needs a depth N >= 1, e.g. keep-last=10");
      conflict(set_hist && q.keep_last != static_cast<int32_t>(n), item, "history");
      set_hist = true, q.keep_last = static_cast<int32_t>(n);
    } else if (key == "volatile" && eq == std::string::npos) {
      conflict(set_dur && q.transient_local, item, "durability");
      set_dur = true, q.transient_local = false;
    } else if (key == "transient-local" && eq == std::string::npos) {
      conflict(set_dur && !q.transient_local, item, "durability");
      set_dur = true, q.transient_local = true;
    } else if (key == "max-blocking") {
      auto d = parse_duration(val, item);
      conflict(set_block && d != q.max_blocking, item, "max-blocking");
      set_block = true, q.max_blocking = d;
    } else {
      throw std::invalid_argument("--qos: unknown item '" + item + "' in '" + whole + "' (expected " + kQosItems + ")");
    }
    if (comma == text.size()) break;
  }
  return q;
}

std::string dds_type_name(std::string_view type) {
  if (type == "string") return "std_msgs::msg::dds_::String_";
  if (type == "frame") return "rvc_msgs::msg::dds_::Frame_";
  throw std::invalid_argument("--dds-type: unknown type '" + std::string(type) +
                              "' (expected 'string' for std_msgs/msg/String or 'frame' for rvc_msgs/msg/Frame)");
}

void validate(const DdsOptions& o) {
  if (o.domain < 0 || o.domain > kMaxDomain)
    throw std::invalid_argument("--domain: " + std::to_string(o.domain) + " is outside 0.." + std::to_string(kMaxDomain));
  parse_qos(o.qos);
  dds_type_name(o.type);
  if (o.config_file.empty() && o.interface.empty())
    throw std::invalid_argument("--dds-interface: empty interface name (use 'lo' for loopback)");
  if (!o.config_file.empty() && !o.trace_file.empty())
    throw std::invalid_argument("--dds-trace cannot be combined with --dds-config: add a <Tracing> section to your file");
  if (!o.config_file.empty() && !o.peers.empty())
    throw std::invalid_argument("--dds-peer cannot be combined with --dds-config: add <Discovery><Peers> to your file");
  if (!o.config_file.empty() && o.write_batch.value_or(false))
    throw std::invalid_argument(
        "--dds-write-batch cannot be combined with --dds-config: add <Internal><WriteBatch>true</WriteBatch></Internal> "
        "to your file");
  for (const auto& p : o.peers)
    if (p.empty()) throw std::invalid_argument("--dds-peer: empty address");
}

std::string dds_topic_name(std::string_view topic, bool ros2) {
  const std::string shown(topic);
  if (!ros2) {
    if (topic.empty()) throw std::invalid_argument("dds: empty topic name");
    for (char c : topic)
      if (std::iscntrl(static_cast<unsigned char>(c)) || std::isspace(static_cast<unsigned char>(c)) || c == '*' || c == '?')
        throw std::invalid_argument("dds: topic '" + shown + "' contains whitespace, control characters, '*' or '?'");
    return std::string(topic);
  }
  std::string_view name = topic;
  if (!name.empty() && name.front() == '/') name.remove_prefix(1);
  auto bad = [&](const std::string& why) {
    return std::invalid_argument("dds: '" + shown + "' is not a valid ROS 2 topic name: " + why +
                                 " (use --no-ros2-names for a plain DDS topic name)");
  };
  if (name.empty()) throw bad("empty");
  if (name.back() == '/') throw bad("ends with '/'");
  size_t start = 0;
  while (start <= name.size()) {
    size_t slash = name.find('/', start);
    if (slash == std::string_view::npos) slash = name.size();
    std::string_view tok = name.substr(start, slash - start);
    if (tok.empty()) throw bad("contains '//'");
    if (std::isdigit(static_cast<unsigned char>(tok.front()))) throw bad("a name token starts with a digit");
    for (char c : tok)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_')
        throw bad(std::string("character '") + c + "' is not allowed (only [A-Za-z0-9_/])");
    if (tok.find("__") != std::string_view::npos) throw bad("contains '__'");
    if (slash == name.size()) break;
    start = slash + 1;
  }
  return "rt/" + std::string(name);
}

std::string generated_config_xml(const DdsOptions& o) {
  const bool loopback = is_loopback_interface(o.interface);
  std::vector<std::string> peers = o.peers;
  if (peers.empty() && loopback) peers.push_back("127.0.0.1");
  const bool unicast = !peers.empty();
  std::string x;
  x += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  x += "<!-- Generated by rvc (dds transport): every participant uses only interface '" + xml_escape(o.interface) + "'";
  x += unicast ? "; multicast off, unicast discovery. -->\n" : ". -->\n";
  x += "<CycloneDDS xmlns=\"https://cdds.io/config\">\n";
  x += "  <Domain Id=\"any\">\n";
  x += "    <General>\n";
  x += "      <Interfaces>\n";
  x += "        <NetworkInterface ";
  x += looks_like_ipv4(o.interface) ? "address=\"" : "name=\"";
  x += xml_escape(o.interface) + "\"";
  if (unicast) x += " multicast=\"false\"";
  x += "/>\n";
  x += "      </Interfaces>\n";
  if (unicast) x += "      <AllowMulticast>false</AllowMulticast>\n";
  x += "    </General>\n";
  x += "    <Discovery>\n";
  if (unicast) {
    // Unicast discovery probes the ports of participant indices 0..Max on
    // every peer: 100 leaves room for many rvc processes per host and domain.
    x += "      <ParticipantIndex>auto</ParticipantIndex>\n";
    x += "      <MaxAutoParticipantIndex>100</MaxAutoParticipantIndex>\n";
    x += "      <Peers>\n";
    for (const auto& p : peers) x += "        <Peer address=\"" + xml_escape(p) + "\"/>\n";
    x += "      </Peers>\n";
  }
  x += "    </Discovery>\n";
  if (o.write_batch.value_or(false)) x += "    <Internal><WriteBatch>true</WriteBatch></Internal>\n";
  if (!o.trace_file.empty()) {
    x += "    <Tracing>\n";
    x += "      <Category>config,info,discovery</Category>\n";
    x += "      <OutputFile>" + xml_escape(o.trace_file) + "</OutputFile>\n";
    x += "    </Tracing>\n";
  }
  x += "  </Domain>\n";
  x += "</CycloneDDS>\n";
  return x;
}

std::string effective_config(const DdsOptions& o) {
  if (o.config_file.empty()) return generated_config_xml(o);
  std::error_code ec;
  auto path = std::filesystem::absolute(o.config_file, ec);
  if (ec || !std::filesystem::is_regular_file(path, ec))
    throw std::invalid_argument("--dds-config: no such file '" + o.config_file + "'");
  return "file://" + path.string();
}

std::string format_eos(const EosMarker& m) {
  return std::string(kEosPrefix) + " last=" + std::to_string(m.last_seq) + " count=" + std::to_string(m.count);
}

std::optional<EosMarker> parse_eos(std::string_view d) {
  if (d.substr(0, kEosPrefix.size()) != kEosPrefix) return std::nullopt;
  d.remove_prefix(kEosPrefix.size());
  auto field = [&](std::string_view key, uint64_t& out) {
    if (d.substr(0, key.size()) != key) return false;
    size_t end = key.size();
    while (end < d.size() && d[end] != ' ') ++end;
    if (!parse_u64(d.substr(key.size(), end - key.size()), out)) return false;
    d.remove_prefix(end);
    return true;
  };
  EosMarker m;
  if (!field(" last=", m.last_seq)) return std::nullopt;
  m.count = m.last_seq;
  if (!d.empty() && !field(" count=", m.count)) return std::nullopt;
  if (!d.empty()) return std::nullopt;
  return m;
}

}  // namespace dds

}  // namespace rvc::transport
