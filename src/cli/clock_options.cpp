#include "cli/clock_options.hpp"

#include "cli/option_ranges.hpp"

#include <stdexcept>

namespace rvc::cli {
namespace {

constexpr const char* kRosPrefix = "ros=";

bool is_ros(const std::string& clock) { return clock.rfind(kRosPrefix, 0) == 0; }

// --clock's value: a clock's name, or ros= and the /clock input's URI.
CLI::Validator live_clock() {
  return CLI::Validator(
      [](std::string& value) -> std::string {
        if (runtime::parse_clock(value)) return "";
        if (!is_ros(value))
          return "a clock is auto, wall, stamps, off or ros=URI (ROS time from /clock), not '" + value + "'";
        const std::string uri = value.substr(std::string(kRosPrefix).size());
        const std::string why = "ros=URI names the /clock input (ros=dds:/clock, ros=zenoh:KEY, ros=file:PATH)";
        if (uri.empty()) return why + ", not an empty URI";
        std::string scheme;  // a scheme is required: a bare path here is more likely a typo than a file
        try {
          scheme = uri.find(':') == std::string::npos ? "" : transport::scheme_of(uri);
        } catch (const std::invalid_argument& e) {
          return why + ": " + e.what();
        }
        if (scheme != "dds" && scheme != "zenoh" && scheme != "file")
          return why + ", not '" + uri + "'";
        return "";
      },
      "auto|wall|stamps|off|ros=URI");
}

}  // namespace

void ClockFlags::add_live(CLI::App& app) {
  app.add_option("--clock", clock,
                 "Dense time: the clock that moves the monitors while no message comes, so a bounded operator falls "
                 "at its instant: wall (system clock, stamps in epoch seconds), stamps (the last stamp plus the time "
                 "since it arrived), auto (wall if the first stamp is within 60 s of the system clock, else stamps), "
                 "off (only messages move time), ros=URI (ROS time, use_sim_time: the latest rosgraph_msgs/Clock on URI, "
                 "e.g. ros=dds:/clock; for simulators and bag replays). A file input ticks once, at its end")
      ->check(live_clock())
      ->capture_default_str();
  app.add_option("--tick", tick,
                 "Dense time on a clock: tick at least every S seconds even with no deadline due (0: only at the "
                 "properties' deadlines, which are exact)")
      ->check(in_range(0, kMaxSeconds, "seconds"))
      ->capture_default_str();
}

void ClockFlags::add_offline(CLI::App& app) {
  app.add_option("--clock", clock,
                 "Dense time: auto ticks at the end of the recording (a bag: its last log time; a JSON trace: its "
                 "last stamp), reporting what falls after the last message; off: only messages move time")
      ->check(CLI::IsMember({"auto", "off"}))
      ->capture_default_str();
}

void ClockFlags::apply(runtime::LoopOptions& loop, bool dense, bool from_file) const {
  loop.tick_bound = tick;
  loop.clock = runtime::ClockKind::Off;
  loop.tick_at_end = dense && from_file && clock != "off";
  if (!dense || from_file) return;  // discrete time has no clock; a file is read as fast as it goes
  loop.clock = is_ros(clock) ? runtime::ClockKind::Ros : *runtime::parse_clock(clock);
}

void ClockFlags::open_ros_clock(runtime::LoopOptions& loop, transport::TransportOptions transports) {
  if (loop.clock != runtime::ClockKind::Ros) return;
  const msg::MessageType& type = ros_types.resolve("rosgraph_msgs/msg/Clock");
#ifdef RVC_HAVE_DDS
  transports.dds.ros_type = &type;  // dds: samples of the ROS type, as a ROS 2 node publishes /clock
#endif
  ros_source = transport::open_source(clock.substr(std::string(kRosPrefix).size()), transports);
  loop.ros_clock = ros_source.get();
  loop.ros_clock_type = &type;
}

}  // namespace rvc::cli
