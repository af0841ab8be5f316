// The monitor's /diagnostics output (`rvc monitor --diagnostics URI`): a
// ROS 2 diagnostic_msgs/msg/DiagnosticArray with one status per property and
// one for the monitor, published on every level change and every `period`
// seconds (as diagnostic_updater does), so a reader that stops hearing from
// rvc marks it STALE itself.
//
// dds: sinks take the CDR sample as a typed DiagnosticArray topic; zenoh:
// sinks the same CDR bytes (as rmw_zenoh and zenoh-bridge-ros2dds carry
// them) or JSON; files and stdout one JSON line per array.
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "engine/checker.hpp"
#include "runtime/diagnostic_status.hpp"
#include "runtime/monitor_loop.hpp"
#include "transport/endpoint.hpp"

namespace rvc::runtime {

struct DiagnosticsOptions {
  DiagIdentity identity;
  double period = 1;       // seconds between two arrays when no level changes
  double stale_after = 5;  // seconds without a message before a property is STALE
  // Property name -> the level of its violation (others: ERROR).
  std::unordered_map<std::string, io::DiagLevel> levels;
};

class DiagnosticsOutput {
 public:
  struct Output {
    std::unique_ptr<transport::Sink> sink;
    bool cdr = false;  // CDR sample (dds:, zenoh: by default) or JSON
  };
  DiagnosticsOutput(std::vector<Output> outputs, const std::vector<engine::PropertySpec>& properties,
                    DiagnosticsOptions options);

  // Every verdict (engine thread): publishes at once if a level changed.
  void on_verdict(const engine::Verdict& v);
  // The loop's tick (engine thread): publishes every `period`, and when a
  // property went STALE or came back.
  void on_tick(const MonitorLoop& loop, std::chrono::steady_clock::time_point now);
  // What on_tick does with the loop's health (public for tests): publishes
  // when the period is due or a level changed.
  void on_health(LoopHealth health, std::chrono::steady_clock::time_point now);
  // The last array (with the final counters), flushed. Throws as a Sink.
  void finish(const MonitorLoop& loop);

  uint64_t published() const { return published_; }

 private:
  std::vector<io::DiagStatus> statuses(const LoopHealth& health) const;
  std::vector<io::DiagLevel> levels(const LoopHealth& health) const;
  void publish(const LoopHealth& health);

  std::vector<Output> outputs_;
  DiagnosticsOptions options_;
  std::vector<PropertyState> properties_;
  std::unordered_map<std::string, size_t> index_;
  LoopHealth health_;        // at the last tick: what a verdict's immediate array reports
  LoopHealth since_;         // at the last periodic array: the monitor's WARN compares with it
  std::vector<io::DiagLevel> last_levels_;
  // At most one array per kMinGap outside the period (level changes).
  static constexpr std::chrono::milliseconds kMinGap{100};
  std::chrono::steady_clock::time_point last_publish_{};  // the last periodic array
  std::chrono::steady_clock::time_point last_any_{};      // the last array of any kind
  std::chrono::steady_clock::time_point last_check_{};    // the last tick that looked at the levels
  uint64_t published_ = 0;
};

}  // namespace rvc::runtime
