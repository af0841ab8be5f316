// ExactTime: a set is one message of every input, all with the same stamp
// (message_filters' ExactTime, for any N).
//
// Pending stamps are kept sorted in a small vector (at most queue_size + 1 of
// them, and new stamps nearly always land at the end); each pending stamp
// owns one block of N slots from a pool, so no allocation happens once the
// pool has queue_size + 1 blocks. When a set goes out, older pending stamps
// can no longer complete (stamps go out in increasing order) and are released
// Unmatched; a message at or before the last set's stamp is Late (message_filters
// would keep it until the next set cleared it).
#pragma once

#include <cstdint>
#include <vector>

#include "sync/policy.hpp"

namespace rvc::sync {

class ExactTime final : public Policy {
 public:
  // Throws std::invalid_argument on inputs == 0 or queue_size == 0.
  ExactTime(const PolicyOptions& options, Handler& handler);

  void add(const Member& message) override;
  void finish() override;
  size_t held() const override { return held_; }

 private:
  struct Pending {
    double stamp;
    uint32_t block;  // slots block * n_ .. block * n_ + n_ - 1
    uint32_t count;  // inputs present
  };
  struct Slot {
    uint64_t token;
    bool present;
  };
  // Releases the messages of pending_[0 .. end) with `why`, oldest stamp first.
  void drop_front(size_t end, Release why);
  void free_block(uint32_t block, double stamp, Release why);

  Handler& handler_;
  const uint32_t n_;
  const size_t queue_size_;
  std::vector<Pending> pending_;  // sorted by stamp, distinct stamps
  std::vector<Slot> slots_;       // the blocks, n_ slots each
  std::vector<uint32_t> free_blocks_;
  bool any_set_ = false;
  double last_set_ = 0;  // stamp of the last set out (valid when any_set_)
  size_t held_ = 0;
  std::vector<Member> members_;  // scratch for one set or one release batch
};

}  // namespace rvc::sync
