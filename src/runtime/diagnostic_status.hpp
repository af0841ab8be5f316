// How a monitor's state becomes ROS 2 DiagnosticStatus entries: one per
// property ("rvc: <monitor>/<property>") and one for the monitor itself
// ("rvc: <monitor>/monitor"). Pure functions of the state, so the mapping
// (levels, STALE, the key/value pairs) is tested without a network.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "io/diagnostics.hpp"
#include "runtime/monitor_loop.hpp"

namespace rvc::runtime {

// What one property has produced so far.
struct PropertyState {
  std::string name;
  std::string spec;
  io::DiagLevel on_violation = io::DiagLevel::Error;  // --level NAME=warn|error
  bool has_verdict = false;
  bool value = true;         // the last verdict
  double verdict_time = 0;   // the last verdict's time (message time; a step index in discrete time)
  std::string verdict_time_text;  // ... as printed: dense time's exact decimal seconds (empty: from verdict_time)
  uint64_t verdicts = 0;     // verdicts published (one per change, or per message with --all)
  uint64_t violations = 0;   // times it became violated
};

// Who is reporting: the status names and hardware_id.
struct DiagIdentity {
  std::string monitor;      // --name
  std::string hardware_id;  // the host
};

// "warn" or "error" (any case) -> the level a violation is reported at.
// Throws std::invalid_argument naming the accepted values otherwise.
io::DiagLevel parse_violation_level(std::string_view text);

// STALE: an input has delivered nothing for longer than `stale_after`
// seconds (> 0), or no verdict yet; else OK while it holds, its
// on_violation level while violated.
io::DiagStatus property_status(const DiagIdentity& who, const PropertyState& p, const LoopHealth& loop,
                               double stale_after);

// OK while every input delivers; WARN when an input has been silent for
// longer than `stale_after`, or messages were rejected, dropped or lost
// since the previous status (`since`: the counters then).
io::DiagStatus monitor_status(const DiagIdentity& who, const LoopHealth& now, const LoopHealth& since,
                              double stale_after);

}  // namespace rvc::runtime
