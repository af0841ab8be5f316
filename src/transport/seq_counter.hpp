// Loss accounting from publisher sequence numbers: received, gaps (missing
// numbers), duplicates (numbers seen again or going backwards). Identical for
// every transport, so Zenoh and DDS report the same counters.
#pragma once

#include <cstdint>

namespace rvc::transport {

struct SeqCounters {
  uint64_t received = 0;
  uint64_t gaps = 0;        // sequence numbers skipped (lost or never sent)
  uint64_t duplicates = 0;  // repeated or backwards sequence numbers
  uint64_t rejected = 0;    // payloads the decoder refused (set by the pipeline)
  uint64_t last_seq = 0;

  void on_seq(uint64_t seq) {
    ++received;
    if (seq == 0) return;  // publisher sent no sequence number
    if (seq <= last_seq) { ++duplicates; return; }
    gaps += seq - last_seq - 1;
    last_seq = seq;
  }
  // At end of stream the publisher tells its last seq: anything after ours is lost.
  void on_eos(uint64_t publisher_last_seq) {
    if (publisher_last_seq > last_seq) { gaps += publisher_last_seq - last_seq; last_seq = publisher_last_seq; }
  }
};

}  // namespace rvc::transport
