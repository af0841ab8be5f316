// StampMerge ("merge"): every message is an event at its own stamp. Messages
// are released in stamp order behind a watermark, newest stamp seen (or
// advanced to) minus max_delay: a stamp strictly below it goes out, so the
// messages of different inputs at one stamp leave together as one set (at
// most one per input; a second message of an input at a stamp replaces the
// first, Replaced). A message at or before the last set's stamp is Late: it
// would break the order of the events (options.process_late: it becomes a set
// of its own, just after that one). The delay may adapt to the lateness seen
// (PolicyOptions::adaptive_limit).
//
// Pending stamps are groups in a binary heap keyed by stamp (O(log n) per
// message) and in an open-addressing hash from stamp to group, which finds
// the group of an equal stamp in O(1). Groups and their member nodes come from
// free lists, so steady state does not allocate.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "sync/policy.hpp"

namespace rvc::sync {

class StampMerge final : public Policy {
 public:
  // Throws std::invalid_argument on inputs == 0 or a negative (or NaN) max_delay or adaptive_limit.
  StampMerge(const PolicyOptions& options, Handler& handler);

  void add(const Member& message) override;
  void advance(double stamp) override;
  void exclude(uint32_t input, bool excluded) override;
  void finish() override;
  size_t held() const override { return held_; }
  double delay() const { return delay_; }  // the watermark's delay now (adapted)

 private:
  static constexpr uint32_t kNone = UINT32_MAX;
  struct Node {
    Member message;
    uint32_t next;  // next member of the same group, or the free list
  };
  struct Group {
    double stamp;
    uint32_t first;  // member list (kNone: empty); next free group when free
  };
  // Stamp bits -> group, linear probing with backward-shift deletion.
  class StampIndex {
   public:
    uint32_t find(uint64_t key) const;
    void insert(uint64_t key, uint32_t value);
    void erase(uint64_t key);
    void clear();

   private:
    size_t home(uint64_t key) const;
    void grow();
    std::vector<uint64_t> keys_;
    std::vector<uint32_t> values_;  // kNone: empty slot
    size_t count_ = 0;
  };

  void release_below(double watermark);
  double watermark() const;  // stamps below it go out
  void release_top();

  Handler& handler_;
  const uint32_t n_;
  const double max_delay_;
  const double adaptive_limit_;
  const bool process_late_;
  const bool wait_for_inputs_;
  const size_t max_held_;
  std::vector<uint8_t> excluded_;  // wait_for_inputs: inputs not waited for
  double delay_;  // max_delay_, grown by adaptation
  std::vector<Node> nodes_;
  uint32_t free_node_ = kNone;
  std::vector<Group> groups_;
  uint32_t free_group_ = kNone;
  std::vector<std::pair<double, uint32_t>> heap_;  // (stamp, group), earliest on top
  StampIndex index_;
  std::vector<double> newest_of_;  // per input, the newest stamp added (no equal stamp pending above it)
  double newest_;                  // the watermark is newest_ - max_delay
  bool any_set_ = false;
  double last_set_ = 0;
  size_t held_ = 0;
  std::vector<Member> members_;
};

}  // namespace rvc::sync
