// A monitor group's member set as liveliness tokens report it: written by a
// Zenoh thread (a token appears or goes), read by the engine thread, which
// only takes a snapshot when the generation moved (one atomic load per
// message otherwise).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace rvc::runtime::fleet {

class GroupMembers {
 public:
  // `self` is always a member: a replica owns shards before its own token
  // comes back to it.
  explicit GroupMembers(std::string self) : self_(std::move(self)) {
    members_.insert(self_);
  }

  // A token of the group appeared (alive) or went; `member` is its last chunk.
  void update(std::string_view member, bool alive) {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string m(member);
    if (m == self_) return;
    if (!alive && retired_.count(m)) return;  // ended at end of stream: still its shards' owner
    const bool changed = alive ? members_.insert(m).second : members_.erase(m) > 0;
    if (!changed) return;
    changed_at_ = std::chrono::steady_clock::now();
    generation_.fetch_add(1, std::memory_order_release);
  }

  // A member that ended at the end of the stream (its "bye", sent before its
  // token goes): it checked everything of its shards, so they keep it as their
  // owner and nobody takes them over when its token goes.
  void retire(std::string_view member) {
    std::lock_guard<std::mutex> lock(mutex_);
    const std::string m(member);
    if (m == self_ || !retired_.insert(m).second) return;
    if (members_.insert(m).second) {
      changed_at_ = std::chrono::steady_clock::now();
      generation_.fetch_add(1, std::memory_order_release);
    }
  }

  uint64_t generation() const { return generation_.load(std::memory_order_acquire); }
  // The members, sorted, and when the set last changed (as the token events reached this replica).
  std::vector<std::string> snapshot(std::chrono::steady_clock::time_point* changed_at = nullptr) const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (changed_at) *changed_at = changed_at_;
    return {members_.begin(), members_.end()};
  }
  const std::string& self() const { return self_; }

 private:
  const std::string self_;
  mutable std::mutex mutex_;
  std::set<std::string> members_, retired_;
  std::chrono::steady_clock::time_point changed_at_ = std::chrono::steady_clock::now();
  std::atomic<uint64_t> generation_{0};
};

}  // namespace rvc::runtime::fleet
