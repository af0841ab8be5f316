// The clock a live dense run ticks on (`rvc monitor --clock`): how the
// messages' time (their stamps, seconds) maps to this host's steady clock,
// so that the loop can sleep until a property's next deadline and tick there
// while no message comes (docs/semantics.md, "Ticks"; docs/cli.md).
//
//   wall    stream time is the system clock, seconds since the epoch: right
//           for ROS header stamps and other epoch stamps.
//   stamps  the last message's stamp plus the steady time elapsed since it
//           arrived: stamps with any origin, going at real-time speed.
//   auto    wall if the first stamp is within kEpochTolerance of the system
//           clock, else stamps.
//   off     no ticks: the monitors move only with messages.
//   ros     ROS time (`use_sim_time`): the latest /clock value
//           (rosgraph_msgs/Clock), set by set_ros_time; it moves only when
//           /clock does, at whatever speed a simulator or a bag replay runs.
//
// Before the first stamped message the clock does not run: the timeline
// starts at 0, and there is nothing held to tick with.
#pragma once

#include <chrono>
#include <functional>
#include <optional>
#include <string>

namespace rvc::runtime {

enum class ClockKind { Off, Auto, Wall, Stamps, Ros };
const char* to_string(ClockKind kind);
// "auto", "wall", "stamps", "off"; nullopt for anything else ("ros" comes
// with its /clock input: ros=URI, parsed by the command).
std::optional<ClockKind> parse_clock(const std::string& text);

// Where the clock reads the time; a fake one in tests.
struct TimeSource {
  std::function<double()> wall;                                   // system clock, seconds since the epoch
  std::function<std::chrono::steady_clock::time_point()> steady;  // monotonic
  static TimeSource system();
};

class StreamClock {
 public:
  using Steady = std::chrono::steady_clock;
  // auto picks wall for stamps at most this far (seconds) from the system
  // clock: clocks of hosts on one network differ by far less, a recording
  // replayed with its own stamps by far more.
  static constexpr double kEpochTolerance = 60;

  explicit StreamClock(ClockKind kind, TimeSource time = TimeSource::system())
      : kind_(kind), time_(std::move(time)) {}

  // The monitors took a message stamped `stamp` (NaN: none); it arrived at
  // steady instant `at`. The first one settles auto.
  void on_message(double stamp, Steady::time_point at);
  // Ros: /clock said `t`. False (and ignored) for a time before the
  // current one: a simulator reset or a bag replayed in a loop must not
  // move the monitors back; an equal time is no change.
  bool set_ros_time(double t);
  // Wall or Stamps, once a message was taken (Off and Auto until then).
  ClockKind kind() const { return kind_; }
  bool running() const { return running_; }
  // Stream time at steady instant `at` (running only).
  double now(Steady::time_point at) const;
  // The steady instant at which stream time reaches `t` (Steady max: never,
  // for +inf or a stopped clock); at most `at` for a time already reached.
  Steady::time_point when(double t, Steady::time_point at) const;
  // Why auto chose what it chose ("stamps are epoch seconds"), once settled.
  const std::string& reason() const { return reason_; }

 private:
  ClockKind kind_;
  TimeSource time_;
  bool running_ = false;
  double stamp_ = 0;        // stamps: the last message's; ros: the latest /clock
  Steady::time_point at_;   // ... and its arrival
  std::string reason_;
};

}  // namespace rvc::runtime
