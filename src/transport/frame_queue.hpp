// Hands frames from transport threads to the engine thread.
//
// Producers copy each payload into a slot of the `incoming` batch (slots and
// their string capacity are reused, so steady state allocates nothing). The
// consumer swaps the whole batch out under one lock, so the lock is taken
// once per batch, not once per message, when the engine falls behind.
//
// Two ways to produce, neither drops a frame:
// - push(): blocks while the queue is full. Backpressure reaches the
//   middleware, which with reliable QoS slows the publisher down. Only for
//   threads that may block (Zenoh's callback, a source's own thread).
// - request() / room() + push_nowait(): for a transport thread that must
//   never block (CycloneDDS's receive thread, which also carries the
//   acknowledgements a verdict writer of the same process waits for). Its
//   listener only calls request(); the consumer then calls the producer's
//   on_room() on its own thread, which takes from the transport only as many
//   messages as room() grants and leaves the rest there (a keep-all
//   reader's history); room() == 0 registers it for another on_room() after
//   the next pop. Several such producers can overshoot the capacity by what
//   room() granted each at once; never by more.
//
// Wake-ups: a producer signals the consumer only while it sleeps in
// pop_batch_until, once per sleep. Before sleeping, the consumer polls for a
// short while (kSpin), so a steady stream is handed over without a futex
// wake and a context switch per message (Zenoh delivers each sample on its
// receive thread: that wake-up was a fifth of the monitor's CPU there).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
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
  // A producer that leaves frames in its transport while the queue is full.
  class RoomWaiter {
   public:
    // Called on the consumer's thread once the queue has room again (after a
    // pop): take what was left behind (room() and push_nowait() again).
    virtual void on_room() = 0;

   protected:
    ~RoomWaiter() = default;
  };

  // How long the consumer polls for frames before it sleeps.
  static constexpr std::chrono::microseconds kSpin{30};

  explicit FrameQueue(size_t capacity = 1 << 14, std::chrono::microseconds spin = kSpin)
      : capacity_(std::max<size_t>(capacity, 1)), spin_(spin) {}

  // Producer side (any thread that may block). Blocks while the queue is full.
  void push(const Frame& frame) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_full_.wait(lock, [&] { return incoming_count_ < capacity_ || closed_; });
    if (closed_) return;
    append(frame, lock);
  }

  // Producer side, never blocking: how many frames may be pushed now. 0 (full
  // or closed) registers `waiter` for one on_room() call after the next pop.
  size_t room(RoomWaiter* waiter) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (closed_) return 0;
    if (incoming_count_ < capacity_) return capacity_ - incoming_count_;
    if (waiter && std::find(waiters_.begin(), waiters_.end(), waiter) == waiters_.end()) waiters_.push_back(waiter);
    return 0;
  }
  // Producer side, never blocking: `waiter` has frames to give (a DDS
  // listener on the receive thread, which does no more than this): its
  // on_room() is called on the consumer's thread at the next pop, waking the
  // consumer if it sleeps. The consumer then takes them (the copy and the
  // transport's take run there, not on the transport's thread).
  void request(RoomWaiter* waiter) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (closed_) return;
    if (std::find(waiters_.begin(), waiters_.end(), waiter) == waiters_.end()) waiters_.push_back(waiter);
    pending_.fetch_add(1, std::memory_order_relaxed);
    wake(lock);
  }
  // Appends without waiting (what room() granted). Dropped only once closed.
  void push_nowait(const Frame& frame) {
    std::unique_lock<std::mutex> lock(mutex_);
    if (closed_) return;
    append(frame, lock);
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
    if (pending_.load(std::memory_order_relaxed) == 0) poll(until);
    std::unique_lock<std::mutex> lock(mutex_);
    call_waiters(lock);  // those that asked to give frames: they fill the queue now
    if (incoming_count_ == 0 && !closed_) {
      sleeping_ = true;
      signalled_ = false;
      not_empty_.wait_until(lock, until, [&] {
        if (incoming_count_ > 0 || closed_ || !waiters_.empty()) return true;
        signalled_ = false;  // a spurious wake-up: the next push signals again
        return false;
      });
      sleeping_ = false;
      call_waiters(lock);
    }
    count = incoming_count_;
    if (count == 0) return !closed_;
    incoming_.swap(batch);
    if (incoming_.size() < batch.size()) incoming_.resize(batch.size());
    incoming_count_ = 0;
    pending_.store(0, std::memory_order_relaxed);
    not_full_.notify_all();
    // Producers that left frames behind take them now (on this thread: the
    // queue has room for a whole batch of theirs); they are the next batch.
    call_waiters(lock);
    return true;
  }

  // Wakes everyone; later pushes are dropped (used only when shutting down).
  void close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    not_full_.notify_all();
    not_empty_.notify_all();
  }

  // Frames queued now (tests).
  size_t size() {
    std::lock_guard<std::mutex> lock(mutex_);
    return incoming_count_;
  }

 private:
  void append(const Frame& frame, std::unique_lock<std::mutex>& lock) {
    if (incoming_count_ == incoming_.size()) incoming_.emplace_back();
    OwnedFrame& slot = incoming_[incoming_count_++];
    slot.payload.assign(frame.payload.data(), frame.payload.size());
    slot.seq = frame.seq;
    slot.eos = frame.eos;
    slot.publisher = frame.publisher;
    slot.input = frame.input;
    slot.key.assign(frame.key.data(), frame.key.size());
    pending_.fetch_add(1, std::memory_order_relaxed);
    wake(lock);
  }

  // Only a sleeping consumer needs the (system call) wake-up, once per sleep.
  void wake(std::unique_lock<std::mutex>& lock) {
    if (sleeping_ && !signalled_) {
      signalled_ = true;
      lock.unlock();
      not_empty_.notify_one();
    }
  }

  // Calls (without the lock) the producers waiting to give frames.
  void call_waiters(std::unique_lock<std::mutex>& lock) {
    if (waiters_.empty()) return;
    asking_.swap(waiters_);
    lock.unlock();
    for (RoomWaiter* w : asking_) w->on_room();
    asking_.clear();
    lock.lock();
  }

  // Before sleeping: poll for up to spin_ (never past `until`), yielding
  // the core to the producer when both share one.
  void poll(std::chrono::steady_clock::time_point until) {
    if (spin_.count() <= 0) return;
    const auto end = std::min(until, std::chrono::steady_clock::now() + spin_);
    for (unsigned i = 0; pending_.load(std::memory_order_relaxed) == 0; ++i) {
      if ((i & 15) == 15) {
        if (std::chrono::steady_clock::now() >= end) return;
        std::this_thread::yield();
      }
    }
  }

  std::mutex mutex_;
  std::condition_variable not_full_, not_empty_;
  std::vector<OwnedFrame> incoming_;
  size_t incoming_count_ = 0;
  std::atomic<size_t> pending_{0};  // frames and requests since the last pop, read while polling
  size_t capacity_;
  std::chrono::microseconds spin_;
  bool closed_ = false;
  bool sleeping_ = false, signalled_ = false;
  std::vector<RoomWaiter*> waiters_, asking_;
};

// A source that can deliver straight into the queue without ever blocking
// its transport thread (DdsSource: room() + push_nowait()). The monitor loop
// starts such a source with start_into() instead of Source::start().
class QueueFeeder {
 public:
  // Starts delivery into `queue`, each frame tagged as `input`.
  virtual void start_into(FrameQueue& queue, uint32_t input) = 0;

 protected:
  ~QueueFeeder() = default;
};

}  // namespace rvc::transport
