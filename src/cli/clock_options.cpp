#include "cli/clock_options.hpp"

#include "cli/option_ranges.hpp"

namespace rvc::cli {

void ClockFlags::add_live(CLI::App& app) {
  app.add_option("--clock", clock,
                 "Dense time: the clock that moves the monitors while no message comes, so a bounded operator falls "
                 "at its instant: wall (system clock, stamps in epoch seconds), stamps (the last stamp plus the time "
                 "since it arrived), auto (wall if the first stamp is within 60 s of the system clock, else stamps), "
                 "off (only messages move time). A file input ticks once, at its end")
      ->check(CLI::IsMember({"auto", "wall", "stamps", "off"}))
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
  loop.clock = *runtime::parse_clock(clock);
}

}  // namespace rvc::cli
