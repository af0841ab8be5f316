// How messages reach the `rvc hz` loop from transport threads: each with
// the time it arrived, read on the transport thread (a batch that waited in
// the queue must not look like a burst), through a bounded queue the loop
// waits on until its next deadline.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "transport/frame.hpp"

namespace rvc::cli {

using SteadyClock = std::chrono::steady_clock;

inline double wall_seconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// One message as it arrived, with both clocks read on the transport thread:
// a batch waiting in the queue must not look like a burst.
struct Arrival {
  uint32_t input = 0;
  bool eos = false;
  SteadyClock::time_point steady;
  double wall = 0;
  std::string payload;
  std::optional<double> time;  // its --time-field, when the file merge has read it already
};

// Transport threads -> the hz loop. Bounded: a full queue blocks the
// producer (backpressure, as transport::FrameQueue), nothing is dropped.
class ArrivalQueue {
 public:
  explicit ArrivalQueue(size_t capacity) : capacity_(capacity) {}
  void push(uint32_t input, const transport::Frame& f) {
    Arrival a{input, f.eos, SteadyClock::now(), wall_seconds(), std::string(f.payload), std::nullopt};
    std::unique_lock<std::mutex> lock(mutex_);
    not_full_.wait(lock, [&] { return items_.size() < capacity_ || closed_; });
    if (closed_) return;
    items_.push_back(std::move(a));
    if (items_.size() == 1) not_empty_.notify_one();
  }
  // Waits until something arrived or `until`, then takes everything queued.
  void pop_until(SteadyClock::time_point until, std::vector<Arrival>& out) {
    out.clear();
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait_until(lock, until, [&] { return !items_.empty() || closed_; });
    out.swap(items_);
    not_full_.notify_all();
  }
  void close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    not_full_.notify_all();
    not_empty_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable not_full_, not_empty_;
  std::vector<Arrival> items_;
  size_t capacity_;
  bool closed_ = false;
};

}  // namespace rvc::cli
