// Dense time's origin, and the conversions between a run's three views of an
// instant (spec/exact_time.hpp):
//   exact     int64 nanoseconds, as the decoders read stamps;
//   engine    nanoseconds from the origin, in a double (exact below 2^53 ns):
//             what the checker and the timed atoms step on;
//   seconds   a double of seconds since the epoch (or the stamps' zero): the
//             Feed interface's unit, which the loop's clock compares with the
//             system clock.
// The origin is where the timeline starts: the first message's stamp (the
// default: nothing is said about instants before it), or 0 (--origin zero,
// Reelay's rule: [0, first stamp) holds with every field unseen).
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>

#include "spec/exact_time.hpp"

namespace rvc::runtime {

enum class Origin { First, Zero };

class EngineTime {
 public:
  explicit EngineTime(Origin origin = Origin::First) : zero_(origin == Origin::Zero) {}

  bool started() const { return started_; }
  // The first message's stamp sets the origin (once).
  void start(int64_t first_ns) {
    if (started_) return;
    started_ = true;
    origin_ns_ = zero_ ? 0 : first_ns;
  }
  int64_t origin_ns() const { return origin_ns_; }
  double engine(int64_t ns) const { return static_cast<double>(ns - origin_ns_); }
  // Engine time to Feed seconds (+-inf and NaN kept).
  double seconds(double engine) const {
    if (!std::isfinite(engine)) return engine;
    return static_cast<double>(origin_ns_ + std::llround(engine)) / 1e9;
  }
  // Feed seconds back to engine time (to the nearest nanosecond a double of
  // seconds can name; callers that handed out a time map it back exactly).
  double from_seconds(double seconds) const {
    if (!std::isfinite(seconds)) return seconds;
    const double origin_s = static_cast<double>(origin_ns_) / 1e9;
    return static_cast<double>(std::llround((seconds - origin_s) * 1e9));
  }
  // Past this, engine times are no longer exact (2^53 ns, about 104 days).
  static bool exact(double engine) { return std::fabs(engine) <= static_cast<double>(spec::kExactSpanNs); }

 private:
  bool zero_;
  bool started_ = false;
  int64_t origin_ns_ = 0;
};

}  // namespace rvc::runtime
