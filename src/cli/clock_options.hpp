// --clock and --tick: the clock dense time ticks on while no message comes
// (docs/cli.md "Clocks", docs/semantics.md "Ticks"). Live runs (rvc monitor)
// take every clock; a recording (rvc check, a bag) has its own time, so
// there only auto (tick at its end) and off make sense.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>
#include <string>

#include "msg/type_registry.hpp"
#include "runtime/monitor_loop.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {

struct ClockFlags {
  std::string clock = "auto";
  double tick = 0;  // --tick SECONDS: at most this long between ticks (0: deadlines only)
  // ros=URI: the /clock input, and the registry owning its type.
  std::unique_ptr<transport::Source> ros_source;
  msg::TypeRegistry ros_types;

  void add_live(CLI::App& app);     // --clock auto|wall|stamps|off|ros=URI, --tick
  void add_offline(CLI::App& app);  // --clock auto|off
  // The loop's clock for a live input (a file: off, its end ticks instead);
  // discrete time has none. Sets the loop's options.
  void apply(runtime::LoopOptions& loop, bool dense, bool from_file) const;
  // --clock ros=URI on a live input: subscribes to /clock (typed
  // rosgraph_msgs/Clock on dds:) for the loop. Call after apply; throws as
  // transport::open_source.
  void open_ros_clock(runtime::LoopOptions& loop, transport::TransportOptions transports);
  // A recording: ticks at its end (auto), or none (off).
  bool ticks_at_end(bool dense) const { return dense && clock != "off"; }
};

}  // namespace rvc::cli
