// Looking ahead from the instant a dense monitor has reached (its clock, the
// end of the last segment stepped), assuming the operand keeps its value at
// that instant: what a window operator says at the instant itself, and when
// it can next change. Clock-driven monitoring (Checker::tick and
// Checker::next_deadline) reads these; stepping never does.
//
// A window is the queue of once's shifted intervals (interval_queue.hpp),
// right-open, already dropped up to the clock `now` (every step ends with
// drop_until(end)), so each queued interval ends after `now`. An operand that
// holds from `now` on adds [now + lo, inf) to it: the operator's output from
// `now` on is the union of the queue and, if the operand holds, that ray.
#pragma once

#include <limits>

#include "engine/interval_queue.hpp"

namespace rvc::engine::dense {

inline constexpr double kNever = std::numeric_limits<double>::infinity();

// The union's value at `now` (the piece [now, now + e) a step would start with).
inline bool window_at(const IntervalQueue<double>& window, bool holds, double lo, double now) {
  if (holds && lo == 0) return true;  // the ray starts at now itself
  return !window.empty() && window.front().lo <= now;
}

// The first time after `now` at which the union can change: exact except
// when the ray starts inside a queued interval other than the last one, where
// it may be early (a deadline that changes nothing; never a late one). Its
// boundaries after `now` are the queue's and the ray's start, and the
// earliest of the queue's is its front's. kNever when it cannot change.
inline double window_next_change(const IntervalQueue<double>& window, bool holds, double lo, double now) {
  double ray = holds ? now + lo : kNever;
  bool last_joined = false;
  if (holds && !window.empty()) {
    // The operand usually held before now too: the last interval then runs
    // into the ray, and they change as one (no deadline at now + lo).
    const Interval<double>& last = window.back();
    if (last.lo <= ray && ray <= last.hi) {
      ray = last.lo;
      last_joined = true;
    }
  }
  if (ray <= now) return kNever;  // true from now on, for good
  double next = ray;
  if (!window.empty() && !(last_joined && window.size() == 1)) {
    const Interval<double>& first = window.front();
    const double edge = first.lo > now ? first.lo : first.hi;
    if (edge < next) next = edge;
  }
  return next;
}

}  // namespace rvc::engine::dense
