// StampMerge (see stamp_merge.hpp): events in stamp order behind a watermark.
#include "sync/stamp_merge.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace rvc::sync {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

bool later(const std::pair<double, uint32_t>& a, const std::pair<double, uint32_t>& b) { return a.first > b.first; }

uint64_t stamp_key(double stamp) { return std::bit_cast<uint64_t>(stamp == 0 ? 0.0 : stamp); }  // -0 == 0
}  // namespace

// ---- stamp -> group hash ----

size_t StampMerge::StampIndex::home(uint64_t key) const {
  key ^= key >> 33;  // stamps differ mostly in their low mantissa bits: mix them up
  key *= 0xff51afd7ed558ccdULL;
  key ^= key >> 33;
  return static_cast<size_t>(key) & (keys_.size() - 1);
}

uint32_t StampMerge::StampIndex::find(uint64_t key) const {
  if (count_ == 0) return kNone;
  for (size_t s = home(key);; s = (s + 1) & (keys_.size() - 1)) {
    if (values_[s] == kNone) return kNone;
    if (keys_[s] == key) return values_[s];
  }
}

void StampMerge::StampIndex::grow() {
  std::vector<uint64_t> keys;
  std::vector<uint32_t> values;
  keys.swap(keys_);
  values.swap(values_);
  size_t capacity = keys.empty() ? 16 : keys.size() * 2;
  keys_.assign(capacity, 0);
  values_.assign(capacity, kNone);
  count_ = 0;
  for (size_t s = 0; s < keys.size(); ++s)
    if (values[s] != kNone) insert(keys[s], values[s]);
}

void StampMerge::StampIndex::insert(uint64_t key, uint32_t value) {
  if ((count_ + 1) * 2 > keys_.size()) grow();  // at most half full: short probes
  size_t s = home(key);
  while (values_[s] != kNone) s = (s + 1) & (keys_.size() - 1);
  keys_[s] = key;
  values_[s] = value;
  ++count_;
}

void StampMerge::StampIndex::erase(uint64_t key) {
  const size_t mask = keys_.size() - 1;
  size_t hole = home(key);
  while (keys_[hole] != key || values_[hole] == kNone) {
    if (values_[hole] == kNone) return;
    hole = (hole + 1) & mask;
  }
  // Shift back the entries of the probe run that would no longer be found.
  for (size_t s = (hole + 1) & mask; values_[s] != kNone; s = (s + 1) & mask) {
    size_t h = home(keys_[s]);
    if (((s - h) & mask) >= ((s - hole) & mask)) {
      keys_[hole] = keys_[s];
      values_[hole] = values_[s];
      hole = s;
    }
  }
  values_[hole] = kNone;
  --count_;
}

void StampMerge::StampIndex::clear() {
  std::fill(values_.begin(), values_.end(), kNone);
  count_ = 0;
}

// ---- the policy ----

StampMerge::StampMerge(const PolicyOptions& options, Handler& handler)
    : handler_(handler),
      n_(static_cast<uint32_t>(options.inputs)),
      max_delay_(options.max_delay),
      adaptive_limit_(options.adaptive_limit),
      process_late_(options.process_late),
      wait_for_inputs_(options.wait_for_inputs),
      max_held_(std::max<size_t>(options.max_held, 1)),
      delay_(options.max_delay),
      newest_(-kInf) {
  if (options.inputs == 0 || options.inputs > std::numeric_limits<uint32_t>::max())
    throw std::invalid_argument("merge: the number of inputs must be positive");
  if (!(max_delay_ >= 0)) throw std::invalid_argument("merge: max_delay must be >= 0");
  if (!(adaptive_limit_ >= 0)) throw std::invalid_argument("merge: adaptive_limit must be >= 0");
  newest_of_.assign(n_, -kInf);
  excluded_.assign(n_, 0);
  members_.reserve(n_);
}

double StampMerge::watermark() const {
  const double delayed = newest_ - delay_;
  if (!wait_for_inputs_) return delayed;
  double slowest = kInf;
  for (uint32_t i = 0; i < n_; ++i)
    if (!excluded_[i]) slowest = std::min(slowest, newest_of_[i]);
  return std::min(slowest, delayed);
}

void StampMerge::exclude(uint32_t input, bool excluded) {
  if (input >= n_) return;
  excluded_[input] = excluded;
  release_below(watermark());
}

