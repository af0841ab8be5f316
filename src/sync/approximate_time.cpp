// ApproximateTime: message_filters' algorithm (see approximate_time.hpp). The
// steps follow message_filters' process() one for one, so its published test
// vectors give the same sets here; the comments say why each step is sound.
#include "sync/approximate_time.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace rvc::sync {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

void ApproximateTime::Ring::push_back(const Slot& s) {
  if (size == buf.size()) {  // grow to the next power of two, unrolling the ring
    std::vector<Slot> bigger(buf.empty() ? 4 : buf.size() * 2);
    for (size_t i = 0; i < size; ++i) bigger[i] = at(i);
    buf.swap(bigger);
    head = 0;
  }
  buf[(head + size) & (buf.size() - 1)] = s;
  ++size;
}

ApproximateTime::Slot ApproximateTime::Ring::pop_front() {
  Slot s = buf[head];
  head = (head + 1) & (buf.size() - 1);
  --size;
  return s;
}

ApproximateTime::ApproximateTime(const PolicyOptions& options, Handler& handler)
    : handler_(handler),
      n_(static_cast<uint32_t>(options.inputs)),
      queue_size_(options.queue_size),
      max_interval_(options.max_interval),
      age_factor_(1 + options.age_penalty) {
  if (options.inputs == 0 || options.inputs > std::numeric_limits<uint32_t>::max() / 2)
    throw std::invalid_argument("approximate: the number of inputs must be positive");
  if (queue_size_ == 0) throw std::invalid_argument("approximate: queue_size must be at least 1");
  if (!(options.age_penalty >= 0)) throw std::invalid_argument("approximate: the age penalty must be >= 0");
  if (!(max_interval_ >= 0)) throw std::invalid_argument("approximate: max_interval must be >= 0");
  if (!options.inter_message_lower_bound.empty() && options.inter_message_lower_bound.size() != n_)
    throw std::invalid_argument("approximate: one inter-message lower bound per input, or none");
  lower_bound_.assign(n_, 0.0);
  for (size_t i = 0; i < options.inter_message_lower_bound.size(); ++i) {
    double b = options.inter_message_lower_bound[i];
    if (!(b >= 0) || std::isinf(b)) throw std::invalid_argument("approximate: a lower bound must be finite and >= 0");
    lower_bound_[i] = b;
  }
  rings_.resize(n_);
  last_stamp_.assign(n_, -kInf);
  dropped_.assign(n_, 0);
  in_with_past_.assign(n_, 0);
  keys_.assign(n_, kInf);
  min_node_.assign(2 * size_t{n_}, 0);
  max_node_.assign(2 * size_t{n_}, 0);
  for (uint32_t i = 0; i < n_; ++i) min_node_[n_ + i] = max_node_[n_ + i] = i;
  rebuild_keys();
  members_.reserve(n_);
  with_past_.reserve(n_);
}

// ---- segment tree over the keys ----

bool ApproximateTime::better(uint32_t a, uint32_t b, bool latest) const {
  if (keys_[a] != keys_[b]) return latest ? keys_[a] > keys_[b] : keys_[a] < keys_[b];
  // message_filters scans the inputs in order and replaces its earliest head
  // only on a strictly earlier one, its latest head on an equal or later one.
  return latest ? a > b : a < b;
}

double ApproximateTime::key_of(uint32_t input) const {
  const Ring& r = rings_[input];
  if (r.queued() > 0) return r.at(r.past).stamp;
  if (!has_pivot_ || r.size == 0) return kInf;  // not read: no candidate search runs with an empty queue
  // The next message cannot come before the last one plus the lower bound,
  // and any set better than the candidate holds a message at or after the pivot.
  double bound = r.at(r.size - 1).stamp + lower_bound_[input];
  return bound > pivot_time_ ? bound : pivot_time_;
}

void ApproximateTime::update_key(uint32_t input) {
  keys_[input] = key_of(input);
  for (size_t k = (size_t{input} + n_) >> 1; k >= 1; k >>= 1) {
    uint32_t a = min_node_[2 * k], b = min_node_[2 * k + 1];
    min_node_[k] = better(b, a, false) ? b : a;
    a = max_node_[2 * k];
    b = max_node_[2 * k + 1];
    max_node_[k] = better(b, a, true) ? b : a;
  }
}

