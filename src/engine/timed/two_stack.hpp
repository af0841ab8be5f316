// A FIFO queue that also answers "the aggregate of everything in it" in O(1)
// amortized per push and pop, for any associative operation (sum, min, max):
// the two-stacks sliding-window aggregation. New values go on the back stack
// with one running aggregate; values leave from the front stack, where each
// entry keeps the aggregate of itself and everything pushed after it (up to
// the front stack's bottom). When the front runs dry, the back stack is moved
// over once, each element once: amortized O(1) whatever the window's length.
//
// Nothing is ever subtracted, so a sum is the fresh sum of at most two
// partial sums: no drift however long the run, and integer sums stay exact
// up to 2^53 (a running sum with add/subtract would accumulate rounding).
#pragma once

#include <cstddef>
#include <vector>

namespace rvc::engine::timed {

// Op: static double identity(); static double combine(double, double).
template <class Op>
class TwoStack {
 public:
  void push(double t, double v) {
    back_.push_back({t, v});
    back_agg_ = Op::combine(back_agg_, v);
  }
  // The oldest element's time (the queue must not be empty).
  double front_time() const { return front_.empty() ? back_.front().t : front_.back().t; }
  void pop() {
    if (front_.empty()) flip();
    front_.pop_back();
  }
  bool empty() const { return front_.empty() && back_.empty(); }
  size_t size() const { return front_.size() + back_.size(); }
  double aggregate() const {
    const double f = front_.empty() ? Op::identity() : front_.back().agg;
    return Op::combine(f, back_agg_);
  }

 private:
  struct Entry {
    double t, v, agg = 0;
  };
  // The back stack, oldest first, becomes the front stack with the oldest
  // on top; each entry's aggregate covers it and every newer one.
  void flip() {
    double agg = Op::identity();
    front_.reserve(back_.size());
    for (size_t i = back_.size(); i-- > 0;) {
      agg = Op::combine(back_[i].v, agg);
      front_.push_back({back_[i].t, back_[i].v, agg});
    }
    back_.clear();
    back_agg_ = Op::identity();
  }
  std::vector<Entry> front_;  // top (back()) = oldest
  std::vector<Entry> back_;   // front() = oldest of the back stack
  double back_agg_ = Op::identity();
};

}  // namespace rvc::engine::timed
