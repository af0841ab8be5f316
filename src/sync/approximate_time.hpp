// message_filters' ApproximateTime policy for any number of inputs.
//
// The algorithm is the one of ROS message_filters (wiki page
// message_filters/ApproximateTime): each input keeps a queue; when every
// queue has a message, the latest head fixes the pivot, and the policy walks
// the candidate sets (the queue heads) by moving the earliest head aside
// ("past") until it can prove that no later candidate holding a message
// contiguous to the previous set is smaller; then it publishes the best one.
// Ties between equal stamps are broken as message_filters breaks them (the
// earliest head: the lowest input; the latest head: the highest input), so the
// same inputs give the same sets.
//
// Differences from message_filters: any N (no limit of 9); a message stamped
// earlier than its input's previous message (or not a finite number) is
// released as Late at once (message_filters only warns, and its sets may then
// cross); every message leaves through Handler::on_release with the reason.
//
// Data layout: per input one ring buffer holds the "past" messages followed by
// the queue proper, so moving the queue's head to the past, and recovering
// the past into the queue, is a counter change. The earliest and latest heads
// come from a segment tree over the inputs' head stamps (O(log N) per change),
// which also holds the virtual stamps of empty queues during the search that
// uses the inter-message lower bounds. No allocation once the rings have grown
// to the queue size.
#pragma once

#include <cstdint>
#include <vector>

#include "sync/policy.hpp"

namespace rvc::sync {

class ApproximateTime final : public Policy {
 public:
  // Throws std::invalid_argument on inputs == 0, queue_size == 0, a negative
  // age penalty, max interval or lower bound, or a lower-bound list whose
  // size is neither 0 nor `inputs`.
  ApproximateTime(const PolicyOptions& options, Handler& handler);

  void add(const Member& message) override;
  void finish() override;
  size_t held() const override { return held_; }

 private:
  struct Slot {
    double stamp;
    uint64_t token;
  };
  // The messages of one input in arrival order: [0, past) are "past" (moved
  // aside during the candidate search), [past, size) the queue proper.
  struct Ring {
    std::vector<Slot> buf;
    size_t head = 0, size = 0, past = 0;
    size_t queued() const { return size - past; }
    const Slot& at(size_t i) const { return buf[(head + i) & (buf.size() - 1)]; }
    void push_back(const Slot& s);
    Slot pop_front();
  };

  void process();
  void virtual_search();
  void publish();
  void make_candidate();
  void move_to_past(uint32_t input);
  void delete_front(uint32_t input, Release why);
  void recover_all();
  void release(uint32_t input, const Slot& slot, Release why);

  // The stamp that stands for input i: its queue head, or, while a candidate
  // exists and the queue is empty, the earliest stamp its next message can
  // have (message_filters' "virtual time").
  double key_of(uint32_t input) const;
  void update_key(uint32_t input);
  void rebuild_keys();
  bool better(uint32_t a, uint32_t b, bool latest) const;

  Handler& handler_;
  const uint32_t n_;
  const size_t queue_size_;
  const double max_interval_;
  const double age_factor_;  // 1 + age penalty
  std::vector<double> lower_bound_;

  std::vector<Ring> rings_;
  std::vector<double> last_stamp_;  // per input, the newest accepted stamp (Late test)
  uint32_t non_empty_ = 0;          // inputs whose queue proper is non-empty
  size_t held_ = 0;

  // The candidate: its member of input i is rings_[i].at(0) (makeCandidate
  // drops the past, so the candidate's messages head the rings until publish).
  bool has_pivot_ = false;
  uint32_t pivot_ = 0;
  double pivot_time_ = 0, cand_start_ = 0, cand_end_ = 0;

  std::vector<char> dropped_;            // message_filters' has_dropped_messages
  std::vector<uint32_t> dropped_list_;   // the inputs whose flag is set (clearing is not O(N))
  std::vector<uint32_t> with_past_;      // every input with past > 0 (making a candidate is not O(N))
  std::vector<char> in_with_past_;       // listed in with_past_
  std::vector<uint32_t> virtual_moves_;  // undo log of the virtual search

  // Segment tree over the inputs' keys: node k (1 <= k < n) holds the input of
  // the earliest key below it (ties: lowest input) and of the latest (ties:
  // highest input); leaves are n..2n-1. Both orders are total, so the root
  // covers all inputs for any n.
  std::vector<double> keys_;
  std::vector<uint32_t> min_node_, max_node_;

  std::vector<Member> members_;  // publish() scratch
};

}  // namespace rvc::sync