void ApproximateTime::rebuild_keys() {
  for (uint32_t i = 0; i < n_; ++i) keys_[i] = key_of(i);
  for (size_t k = n_ - 1; k >= 1; --k) {
    uint32_t a = min_node_[2 * k], b = min_node_[2 * k + 1];
    min_node_[k] = better(b, a, false) ? b : a;
    a = max_node_[2 * k];
    b = max_node_[2 * k + 1];
    max_node_[k] = better(b, a, true) ? b : a;
  }
}

// ---- queue moves ----

void ApproximateTime::release(uint32_t input, const Slot& slot, Release why) {
  handler_.on_release(Member{input, slot.stamp, slot.token}, why);
}

void ApproximateTime::move_to_past(uint32_t input) {
  Ring& r = rings_[input];
  ++r.past;
  if (!in_with_past_[input]) {
    in_with_past_[input] = 1;
    with_past_.push_back(input);
  }
  if (r.queued() == 0) --non_empty_;
  update_key(input);
}

void ApproximateTime::delete_front(uint32_t input, Release why) {
  Ring& r = rings_[input];  // no candidate, so no past: the front is the queue's head
  Slot s = r.pop_front();
  --held_;
  if (r.queued() == 0) --non_empty_;
  update_key(input);
  release(input, s, why);
}

void ApproximateTime::make_candidate() {
  // The past messages lie before the new candidate's member of their input:
  // sets do not cross, so no later set can use them.
  for (uint32_t i : with_past_) {
    Ring& r = rings_[i];
    while (r.past > 0) {
      Slot s = r.pop_front();
      --r.past;
      --held_;
      release(i, s, Release::Unmatched);
    }
    in_with_past_[i] = 0;
  }
  with_past_.clear();
}

// Puts every past message back at the front of its queue and drops the
// candidate. Only inputs with a past change (an input whose queue is empty
// while a candidate exists holds the candidate's member in its past), so this
// is not O(N): an input that keeps overflowing stays cheap.
void ApproximateTime::recover_all() {
  has_pivot_ = false;
  for (uint32_t i : with_past_) {
    Ring& r = rings_[i];
    if (r.past > 0 && r.queued() == 0) ++non_empty_;
    r.past = 0;
    in_with_past_[i] = 0;
    update_key(i);
  }
  with_past_.clear();
}

void ApproximateTime::publish() {
  members_.clear();
  for (uint32_t i = 0; i < n_; ++i) {
    Ring& r = rings_[i];
    r.past = 0;
    Slot s = r.pop_front();
    members_.push_back(Member{i, s.stamp, s.token});
  }
  for (uint32_t i : with_past_) in_with_past_[i] = 0;
  with_past_.clear();
  held_ -= n_;
  has_pivot_ = false;
  non_empty_ = 0;
  for (const Ring& r : rings_) non_empty_ += r.queued() > 0;
  rebuild_keys();
  handler_.on_set(members_.data(), members_.size(), cand_end_);
  for (const Member& m : members_) handler_.on_release(m, Release::Used);
}

// ---- the algorithm ----

void ApproximateTime::add(const Member& message) {
  if (message.input >= n_) throw std::out_of_range("approximate: input out of range");
  const uint32_t i = message.input;
  // The algorithm assumes each input in stamp order; an older message would
  // make sets cross. A stamp that is no number cannot be placed at all.
  if (!std::isfinite(message.stamp) || message.stamp < last_stamp_[i]) {
    handler_.on_release(message, Release::Late);
    return;
  }
  last_stamp_[i] = message.stamp;
  Ring& r = rings_[i];
  r.push_back(Slot{message.stamp, message.token});
  ++held_;
  if (r.queued() == 1) {  // the queue was empty: it may complete the heads
    ++non_empty_;
    update_key(i);
    if (non_empty_ == n_) process();
  }
  // process() may leave queue_size + 1 messages in this input; past ones count.
  if (r.size > queue_size_) {
    const bool had_candidate = has_pivot_;
    recover_all();  // the candidate search is void: start over with the oldest of this input gone
    Slot s = r.pop_front();  // more than queue_size >= 1 messages: the queue stays non-empty
    --held_;
    update_key(i);
    if (!dropped_[i]) {
      dropped_[i] = 1;
      dropped_list_.push_back(i);
    }
    release(i, s, Release::Overflow);
    if (had_candidate) process();  // the remaining messages may still make one
  }
}

