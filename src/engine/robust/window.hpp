// The extremum of φ's robustness over the steps j with now - j in [lo, hi]:
// once[lo:hi] takes the maximum, historically[lo:hi] the minimum.
//
// A value enters the window `lo` steps after it was seen (a delay line of lo
// values), and leaves after `hi`; in between a monotonic deque keeps only the
// values that can still be the extremum. O(1) amortized per step, memory
// O(hi) at most: the same cost whatever the bounds' size, up to the window.
#pragma once

#include <cstdint>
#include <deque>
#include <limits>
#include <vector>

namespace rvc::engine::robust {

using Step = int64_t;
inline constexpr Step kForever = std::numeric_limits<Step>::max() / 4;

template <bool Max>
class Window {
 public:
  // Reelay starts `once` and `historically` written without bounds at the
  // lowest (highest) finite double, not at an infinity: once{x > 3} over a
  // missing x is -1.8e308; written with bounds (even once[0:]) at -inf (+inf).
  Window(Step lo, Step hi, bool written_bounds)
      : lo_(lo), hi_(hi), delay_(static_cast<size_t>(lo)), running_(written_bounds ? empty() : finite_start()) {}

  // The extremum at step `now` (steps 0, 1, 2, ... in order), given φ's value now.
  double update(Step now, double value) {
    // What enters the window now: the value of step now - lo.
    double entering = value;
    if (lo_ > 0) {
      double& slot = delay_[static_cast<size_t>(now % lo_)];
      entering = slot;
      slot = value;
      if (now < lo_) return empty();
    }
    const Step j = now - lo_;
    if (hi_ >= kForever) {  // unbounded: one running extremum
      if (better(entering, running_)) running_ = entering;
      return running_;
    }
    while (!deque_.empty() && !better(deque_.back().value, entering)) deque_.pop_back();
    deque_.push_back({j, entering});
    while (deque_.front().step < now - hi_) deque_.pop_front();
    return deque_.front().value;
  }

 private:
  struct Entry {
    Step step;
    double value;
  };
  static bool better(double a, double b) { return Max ? a > b : a < b; }
  static double empty() { return Max ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity(); }
  Step lo_, hi_;
  std::vector<double> delay_;
  std::deque<Entry> deque_;
  static double finite_start() { return Max ? std::numeric_limits<double>::lowest() : std::numeric_limits<double>::max(); }
  double running_;
};

}  // namespace rvc::engine::robust
