#include "runtime/topic_rate.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rvc::runtime {

const char* to_string(TopicState state) {
  switch (state) {
    case TopicState::Ok: return "OK";
    case TopicState::NotReceived: return "NotReceived";
    case TopicState::WarnRate: return "WarnRate";
    case TopicState::ErrorRate: return "ErrorRate";
    case TopicState::Timeout: return "Timeout";
  }
  return "Unknown";
}

io::DiagLevel diag_level(TopicState state) {
  switch (state) {
    case TopicState::Ok: return io::DiagLevel::Ok;
    case TopicState::WarnRate: return io::DiagLevel::Warn;
    case TopicState::NotReceived:
    case TopicState::ErrorRate:
    case TopicState::Timeout: return io::DiagLevel::Error;
  }
  return io::DiagLevel::Error;
}

// Welford's update, and its exact inverse for the value leaving the window:
// stable where sum/sum-of-squares would cancel (intervals of 0.1 s differing
// in the microseconds).
void SlidingMoments::add(double x) {
  ++n_;
  const double d = x - mean_;
  mean_ += d / static_cast<double>(n_);
  m2_ += d * (x - mean_);
}

void SlidingMoments::remove(double x) {
  if (n_ <= 1) {
    *this = SlidingMoments();
    return;
  }
  --n_;
  const double d = x - mean_;
  mean_ -= d / static_cast<double>(n_);
  m2_ -= d * (x - mean_);
}

void SlidingExtremum::push(uint64_t index, double x) {
  // A value that can never be the extremum again (an older one beaten by x,
  // which stays longer) is dropped now: each value enters and leaves once.
  while (!q_.empty() && (keep_max_ ? q_.back().second <= x : q_.back().second >= x)) q_.pop_back();
  q_.emplace_back(index, x);
}

void SlidingExtremum::drop_below(uint64_t index) {
  while (!q_.empty() && q_.front().first < index) q_.pop_front();
}

TopicRate::TopicRate(const RateThresholds& thresholds) : thresholds_(thresholds), cap_(thresholds.window_size) {
  if (cap_ < 2)
    throw std::invalid_argument("window_size must be at least 2 (a rate needs two arrivals), got " +
                                std::to_string(cap_));
  for (const auto& [name, v] : {std::pair{"warn_rate", thresholds.warn_rate},
                                {"error_rate", thresholds.error_rate}, {"timeout", thresholds.timeout}})
    if (!std::isfinite(v) || v < 0)
      throw std::invalid_argument(std::string(name) + " must be a finite number >= 0 (0: off), got " +
                                  std::to_string(v));
  arrivals_.resize(cap_);
  latencies_.resize(cap_);
}

void TopicRate::add(double arrival, std::optional<double> latency) {
  const uint64_t index = received_;
  if (size_ == cap_) {  // the oldest arrival leaves, and the interval after it
    const size_t next = (head_ + 1) % cap_;
    intervals_.remove(arrivals_[next] - arrivals_[head_]);
    if (latencies_[head_]) latency_.remove(*latencies_[head_]);
    head_ = next;
    --size_;
  }
  if (size_ > 0) {
    const double interval = arrival - last_;
    intervals_.add(interval);
    interval_min_.push(index, interval);
    interval_max_.push(index, interval);
  }
  const size_t slot = (head_ + size_) % cap_;
  arrivals_[slot] = arrival;
  latencies_[slot] = latency;
  ++size_;
  if (latency) {
    latency_.add(*latency);
    latency_max_.push(index, *latency);
  }
  ++received_;
  last_ = arrival;
  const uint64_t first = received_ - size_;  // the window's oldest arrival
  interval_min_.drop_below(first + 1);       // interval i ends at arrival i
  interval_max_.drop_below(first + 1);
  latency_max_.drop_below(first);
}

double TopicRate::rate() const {
  if (size_ < 2) return std::numeric_limits<double>::infinity();
  const double span = last_ - arrivals_[head_];
  return span > 0 ? static_cast<double>(size_ - 1) / span : std::numeric_limits<double>::infinity();
}

TopicState TopicRate::state(double now) const {
  if (received_ == 0) return TopicState::NotReceived;
  if (thresholds_.timeout > 0 && now - last_ > thresholds_.timeout) return TopicState::Timeout;
  const double r = rate();
  if (thresholds_.error_rate > 0 && r < thresholds_.error_rate) return TopicState::ErrorRate;
  if (thresholds_.warn_rate > 0 && r < thresholds_.warn_rate) return TopicState::WarnRate;
  return TopicState::Ok;
}

std::optional<double> TopicRate::timeout_at() const {
  if (received_ == 0 || thresholds_.timeout <= 0) return std::nullopt;
  return last_ + thresholds_.timeout;
}

RateSummary TopicRate::summary(double now) const {
  RateSummary s;
  s.received = received_;
  s.window = size_;
  s.rate = rate();
  if (intervals_.count() > 0) {
    s.interval_mean = intervals_.mean();
    s.interval_std = std::sqrt(intervals_.variance());
    s.interval_min = interval_min_.value();
    s.interval_max = interval_max_.value();
  }
  s.latency_samples = latency_.count();
  if (s.latency_samples > 0) {
    s.latency_mean = latency_.mean();
    s.latency_max = latency_max_.value();
  }
  s.silence = received_ > 0 ? now - last_ : 0;
  return s;
}

namespace {
// `candidate` if it is after `after`, else the next double after `after`.
double after_(double candidate, double after) {
  return candidate > after ? candidate : std::nextafter(after, std::numeric_limits<double>::infinity());
}
}  // namespace

const StampSchedule::Step& StampSchedule::step(double time) {
  step_.reports.clear();
  step_.skipped = 0;
  if (!std::isfinite(time)) return step_;  // callers refuse such times first; no boundary moves to NaN
  if (!started()) {
    next_ = after_(time + period_, time);
    return step_;
  }
  if (!(time >= next_)) return step_;  // NaN too: callers refuse it first
  const double due = std::floor((time - next_) / period_) + 1;  // boundaries passed
  if (due > kMaxCatchUp) {
    step_.reports.push_back(next_);
    step_.skipped = due - 1;
    const double next = next_ + due * period_;  // inf for a jump past the doubles' range of periods
    next_ = after_(std::isfinite(next) ? next : time, time);
    return step_;
  }
  while (time >= next_) {
    step_.reports.push_back(next_);
    next_ = after_(next_ + period_, next_);
  }
  return step_;
}

}  // namespace rvc::runtime