void ApproximateTime::process() {
  while (non_empty_ == n_) {
    const uint32_t end_i = max_node_[1], start_i = min_node_[1];
    const double end_t = keys_[end_i], start_t = keys_[start_i];
    // No dropped message of another input could have made a better set than
    // these heads, so those inputs may be the pivot again.
    if (!dropped_list_.empty()) {
      bool keep = dropped_[end_i] != 0;
      for (uint32_t d : dropped_list_) dropped_[d] = 0;
      dropped_list_.clear();
      if (keep) {
        dropped_[end_i] = 1;
        dropped_list_.push_back(end_i);
      }
    }
    if (!has_pivot_) {
      if (end_t - start_t > max_interval_) {  // too wide for any set: the earliest head can never be used
        delete_front(start_i, Release::Interval);
        continue;
      }
      if (dropped_[end_i]) {  // the pivot's input lost messages, a better set may have been lost with them
        delete_front(start_i, Release::Unmatched);
        continue;
      }
      make_candidate();
      cand_start_ = start_t;
      cand_end_ = end_t;
      pivot_ = end_i;
      pivot_time_ = end_t;
      has_pivot_ = true;
      move_to_past(start_i);
    } else if ((end_t - cand_end_) * age_factor_ >= start_t - cand_start_) {
      move_to_past(start_i);  // not better than the candidate
    } else {
      make_candidate();  // better: same pivot and pivot time
      cand_start_ = start_t;
      cand_end_ = end_t;
      move_to_past(start_i);
    }
    if (start_i == pivot_) {
      publish();  // the pivot itself moved aside: every candidate holding it has been seen
    } else if ((end_t - cand_end_) * age_factor_ >= pivot_time_ - cand_start_) {
      // Any later candidate spans [pivot time, end] at least, which is already
      // no better than the candidate.
      publish();
    } else if (non_empty_ < n_) {
      virtual_search();
    }
  }
}

// With a queue empty, assume its next message comes as early as it can (its
// lower bound, and not before the pivot) and keep walking: if even these
// optimistic sets cannot beat the candidate, it is optimal now. Otherwise the
// walk is undone and the policy waits for messages.
void ApproximateTime::virtual_search() {
  virtual_moves_.clear();
  for (;;) {
    const uint32_t end_i = max_node_[1], start_i = min_node_[1];
    const double end_t = keys_[end_i], start_t = keys_[start_i];
    const double age_check = (end_t - cand_end_) * age_factor_;
    if (age_check >= pivot_time_ - cand_start_) {
      publish();  // recovers the virtual moves too
      return;
    }
    if (age_check < start_t - cand_start_) break;  // an optimistic set would be better: wait
    // Here start_t < pivot_time_ (at equality one of the tests above holds),
    // so the earliest head is a real message, not a virtual stamp.
    if (rings_[start_i].queued() == 0) break;  // unreachable; guards the ring
    move_to_past(start_i);
    virtual_moves_.push_back(start_i);
  }
  for (uint32_t i : virtual_moves_) {
    Ring& r = rings_[i];
    if (r.queued() == 0) ++non_empty_;
    --r.past;
    update_key(i);
  }
}

void ApproximateTime::finish() {
  for (uint32_t i = 0; i < n_; ++i) {
    Ring& r = rings_[i];
    r.past = 0;
    while (r.size > 0) release(i, r.pop_front(), Release::Unfinished);
  }
  held_ = 0;
  for (uint32_t i : with_past_) in_with_past_[i] = 0;
  with_past_.clear();
  has_pivot_ = false;
  non_empty_ = 0;
  for (uint32_t d : dropped_list_) dropped_[d] = 0;
  dropped_list_.clear();
  last_stamp_.assign(n_, -kInf);
  rebuild_keys();
}

}  // namespace rvc::sync