void StampMerge::add(const Member& arrived) {
  if (arrived.input >= n_) throw std::out_of_range("merge: input out of range");
  if (!std::isfinite(arrived.stamp)) {
    handler_.on_release(arrived, Release::Late);
    return;
  }
  // Adapt: a message behind the newest stamp shows how late this stream's
  // messages come; wait twice that from now on (up to the limit).
  if (adaptive_limit_ > 0 && arrived.stamp < newest_)
    delay_ = std::max(delay_, std::min(2 * (newest_ - arrived.stamp), std::max(adaptive_limit_, max_delay_)));
  Member message = arrived;
  const bool late = any_set_ && message.stamp <= last_set_;
  if (late) {
    if (!process_late_) {
      handler_.on_release(message, Release::Late);
      return;
    }
    message.stamp = std::nextafter(last_set_, kInf);  // the next event, before everything held
  }
  const double stamp = message.stamp;
  const uint64_t key = stamp_key(stamp);
  uint32_t g = index_.find(key);
  if (g == kNone) {
    if (free_group_ != kNone) {
      g = free_group_;
      free_group_ = groups_[g].first;
    } else {
      g = static_cast<uint32_t>(groups_.size());
      groups_.push_back(Group{});
    }
    groups_[g] = Group{stamp, kNone};
    index_.insert(key, g);
    heap_.emplace_back(stamp, g);
    std::push_heap(heap_.begin(), heap_.end(), later);
  } else if (stamp <= newest_of_[message.input]) {
    // This input may have a message at this stamp already (it repeated a
    // stamp, or came out of order): the newer replaces it.
    for (uint32_t k = groups_[g].first; k != kNone; k = nodes_[k].next) {
      if (nodes_[k].message.input != message.input) continue;
      Member old = nodes_[k].message;
      nodes_[k].message = message;
      handler_.on_release(old, Release::Replaced);
      g = kNone;
      break;
    }
  }
  if (g != kNone) {
    uint32_t k;
    if (free_node_ != kNone) {
      k = free_node_;
      free_node_ = nodes_[k].next;
    } else {
      k = static_cast<uint32_t>(nodes_.size());
      nodes_.push_back(Node{});
    }
    nodes_[k] = Node{message, groups_[g].first};
    groups_[g].first = k;
    ++held_;
  }
  if (stamp > newest_of_[message.input]) newest_of_[message.input] = stamp;
  if (stamp > newest_) newest_ = stamp;
  // A late message goes out at once: its group is the earliest held (every
  // other stamp held is above the last set's), and a second late message of
  // its input must not find it still held and replace it.
  if (late) release_top();
  else release_below(watermark());
  while (held_ > max_held_) release_top();  // memory bound: the earliest goes, later ones of it may be late
}

void StampMerge::advance(double stamp) {
  if (stamp > newest_) newest_ = stamp;  // NaN compares false: ignored
  // Stamps that follow a clock: no input can still deliver an earlier one.
  for (double& n : newest_of_)
    if (stamp > n) n = stamp;
  release_below(watermark());
}

void StampMerge::release_below(double watermark) {
  while (!heap_.empty() && heap_.front().first < watermark) release_top();
}

void StampMerge::release_top() {
  std::pop_heap(heap_.begin(), heap_.end(), later);
  const auto [stamp, g] = heap_.back();
  heap_.pop_back();
  index_.erase(stamp_key(stamp));
  members_.clear();
  for (uint32_t k = groups_[g].first; k != kNone;) {
    members_.push_back(nodes_[k].message);
    uint32_t next = nodes_[k].next;
    nodes_[k].next = free_node_;
    free_node_ = k;
    k = next;
  }
  groups_[g].first = free_group_;
  free_group_ = g;
  held_ -= members_.size();
  std::sort(members_.begin(), members_.end(), [](const Member& a, const Member& b) { return a.input < b.input; });
  any_set_ = true;
  last_set_ = stamp;
  handler_.on_set(members_.data(), members_.size(), stamp);
  for (const Member& m : members_) handler_.on_release(m, Release::Used);
}

void StampMerge::finish() {
  while (!heap_.empty()) release_top();
  index_.clear();
  newest_of_.assign(n_, -kInf);
  newest_ = -kInf;
  delay_ = max_delay_;
  excluded_.assign(n_, 0);
  any_set_ = false;
}

}  // namespace rvc::sync
