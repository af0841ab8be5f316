#include "runtime/stream_clock.hpp"

#include <cmath>

namespace rvc::runtime {
namespace {

double seconds(std::chrono::steady_clock::duration d) { return std::chrono::duration<double>(d).count(); }

}  // namespace

const char* to_string(ClockKind kind) {
  switch (kind) {
    case ClockKind::Off: return "off";
    case ClockKind::Auto: return "auto";
    case ClockKind::Wall: return "wall";
    case ClockKind::Stamps: return "stamps";
    case ClockKind::Ros: return "ros";
  }
  return "unknown";
}

std::optional<ClockKind> parse_clock(const std::string& text) {
  for (ClockKind k : {ClockKind::Off, ClockKind::Auto, ClockKind::Wall, ClockKind::Stamps})
    if (text == to_string(k)) return k;
  return std::nullopt;
}

TimeSource TimeSource::system() {
  return TimeSource{
      [] { return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count(); },
      [] { return std::chrono::steady_clock::now(); }};
}

void StreamClock::on_message(double stamp, Steady::time_point at) {
  // ROS time is /clock's alone: messages do not set it.
  if (kind_ == ClockKind::Off || kind_ == ClockKind::Ros || std::isnan(stamp)) return;
  if (kind_ == ClockKind::Auto) {
    const bool epoch = std::fabs(stamp - time_.wall()) <= kEpochTolerance;
    kind_ = epoch ? ClockKind::Wall : ClockKind::Stamps;
    reason_ = epoch ? "the first stamp is within 60 s of the system clock (epoch seconds)"
                    : "the first stamp is not epoch seconds (over 60 s from the system clock)";
  }
  running_ = true;
  stamp_ = stamp;
  at_ = at;
}

bool StreamClock::set_ros_time(double t) {
  if (kind_ != ClockKind::Ros || !std::isfinite(t) || (running_ && t < stamp_)) return false;
  running_ = true;
  stamp_ = t;
  return true;
}

double StreamClock::now(Steady::time_point at) const {
  if (kind_ == ClockKind::Ros) return stamp_;  // stands still between /clock messages
  if (kind_ == ClockKind::Wall) return time_.wall() + seconds(at - time_.steady());
  return stamp_ + seconds(at - at_);
}

StreamClock::Steady::time_point StreamClock::when(double t, Steady::time_point at) const {
  if (!running_ || !(t < INFINITY)) return Steady::time_point::max();
  // ROS time does not run on this host's clock: a deadline is reached when
  // /clock passes it, and no sleep can bring that on.
  if (kind_ == ClockKind::Ros) return t <= stamp_ ? at : Steady::time_point::max();
  const double ahead = t - now(at);  // seconds of stream time still to go
  // Within a microsecond counts as reached: the wall clock and the steady
  // clock are read one after the other, and a wake-up at the rounded
  // instant must not find the deadline a few nanoseconds away.
  if (ahead <= 1e-6) return at;
  // Far deadlines (beyond a day) are left to a later wake-up: no overflow.
  if (ahead > 86400) return at + std::chrono::hours(24);
  // Rounded up to the steady clock's tick: never wake before the deadline.
  return at + std::chrono::ceil<Steady::duration>(std::chrono::duration<double>(ahead));
}

}  // namespace rvc::runtime
