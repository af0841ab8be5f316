// Command-line flags of dds: endpoints (CLI11). The transport itself knows
// only the plain DdsOptions struct.
#include <CLI/CLI.hpp>

#include <stdexcept>

#include "cli/transport_flags.hpp"
#include "cli/option_ranges.hpp"

namespace rvc::cli {

void add_dds_options(CLI::App& app, transport::DdsOptions& o) {
  const std::string group = "DDS (dds:TOPIC endpoints)";
  app.add_option("--domain", o.domain, "DDS domain id (0..232)")
      ->check(in_range(0, kMaxDomain))
      ->capture_default_str()
      ->group(group);
  app.add_option("--partition", o.partition, "DDS partition (default: none, as ROS 2)")->group(group);
  app.add_option("--qos", o.qos,
                 "Comma-separated QoS: reliable|best-effort, keep-all|keep-last=N, volatile|transient-local, "
                 "max-blocking=DURATION")
      ->capture_default_str()
      ->check([](const std::string& v) -> std::string {
        try {
          transport::dds::parse_qos(v);
          return {};
        } catch (const std::invalid_argument& e) {
          return e.what();
        }
      })
      ->group(group);
  app.add_option("--dds-type", o.type,
                 "Payload type: string (std_msgs/msg/String) or frame (rvc_msgs/msg/Frame: seq + data)")
      ->capture_default_str()
      ->check(CLI::IsMember({"string", "frame"}))
      ->group(group);
  app.add_option("--dds-interface", o.interface, "Network interface (name or IPv4 address) DDS may use")
      ->capture_default_str()
      ->group(group);
  app.add_option("--dds-peer", o.peers, "Unicast discovery peer address (repeatable; default 127.0.0.1 on lo)")
      ->group(group);
  app.add_option("--dds-config", o.config_file, "CycloneDDS XML configuration file (replaces the generated one)")
      ->check(CLI::ExistingFile)
      ->group(group);
  app.add_option("--dds-trace", o.trace_file, "Write a CycloneDDS trace (config, discovery) to this file")
      ->group(group);
  // Unset: the command decides (rvc replay, rvc perf pub --rate max: on).
  CLI::Option* batch = app.add_flag_callback(
         "--dds-write-batch", [&o] { o.write_batch = true; },
         "Pack several samples per packet (CycloneDDS WriteBatch; flushed before pauses and at the end). On by "
         "default for rvc replay and rvc perf pub --rate max")
      ->group(group);
  app.add_flag_callback(
         "--no-dds-write-batch", [&o] { o.write_batch = false; }, "One UDP packet per sample (no WriteBatch)")
      ->excludes(batch)
      ->group(group);
  app.add_flag_callback(
         "--no-ros2-names", [&o] { o.ros2 = false; },
         "Use TOPIC as the DDS topic name (no ROS 2 'rt/' prefix or name checks)")
      ->group(group);
}

}  // namespace rvc::cli
