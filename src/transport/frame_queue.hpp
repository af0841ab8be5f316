// Hands frames from transport threads to the engine thread.
//
// Producers copy each payload into a slot of the `incoming` batch (slots and
// their string capacity are reused, so steady state allocates nothing) and
// block while the batch is full: backpressure reaches the middleware, which
// with reliable QoS slows the publisher down; nothing is dropped. The
// consumer swaps the whole batch out under one lock, so the lock is taken
// once per batch, not once per message, when the engine falls behind.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "transport/frame.hpp"

namespace rvc::transport {

struct OwnedFrame {
  std::string payload;
  uint64_t seq = 0;
  bool eos = false;
  uint64_t publisher = 0;
  uint32_t input = 0;
  std::string key;
};

class FrameQueue {
 public:
  explicit FrameQueue(size_t capacity = 1 << 14) : capacity_(capacity) {}

  // Producer side (any thread). Blocks while the queue is full.
  void push(const Frame& frame) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_full_.wait(lock, [&] { return incoming_count_ < capacity_ || closed_; });
    if (closed_) return;
    if (incoming_count_ == incoming_.size()) incoming_.emplace_back();
    OwnedFrame& slot = incoming_[incoming_count_++];
    slot.payload.assign(frame.payload.data(), frame.payload.size());
    slot.seq = frame.seq;
    slot.eos = frame.eos;
    slot.publisher = frame.publisher;
    slot.input = frame.input;
    slot.key.assign(frame.key.data(), frame.key.size());
    if (incoming_count_ == 1) not_empty_.notify_one();
  }

  // Consumer side (one thread). Waits up to `timeout_ms` for frames, then
  // swaps every queued frame into `batch` (whose first `count` slots are
  // valid). Returns false once closed and drained.
  bool pop_batch(std::vector<OwnedFrame>& batch, size_t& count, int timeout_ms) {
    return pop_batch_until(batch, count, std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms));
  }
  // The same, waiting until a steady-clock instant (a tick's deadline): the
  // wait ends there to within the kernel's timer slack (tens of
  // microseconds), not at a polling period's next multiple.
  bool pop_batch_until(std::vector<OwnedFrame>& batch, size_t& count, std::chrono::steady_clock::time_point until) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait_until(lock, until, [&] { return incoming_count_ > 0 || closed_; });
    count = incoming_count_;
    if (count == 0) return !closed_;
    incoming_.swap(batch);
    if (incoming_.size() < batch.size()) incoming_.resize(batch.size());
    incoming_count_ = 0;
    not_full_.notify_all();
    return true;
  }

  // Wakes everyone; later pushes are dropped (used only when shutting down).
  void close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    not_full_.notify_all();
    not_empty_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable not_full_, not_empty_;
  std::vector<OwnedFrame> incoming_;
  size_t incoming_count_ = 0;
  size_t capacity_;
  bool closed_ = false;
};

}  // namespace rvc::transport
