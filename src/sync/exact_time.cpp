// ExactTime (see exact_time.hpp): sets of equal stamps, pending stamps bounded
// by queue_size as in message_filters (the oldest pending stamp goes first).
#include "sync/exact_time.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rvc::sync {

ExactTime::ExactTime(const PolicyOptions& options, Handler& handler)
    : handler_(handler), n_(static_cast<uint32_t>(options.inputs)), queue_size_(options.queue_size) {
  if (options.inputs == 0 || options.inputs > std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("exact: the number of inputs must be positive");
  if (queue_size_ == 0) throw std::invalid_argument("exact: queue_size must be at least 1");
  members_.reserve(n_);
}

void ExactTime::free_block(uint32_t block, double stamp, Release why) {
  Slot* slots = &slots_[size_t{block} * n_];
  members_.clear();
  for (uint32_t i = 0; i < n_; ++i) {
    if (!slots[i].present) continue;
    members_.push_back(Member{i, stamp, slots[i].token});
    slots[i].present = false;
  }
  free_blocks_.push_back(block);
  held_ -= members_.size();
  for (const Member& m : members_) handler_.on_release(m, why);
}

void ExactTime::drop_front(size_t end, Release why) {
  for (size_t k = 0; k < end; ++k) free_block(pending_[k].block, pending_[k].stamp, why);
  pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(end));
}

void ExactTime::add(const Member& message) {
  if (message.input >= n_) throw std::out_of_range("exact: input out of range");
  const double stamp = message.stamp;
  // A set at or after this stamp went out: older stamps cannot complete any more.
  if (!std::isfinite(stamp) || (any_set_ && stamp <= last_set_)) {
    handler_.on_release(message, Release::Late);
    return;
  }
  // New stamps nearly always sort last: test the end before searching.
  size_t k;
  if (pending_.empty() || pending_.back().stamp < stamp) {
    k = pending_.size();
  } else {
    auto it = std::lower_bound(pending_.begin(), pending_.end(), stamp,
                               [](const Pending& p, double s) { return p.stamp < s; });
    k = static_cast<size_t>(it - pending_.begin());
  }
  if (k == pending_.size() || pending_[k].stamp != stamp) {
    uint32_t block;
    if (!free_blocks_.empty()) {
      block = free_blocks_.back();
      free_blocks_.pop_back();
    } else {
      block = static_cast<uint32_t>(slots_.size() / n_);
      slots_.resize(slots_.size() + n_, Slot{0, false});
    }
    pending_.insert(pending_.begin() + static_cast<std::ptrdiff_t>(k), Pending{stamp, block, 0});
  }
  Pending& p = pending_[k];
  Slot& slot = slots_[size_t{p.block} * n_ + message.input];
  if (slot.present) {  // same input, same stamp: the newer one takes the place
    uint64_t old = slot.token;
    slot.token = message.token;
    handler_.on_release(Member{message.input, stamp, old}, Release::Replaced);
    return;
  }
  slot = Slot{message.token, true};
  ++held_;
  if (++p.count == n_) {
    // The set: its members, then everything older (it can never complete now).
    Slot* slots = &slots_[size_t{p.block} * n_];
    members_.clear();
    for (uint32_t i = 0; i < n_; ++i) {
      members_.push_back(Member{i, stamp, slots[i].token});
      slots[i].present = false;
    }
    free_blocks_.push_back(p.block);
    held_ -= n_;
    pending_.erase(pending_.begin() + static_cast<std::ptrdiff_t>(k));
    any_set_ = true;
    last_set_ = stamp;
    handler_.on_set(members_.data(), members_.size(), stamp);
    for (const Member& m : members_) handler_.on_release(m, Release::Used);
    drop_front(k, Release::Unmatched);
    return;
  }
  if (pending_.size() > queue_size_) drop_front(pending_.size() - queue_size_, Release::Overflow);
}

void ExactTime::finish() {
  drop_front(pending_.size(), Release::Unfinished);
  any_set_ = false;
}

}  // namespace rvc::sync
