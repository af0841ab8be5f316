// A FIFO of disjoint, sorted time intervals on a growable ring buffer.
//
// Every bounded past operator keeps its window as intervals already shifted by
// the bounds: an input that holds on [x, y] makes once[a:b] hold on
// [x+a, y+b]. Shifted intervals that overlap are merged on insertion, so the
// queue stays disjoint and a step only touches its front and back: O(1)
// amortized work per event whatever a and b are, and no allocation once the
// buffer has grown to the window's size.
#pragma once

#include <cstddef>
#include <vector>

namespace rvc::engine {

template <class T>
struct Interval {
  T lo, hi;
};

template <class T>
class IntervalQueue {
 public:
  bool empty() const { return size_ == 0; }
  size_t size() const { return size_; }
  const Interval<T>& front() const { return buf_[head_]; }
  const Interval<T>& at(size_t i) const { return buf_[(head_ + i) & mask_]; }
  Interval<T>& back() { return buf_[(head_ + size_ - 1) & mask_]; }
  const Interval<T>& back() const { return buf_[(head_ + size_ - 1) & mask_]; }

  // Appends [lo, hi], merging with the last interval when they touch.
  // `touch` says how close counts as touching: 1 for integer steps (closed
  // intervals [.., 4] and [5, ..] are contiguous), 0 for right-open reals.
  void add(T lo, T hi, T touch) {
    if (size_ > 0) {
      Interval<T>& last = back();
      if (lo <= last.hi + touch) {
        if (hi > last.hi) last.hi = hi;
        return;
      }
    }
    if (size_ == buf_.size()) grow();
    buf_[(head_ + size_) & mask_] = Interval<T>{lo, hi};
    ++size_;
  }
  void pop_front() {
    head_ = (head_ + 1) & mask_;
    --size_;
  }
  // Drops intervals that end before `t` (they can never cover t or later).
  void drop_before(T t) {
    while (size_ > 0 && buf_[head_].hi < t) pop_front();
  }
  // Same for right-open intervals: [lo, hi) is useless once hi <= t.
  void drop_until(T t) {
    while (size_ > 0 && buf_[head_].hi <= t) pop_front();
  }
  void clear() { head_ = size_ = 0; }

 private:
  void grow() {
    size_t cap = buf_.empty() ? 8 : buf_.size() * 2;
    std::vector<Interval<T>> next(cap);
    for (size_t i = 0; i < size_; ++i) next[i] = at(i);
    buf_.swap(next);
    head_ = 0;
    mask_ = cap - 1;
  }
  std::vector<Interval<T>> buf_;
  size_t head_ = 0, size_ = 0, mask_ = 0;
};

}  // namespace rvc::engine
