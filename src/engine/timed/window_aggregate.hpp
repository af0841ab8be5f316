// One window aggregate, count/sum/avg/min/max[a:b](x), over the samples of
// one input: each of its messages gives a sample (its time, the field's value,
// or 1 for an arrival). At time t a sample taken at s is in the window when
//
//   discrete (steps):    s + a <= t <= s + b        (closed, like once[a:b])
//   dense (seconds):     s + a <= t <  s + b        (the window (t-b, t-a])
//
// Dense signals in rvc are right-continuous (a value holds over [t, next)),
// so the instant s + b, where the sample leaves, takes the value after it.
//
// Samples arrive in time order. Those not yet in the window (a > 0) wait in
// `pending_`; those in it are in a TwoStack per operation. Every sample
// enters once and leaves once: O(1) amortized per sample, whatever the
// window holds. Empty window: count and sum 0; avg, min, max NaN (every
// comparison with them is false; robustness -inf).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>

#include "engine/timed/two_stack.hpp"
#include "spec/ast.hpp"

namespace rvc::engine::timed {

struct SumOp {
  static double identity() { return 0; }
  static double combine(double a, double b) { return a + b; }
};
struct MinOp {
  static double identity() { return std::numeric_limits<double>::infinity(); }
  static double combine(double a, double b) { return b < a ? b : a; }
};
struct MaxOp {
  static double identity() { return -std::numeric_limits<double>::infinity(); }
  static double combine(double a, double b) { return b > a ? b : a; }
};

class WindowAggregate {
 public:
  // `dense`: bounds in seconds, window (t-b, t-a]; else steps, [t-b, t-a].
  WindowAggregate(spec::Timed::Func func, spec::Bounds window, bool dense)
      : func_(func), enter_(window.lo), leave_(dense ? window.hi : window.hi + 1) {}

  // Time moves on to t (never back): samples enter and leave.
  void advance(double t) {
    while (!pending_.empty() && pending_.front().t + enter_ <= t) {
      insert(pending_.front().t, pending_.front().v);
      pending_.pop_front();
    }
    while (count_ > 0 && front_time() + leave_ <= t) remove();
  }
  // A sample at time t (the current time: advance(t) came first).
  void add(double t, double v) {
    if (enter_ > 0) pending_.push_back({t, v});
    else if (t + leave_ > t) insert(t, v);  // a window [0:0] in dense time holds nothing
  }
  // The first instant after `now` at which the window's content changes
  // (+inf: none), computed as advance() compares, so stepping to it moves.
  double next_change(double now) const {
    double next = std::numeric_limits<double>::infinity();
    if (!pending_.empty()) next = pending_.front().t + enter_;
    if (count_ > 0) next = std::min(next, front_time() + leave_);
    return next > now ? next : std::numeric_limits<double>::infinity();
  }
  double value() const {
    constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
    switch (func_) {
      case spec::Timed::Func::Count: return static_cast<double>(count_);
      case spec::Timed::Func::Sum: return count_ ? sum_.aggregate() : 0;
      case spec::Timed::Func::Avg: return count_ ? sum_.aggregate() / static_cast<double>(count_) : kNone;
      case spec::Timed::Func::Min: return count_ ? min_.aggregate() : kNone;
      case spec::Timed::Func::Max: return count_ ? max_.aggregate() : kNone;
    }
    return kNone;
  }
  uint64_t size() const { return count_; }

 private:
  struct Sample {
    double t, v;
  };
  void insert(double t, double v) {
    ++count_;
    times_.push_back(t);
    switch (func_) {
      case spec::Timed::Func::Count: break;
      case spec::Timed::Func::Sum:
      case spec::Timed::Func::Avg: sum_.push(t, v); break;
      case spec::Timed::Func::Min: min_.push(t, v); break;
      case spec::Timed::Func::Max: max_.push(t, v); break;
    }
  }
  void remove() {
    --count_;
    times_.pop_front();
    switch (func_) {
      case spec::Timed::Func::Count: break;
      case spec::Timed::Func::Sum:
      case spec::Timed::Func::Avg: sum_.pop(); break;
      case spec::Timed::Func::Min: min_.pop(); break;
      case spec::Timed::Func::Max: max_.pop(); break;
    }
  }
  double front_time() const { return times_.front(); }

  spec::Timed::Func func_;
  double enter_, leave_;  // a sample at s is in the window from s + enter_ until s + leave_
  std::deque<Sample> pending_;
  std::deque<double> times_;  // the window's samples' times, oldest first
  uint64_t count_ = 0;
  TwoStack<SumOp> sum_;
  TwoStack<MinOp> min_;
  TwoStack<MaxOp> max_;
};

}  // namespace rvc::engine::timed
