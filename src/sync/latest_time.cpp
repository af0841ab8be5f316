// LatestTime (see latest_time.hpp): one held message per input, a set per
// pivot message. Choosing the fastest input costs O(1) per message except
// when the pivot's own rate got worse (then one scan over the inputs).
#include "sync/latest_time.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace rvc::sync {

LatestTime::LatestTime(const PolicyOptions& options, Handler& handler)
    : handler_(handler), n_(static_cast<uint32_t>(options.inputs)), fixed_pivot_(options.pivot) {
  if (options.inputs == 0 || options.inputs > std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("latest: the number of inputs must be positive");
  if (fixed_pivot_ < -1 || (fixed_pivot_ >= 0 && static_cast<size_t>(fixed_pivot_) >= options.inputs))
    throw std::invalid_argument("latest: the pivot must be -1 (the fastest input) or an input");
  inputs_.resize(n_);
  if (fixed_pivot_ >= 0) pivot_ = static_cast<uint32_t>(fixed_pivot_);
  members_.reserve(n_);
}

bool LatestTime::faster(uint32_t a, uint32_t b) const {
  const Input& x = inputs_[a];
  const Input& y = inputs_[b];
  const bool rx = x.count >= 2, ry = y.count >= 2;
  if (rx != ry) return rx;  // a known rate beats none
  if (rx) {
    double mx = (x.hi - x.lo) / static_cast<double>(x.count - 1);
    double my = (y.hi - y.lo) / static_cast<double>(y.count - 1);
    if (mx != my) return mx < my;
  } else if (x.count != y.count) {
    return x.count > y.count;  // no rates yet: the input with most messages
  }
  return a < b;
}

void LatestTime::add(const Member& message) {
  if (message.input >= n_) throw std::out_of_range("latest: input out of range");
  if (!std::isfinite(message.stamp)) {  // no rate can be computed from it
    handler_.on_release(message, Release::Late);
    return;
  }
  const uint32_t i = message.input;
  Input& in = inputs_[i];
  const bool had = in.has;
  const Member old = in.held;
  const Release old_why = in.used ? Release::Used : Release::Replaced;
  if (!had) {
    in.has = true;
    ++with_data_;
    ++held_;
  }
  in.held = message;
  in.used = false;

  // The rate, and the pivot: only this input's rank changed, so the best is
  // the old pivot or this input, unless this input was the pivot and slowed down.
  const bool had_rate = in.count >= 2;
  const double old_mean = had_rate ? (in.hi - in.lo) / static_cast<double>(in.count - 1) : 0;
  if (in.count == 0) {
    in.lo = in.hi = message.stamp;
  } else {
    if (message.stamp < in.lo) in.lo = message.stamp;
    if (message.stamp > in.hi) in.hi = message.stamp;
  }
  ++in.count;
  if (fixed_pivot_ < 0) {
    if (i != pivot_) {
      if (faster(i, pivot_)) pivot_ = i;
    } else if (had_rate && (in.hi - in.lo) / static_cast<double>(in.count - 1) > old_mean) {
      for (uint32_t k = 0; k < n_; ++k)
        if (faster(k, pivot_)) pivot_ = k;
    }
  }

  if (had) handler_.on_release(old, old_why);
  if (i != pivot_ || with_data_ != n_) return;
  members_.clear();
  for (Input& x : inputs_) {
    members_.push_back(x.held);
    x.used = true;
  }
  handler_.on_set(members_.data(), members_.size(), message.stamp);
}

void LatestTime::finish() {
  for (Input& x : inputs_) {
    if (x.has) handler_.on_release(x.held, x.used ? Release::Used : Release::Unfinished);
    x = Input{};
  }
  with_data_ = 0;
  held_ = 0;
  pivot_ = fixed_pivot_ >= 0 ? static_cast<uint32_t>(fixed_pivot_) : 0;
}

}  // namespace rvc::sync
