// Loss accounting from publisher sequence numbers: received, gaps (missing
// numbers), duplicates (numbers seen again or going backwards), counted per
// publisher, so two publishers on one topic do not read as each other's
// duplicates, and a publisher that starts again from 1 reads as a restart,
// not as a flood of duplicates. Identical for every transport, so Zenoh and
// DDS report the same counters.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace rvc::transport {

class SeqCounters {
 public:
  // Totals over all publishers.
  uint64_t received = 0;
  uint64_t gaps = 0;        // sequence numbers skipped (lost or never sent)
  uint64_t duplicates = 0;  // repeated or backwards sequence numbers
  uint64_t rejected = 0;    // payloads the decoder refused (set by the pipeline)
  uint64_t last_seq = 0;    // messages announced: the sum of each publisher's last sequence number
  uint64_t restarts = 0;    // a publisher that began again (from 1, or a new one after an end of stream)
  // join_mid_stream(): the numbers a publisher had sent before its first one
  // reached this subscriber (not lost: sent before it joined).
  uint64_t before_join = 0;

  // A subscriber that joins publishers already running (a monitor group's
  // replica started or restarted mid-run, docs/fleet.md): a publisher's
  // first sequence number past 1 is where it joined, not a gap.
  void join_mid_stream() { join_mid_stream_ = true; }

  // One message; `publisher` identifies its sender (0: unknown — counted, not
  // accounted). seq 0: the publisher sent no sequence number.
  void on_seq(uint64_t seq, uint64_t publisher = 0);
  // End of stream: the publisher tells its last seq; anything after ours is lost.
  void on_eos(uint64_t publisher_last_seq, uint64_t publisher = 0);

  // How many publishers the run expects (monitor --publishers N): until that
  // many have been seen, a newcomer after another one ended is one of them
  // discovered late, not a publisher that restarted.
  void expect(size_t publishers) { expected_ = publishers; }
  size_t publishers() const { return by_publisher_.size(); }
  // Every publisher seen so far has sent its end-of-stream marker.
  bool all_ended() const { return ended_ == by_publisher_.size(); }

  // One publisher's share of the totals (rvc monitor's "by_publisher").
  struct Publisher {
    uint64_t last_seq = 0;
    bool ended = false;
    uint64_t received = 0, gaps = 0, duplicates = 0, restarts = 0;  // kept across its restarts
  };
  // Calls f(id, publisher) for every publisher seen, in order of id.
  template <class F>
  void each_publisher(F f) const;

 private:
  Publisher& publisher(uint64_t id, uint64_t seq);

  std::unordered_map<uint64_t, Publisher> by_publisher_;
  size_t ended_ = 0;
  bool any_ended_ = false;  // some publisher ended: a newcomer after it is a restart
  size_t expected_ = 1;
  bool join_mid_stream_ = false;
};

// Header-only: the transports' own test probes use it without the rest of rvc.
inline SeqCounters::Publisher& SeqCounters::publisher(uint64_t id, uint64_t seq) {
  auto [it, fresh] = by_publisher_.try_emplace(id);
  Publisher& p = it->second;
  if (fresh) {
    // A publisher that ended, started again (DDS and Zenoh give it a new id);
    // unless fewer publishers than expected were seen before this one.
    if (any_ended_ && by_publisher_.size() - 1 >= expected_) ++restarts;
    return p;
  }
  // The same publisher numbering from the start again: it restarted.
  if (seq == 1 && (p.last_seq > 1 || p.ended)) {
    ++restarts;
    ++p.restarts;
    if (p.ended) --ended_;
    p.last_seq = 0;
    p.ended = false;
  }
  return p;
}

inline void SeqCounters::on_seq(uint64_t seq, uint64_t id) {
  ++received;
  if (seq == 0) return;  // publisher sent no sequence number
  const bool first = join_mid_stream_ && by_publisher_.find(id) == by_publisher_.end();
  Publisher& p = publisher(id, seq);
  ++p.received;
  if (first && seq > 1) {
    before_join += seq - 1;
    last_seq += seq - 1;
    p.last_seq = seq - 1;
  }
  if (seq <= p.last_seq) {
    ++duplicates;
    ++p.duplicates;
    return;
  }
  gaps += seq - p.last_seq - 1;
  p.gaps += seq - p.last_seq - 1;
  last_seq += seq - p.last_seq;
  p.last_seq = seq;
}

inline void SeqCounters::on_eos(uint64_t publisher_last_seq, uint64_t id) {
  Publisher& p = publisher(id, 0);
  if (publisher_last_seq > p.last_seq) {
    gaps += publisher_last_seq - p.last_seq;
    p.gaps += publisher_last_seq - p.last_seq;
    last_seq += publisher_last_seq - p.last_seq;
    p.last_seq = publisher_last_seq;
  }
  if (!p.ended) {
    p.ended = true;
    ++ended_;
  }
  any_ended_ = true;
}

template <class F>
void SeqCounters::each_publisher(F f) const {
  std::vector<uint64_t> ids;
  for (const auto& [id, p] : by_publisher_) ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  for (uint64_t id : ids) f(id, by_publisher_.at(id));
}

}  // namespace rvc::transport
