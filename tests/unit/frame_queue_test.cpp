// FrameQueue: the never-blocking hand-off (room() + push_nowait(), the
// DDS receive thread's path) and the wake-up of a sleeping consumer.
// No timing is asserted: a producer that blocked, or a wake-up that was
// lost, would hang the test (ctest's timeout), not make it slower.
#include <gtest/gtest.h>

#include <chrono>
#include <deque>
#include <string>
#include <thread>
#include <vector>

#include "transport/frame_queue.hpp"

namespace {

using rvc::transport::Frame;
using rvc::transport::FrameQueue;
using rvc::transport::OwnedFrame;

// A transport that holds messages until taken (a keep-all reader's history)
// and delivers them as the DDS source does: only what the queue has room for.
struct HeldMessages final : FrameQueue::RoomWaiter {
  FrameQueue& queue;
  std::deque<uint64_t> held;
  std::vector<std::thread::id> on_room_threads;
  explicit HeldMessages(FrameQueue& q) : queue(q) {}

  // What the receive thread does on data: never waits for the queue.
  void deliver() {
    while (!held.empty()) {
      const size_t room = queue.room(this);
      if (room == 0) return;  // full: the rest stays held
      for (size_t i = 0; i < room && !held.empty(); ++i) {
        const std::string payload = "{\"n\":" + std::to_string(held.front()) + "}";
        Frame f;
        f.payload = payload;
        f.seq = held.front();
        queue.push_nowait(f);
        held.pop_front();
      }
    }
  }
  void on_room() override {
    on_room_threads.push_back(std::this_thread::get_id());
    deliver();
  }
};

TEST(FrameQueue, FullQueueLeavesMessagesInTheTransportAndTheConsumerTakesThem) {
  FrameQueue queue(4);
  HeldMessages transport(queue);
  for (uint64_t n = 1; n <= 10; ++n) transport.held.push_back(n);

  transport.deliver();  // returns although the queue cannot take all ten
  EXPECT_EQ(queue.size(), 4u);
  EXPECT_EQ(transport.held.size(), 6u);
  EXPECT_TRUE(transport.on_room_threads.empty());

  std::vector<uint64_t> got;
  std::vector<OwnedFrame> batch;
  size_t count = 0;
  while (got.size() < 10) {
    ASSERT_TRUE(queue.pop_batch(batch, count, 1000));
    ASSERT_GT(count, 0u) << "frames left in the transport were never taken";
    for (size_t i = 0; i < count; ++i) {
      got.push_back(batch[i].seq);
      EXPECT_EQ(batch[i].payload, "{\"n\":" + std::to_string(batch[i].seq) + "}");
    }
  }
  // Each pop that found a producer waiting asked it on the consumer's thread.
  ASSERT_FALSE(transport.on_room_threads.empty());
  for (auto id : transport.on_room_threads) EXPECT_EQ(id, std::this_thread::get_id());
  std::vector<uint64_t> want;
  for (uint64_t n = 1; n <= 10; ++n) want.push_back(n);
  EXPECT_EQ(got, want);  // nothing lost, nothing doubled, in order
  EXPECT_TRUE(transport.held.empty());
}

TEST(FrameQueue, ClosedQueueGrantsNoRoom) {
  FrameQueue queue(4);
  HeldMessages transport(queue);
  transport.held = {1, 2};
  queue.close();
  transport.deliver();  // returns; the messages stay with the transport
  EXPECT_EQ(transport.held.size(), 2u);
  std::vector<OwnedFrame> batch;
  size_t count = 1;
  EXPECT_FALSE(queue.pop_batch(batch, count, 0));
  EXPECT_EQ(count, 0u);
}

// A receive thread delivering while the engine pops concurrently: every
// message arrives once, in order, and the queue never holds more than its
// capacity (one never-blocking producer cannot overshoot it).
TEST(FrameQueue, NeverBlockingProducerAgainstAConsumerLosesNothing) {
  constexpr uint64_t kMessages = 200000;
  constexpr size_t kCapacity = 64;
  FrameQueue queue(kCapacity);
  std::mutex transport_mu;  // the reader's own lock: receive thread vs the engine's on_room
  struct Reader final : FrameQueue::RoomWaiter {
    FrameQueue& queue;
    std::mutex& mu;
    uint64_t next = 1, arrived = 0;
    Reader(FrameQueue& q, std::mutex& m) : queue(q), mu(m) {}
    void take() {
      std::lock_guard lock(mu);
      while (next <= arrived) {
        const size_t room = queue.room(this);
        if (room == 0) return;
        for (size_t i = 0; i < room && next <= arrived; ++i, ++next) {
          Frame f;
          f.seq = next;
          f.eos = next == kMessages;
          queue.push_nowait(f);
        }
      }
    }
    void on_room() override { take(); }
  } reader(queue, transport_mu);

  std::thread receive([&] {
    for (uint64_t n = 1; n <= kMessages; ++n) {
      {
        std::lock_guard lock(transport_mu);
        reader.arrived = n;
      }
      if (n % 7 == 0 || n == kMessages) reader.take();  // data-available, now and then
    }
  });
  uint64_t expect = 1;
  size_t largest = 0;
  bool eos = false;
  std::vector<OwnedFrame> batch;
  size_t count = 0;
  while (!eos) {
    ASSERT_TRUE(queue.pop_batch(batch, count, 100));
    largest = std::max(largest, count);
    for (size_t i = 0; i < count; ++i) {
      ASSERT_EQ(batch[i].seq, expect);
      ++expect;
      eos = batch[i].eos;
    }
  }
  receive.join();
  EXPECT_EQ(expect, kMessages + 1);
  EXPECT_LE(largest, kCapacity);
}

// The consumer sleeps (no deadline soon); a push from another thread wakes
// it, also the second time (one signal per sleep, none lost).
TEST(FrameQueue, PushWakesASleepingConsumerEveryTime) {
  FrameQueue queue(16);
  for (int round = 0; round < 3; ++round) {
    std::thread producer([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));  // let it fall asleep (not asserted)
      Frame f;
      f.seq = static_cast<uint64_t>(round + 1);
      queue.push(f);
    });
    std::vector<OwnedFrame> batch;
    size_t count = 0;
    ASSERT_TRUE(queue.pop_batch_until(batch, count, std::chrono::steady_clock::now() + std::chrono::hours(1)));
    ASSERT_EQ(count, 1u);
    EXPECT_EQ(batch[0].seq, static_cast<uint64_t>(round + 1));
    producer.join();
  }
}

}  // namespace
