// Options of the dds: transport (domain, partition, QoS, naming, network
// pinning) and the pure helpers behind them: QoS parsing, topic-name mapping,
// the generated CycloneDDS configuration and the end-of-stream marker. None of
// this touches the network; see docs/dds.md for the design.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rvc::msg {
struct MessageType;
}

namespace rvc::transport {

struct DdsOptions {
  int domain = 0;                  // DDS domain id, 0..232 (ports 7400 + 250 * domain)
  std::string partition;           // publisher/subscriber partition; "" = default partition
  std::string qos = "reliable";    // comma-separated QoS items, see parse_qos()
  bool ros2 = true;                // ROS 2 naming: "/a/b" -> DDS topic "rt/a/b"
  std::string type = "string";     // "string": std_msgs/msg/String | "frame": rvc_msgs/msg/Frame (seq + data)
  std::string interface = "lo";    // network interface the generated config pins (name or IPv4 address)
  std::vector<std::string> peers;  // unicast discovery peers; default 127.0.0.1 when interface is loopback
  std::string config_file;         // user's CycloneDDS XML: replaces the generated configuration entirely
  std::string trace_file;          // CycloneDDS trace (config, discovery, info) written to this file
  // CycloneDDS Internal/WriteBatch: a writer packs the samples of a burst
  // into one packet instead of one sendmsg per sample (what ddsperf always
  // does). CycloneDDS never flushes a batch by itself, so sinks flush after
  // the end-of-stream marker, in flush() and idle(), and the commands that
  // turn it on call idle() before every pause. Unset: the command decides
  // (rvc replay and rvc perf pub --rate max: on, measured 0.18 -> 0.9 M
  // samples/s, docs/performance.md; everything else: off);
  // --dds-write-batch / --no-dds-write-batch set it. Not with --dds-config.
  std::optional<bool> write_batch;
  // Set by commands, not by a flag: sources call the handler directly on
  // CycloneDDS's receive thread (a data-available listener) instead of
  // handing samples to a thread of their own. Faster (no wake-up per sample),
  // but only safe when the handler never waits for a DDS writer of this
  // process: a writer blocked on acknowledgements needs the receive thread.
  bool deliver_on_receive_thread = false;
  // Set by commands (--type), not a flag of its own: the topic has this ROS 2
  // type (pkg::msg::dds_::Name_, descriptor built at run time). Sources deliver
  // each sample's CDR (with its encapsulation header) as the payload; sinks
  // take CDR payloads and publish them as samples of the type. Typed topics
  // carry no end-of-stream marker (a ROS 2 publisher sends none).
  const msg::MessageType* ros_type = nullptr;
  // Set by commands (rvc monitor --liveliness-lease), not a flag of every
  // command: writers assert LIVELINESS AUTOMATIC with this lease, so a reader
  // sees a killed writer lose liveliness once it expires. Zero: the DDS
  // default (infinite). Readers keep the default, which accepts any lease.
  std::chrono::milliseconds liveliness_lease{0};
};


namespace dds {

// Parsed --qos. Defaults are the paper's loss-free setting: reliable,
// keep-all, volatile; a writer whose history is full blocks (up to
// max_blocking) instead of dropping.
struct QosSpec {
  bool reliable = true;
  int32_t keep_last = 0;  // 0 = keep-all, else keep-last depth
  bool transient_local = false;
  std::chrono::milliseconds max_blocking{std::chrono::seconds(30)};  // negative = infinite
};

// Items (comma separated, case-insensitive, later ones may not contradict
// earlier ones): reliable | best-effort | keep-all | keep-last=N | volatile |
// transient-local | max-blocking=DURATION (e.g. 500ms, 30s, 2m, inf).
// Throws std::invalid_argument naming the offending item.
QosSpec parse_qos(std::string_view text);

// Validates opts (qos, type, domain, interface) without touching the network.
// Throws std::invalid_argument.
void validate(const DdsOptions& opts);

// The DDS topic name for a user topic: ROS 2 mode strips one leading '/',
// checks ROS 2 name rules and prefixes "rt/"; plain mode uses it as-is.
// Throws std::invalid_argument for names DDS/ROS 2 would reject.
std::string dds_topic_name(std::string_view topic, bool ros2);

// DDS type name of the payload type selected by DdsOptions::type.
std::string dds_type_name(std::string_view type);

// The CycloneDDS XML this process hands to dds_create_domain (never via the
// environment): every participant bound to opts.interface; on a loopback
// interface multicast is off and discovery is unicast to the peers
// (127.0.0.1 by default) with automatic participant indices.
std::string generated_config_xml(const DdsOptions& opts);

// The configuration string actually used: the generated XML, or a file://
// reference to opts.config_file.
std::string effective_config(const DdsOptions& opts);

// End-of-stream marker: a sample on the data topic (same writer, so it is
// ordered after every data sample) whose data is
//   "\x04rvc-eos last=<last_seq> count=<samples written>"
// U+0004 (EOT) can never start a JSON text, so no JSON payload collides.
struct EosMarker {
  uint64_t last_seq = 0;  // publisher's last data sequence number
  uint64_t count = 0;     // data samples the writer published before the marker
};
inline constexpr std::string_view kEosPrefix = "\x04rvc-eos";
std::string format_eos(const EosMarker& m);
// Strict: the prefix, then " last=N" and optionally " count=M" (defaults to
// last); anything else is ordinary data.
std::optional<EosMarker> parse_eos(std::string_view data);

}  // namespace dds
}  // namespace rvc::transport
