// `rvc hz`'s statistics of one topic: rate, inter-arrival jitter, silence and
// stamp latency over the last `window_size` arrivals, and the topic state
// Autoware's topic_state_monitor reports (OK / NotReceived / WarnRate /
// ErrorRate / Timeout) from the same parameters (warn_rate, error_rate,
// timeout, window_size).
//
// Every add() is O(1) (amortized for min/max): arrivals and latencies live in
// ring buffers of window_size, their mean and variance in sliding Welford
// sums (an add and a remove per message, no re-summing of the window), the
// extrema in monotonic deques. Times are plain seconds on whatever clock the
// caller chose (steady clock, or the messages' own stamps); nothing here reads
// a clock, so tests drive it with exact numbers.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "io/diagnostics.hpp"

namespace rvc::runtime {

// topic_state_monitor's parameters. A zero rate or timeout disables that
// check, as there.
struct RateThresholds {
  double warn_rate = 0;     // Hz: below it (strictly), WarnRate
  double error_rate = 0;    // Hz: below it (strictly), ErrorRate
  double timeout = 1.0;     // s: no message for longer than this (strictly), Timeout
  size_t window_size = 10;  // arrivals the rate and jitter are computed over (>= 2)
};

// In topic_state_monitor's order of precedence: NotReceived, then Timeout,
// then ErrorRate, then WarnRate, else Ok.
enum class TopicState : uint8_t { Ok, NotReceived, WarnRate, ErrorRate, Timeout };
const char* to_string(TopicState state);  // "OK", "NotReceived", "WarnRate", "ErrorRate", "Timeout"
// The DiagnosticStatus level topic_state_monitor gives each state: OK -> OK,
// WarnRate -> WARN, NotReceived / ErrorRate / Timeout -> ERROR.
io::DiagLevel diag_level(TopicState state);

// Mean and population variance of a sliding multiset of numbers.
class SlidingMoments {
 public:
  void add(double x);
  void remove(double x);  // x must have been added and not yet removed
  size_t count() const { return n_; }
  double mean() const { return mean_; }
  double variance() const { return n_ == 0 || m2_ < 0 ? 0 : m2_ / static_cast<double>(n_); }

 private:
  size_t n_ = 0;
  double mean_ = 0, m2_ = 0;
};

// Minimum or maximum of the values pushed with index >= a floor that only
// rises: a monotonic deque, amortized O(1) per value.
class SlidingExtremum {
 public:
  explicit SlidingExtremum(bool keep_max) : keep_max_(keep_max) {}
  void push(uint64_t index, double x);
  void drop_below(uint64_t index);  // forget values pushed with a smaller index
  bool empty() const { return q_.empty(); }
  double value() const { return q_.front().second; }

 private:
  bool keep_max_;
  std::deque<std::pair<uint64_t, double>> q_;
};

// What a report shows of one topic's window.
struct RateSummary {
  uint64_t received = 0;    // every message added since the start
  size_t window = 0;        // arrivals in the window (<= window_size)
  double rate = std::numeric_limits<double>::infinity();  // Hz: (window - 1) / (last - first); inf below 2
  double interval_mean = 0, interval_std = 0, interval_min = 0, interval_max = 0;  // s, 0 below 2 arrivals
  size_t latency_samples = 0;  // arrivals of the window that carried a stamp
  double latency_mean = 0, latency_max = 0;  // s (arrival - stamp)
  double silence = 0;          // s since the last arrival (at the `now` asked for); 0 before any
};

class TopicRate {
 public:
  // Throws std::invalid_argument for window_size < 2 or negative thresholds.
  explicit TopicRate(const RateThresholds& thresholds);

  // One message arrived at `arrival` (not before the previous one: callers
  // refuse those), with `latency` = arrival - its stamp when it has a stamp.
  void add(double arrival, std::optional<double> latency);

  const RateThresholds& thresholds() const { return thresholds_; }
  uint64_t received() const { return received_; }
  bool any() const { return received_ > 0; }
  double last_arrival() const { return last_; }
  // Rate over the window, as topic_state_monitor computes it; inf with fewer
  // than two arrivals (it then reports its maximum rate: no rate state).
  double rate() const;
  TopicState state(double now) const;
  // When the topic turns Timeout if nothing arrives: strictly after this
  // time. nullopt if it cannot (no timeout set, or nothing received yet).
  std::optional<double> timeout_at() const;
  RateSummary summary(double now) const;

 private:
  RateThresholds thresholds_;
  size_t cap_;
  std::vector<double> arrivals_;                 // ring of the window's arrivals
  std::vector<std::optional<double>> latencies_;  // ring, same slots
  size_t head_ = 0, size_ = 0;                   // oldest slot, arrivals held
  uint64_t received_ = 0;                        // also the index of the next arrival
  double last_ = 0;
  SlidingMoments intervals_, latency_;
  SlidingExtremum interval_min_{false}, interval_max_{true}, latency_max_{true};
};

// `rvc hz --time-source stamps`: the reports fall on period boundaries of the
// messages' own times. step(time) gives the boundaries a message at `time`
// passes (each report is due before that message is counted), at most
// kMaxCatchUp of them: a message further ahead is a jump of the stamps (a
// simulator reset), which gives one report, at the first boundary, and the
// count of the boundaries skipped; the schedule goes on from the first
// boundary after `time`. Boundaries always move forward, even where the
// period is below the stamps' resolution (1e20 s).
class StampSchedule {
 public:
  static constexpr double kMaxCatchUp = 100;
  explicit StampSchedule(double period) : period_(period) {}

  struct Step {
    std::vector<double> reports;  // the boundaries passed, in order (at most kMaxCatchUp)
    double skipped = 0;           // > 0: a jump; the boundaries skipped after reports' one
  };
  // `time` >= every earlier one (callers refuse the others).
  const Step& step(double time);
  bool started() const { return next_ != std::numeric_limits<double>::infinity(); }

 private:
  double period_;
  double next_ = std::numeric_limits<double>::infinity();  // set by the first message
  Step step_;
};

}  // namespace rvc::runtime
