// What the monitor loop feeds messages to: one Pipeline (one input), or a
// SyncedPipeline (several named inputs merged into one stream). The loop
// only moves payloads and counts them; everything about decoding, ordering
// and checking is behind this interface.
#pragma once

#include <cstdint>
#include <limits>
#include <string_view>

#include "io/json_writer.hpp"
#include "io/jsonl_reader.hpp"

namespace rvc::runtime {

struct PipelineStats {
  uint64_t accepted = 0;  // messages fed to the monitors
  uint64_t rejected = 0;  // messages refused (malformed, wrong time order, strict-mode problems)
  uint64_t oversized = 0;  // of the rejected typed samples: over the size cap (no hint about their definition)
  uint64_t warnings = 0;  // fields that kept their previous value (wrong type)
  uint64_t by_layout = 0;  // of the accepted, read by a learned layout without a parse (io/json_layout.hpp)
  // Dense time on a clock: accepted messages stamped at or before the
  // instant ticks had reached; checked, taking effect at that instant.
  uint64_t late_to_clock = 0;
};

class Feed {
 public:
  virtual ~Feed() = default;
  // One payload of input `input` (0 with one input); `position` names it in
  // errors (its sequence number, or line number for a file).
  virtual void feed_input(uint32_t input, std::string_view payload, uint64_t position) = 0;
  // The same with the sample's own key (a wildcard subscriber sees many): a
  // monitor group's feed shards by it (runtime/fleet/sharded_feed.hpp).
  virtual void feed_keyed(uint32_t input, std::string_view key, std::string_view payload, uint64_t position) {
    (void)key;
    feed_input(input, payload, position);
  }
  // The same for a recorded message: `log_time` (seconds) stands for its
  // arrival (a bag's log time).
  virtual void feed_logged(uint32_t input, std::string_view payload, uint64_t position, double log_time) {
    (void)log_time;
    feed_input(input, payload, position);
  }
  virtual void warn(const io::LineError& warning) = 0;

  // ---- Dense time on a clock (docs/semantics.md, "Ticks") ----
  // The only way time moves without a message: the loop asks for the next
  // deadline after every message and tick, waits until its clock reaches it
  // (or a message comes) and ticks there. Stream time, in the messages'
  // own unit (seconds).
  //
  // The first instant at which some verdict can change with every field
  // holding its value; +inf when none can (discrete time, nothing accepted
  // yet, a decode-only feed).
  virtual double next_deadline() { return std::numeric_limits<double>::infinity(); }
  // An empty message at `stream_now`: verdicts up to and at that instant.
  // Before the instant already reached: nothing.
  virtual void tick(double stream_now) { (void)stream_now; }
  // The stamp of the last message the monitors took (NaN: none yet): what
  // the loop's clock is set from.
  virtual double last_stamp() const { return std::numeric_limits<double>::quiet_NaN(); }
  // No message is pending (the loop is waiting): time-driven work.
  virtual void idle() {}
  // Every input has ended (end-of-stream, file end): nothing more will come.
  virtual void end_of_input() {}
  // The run ends (after end_of_input and the end's tick): bounded-future
  // verdicts still pending are settled (engine::Checker::finish).
  virtual void settle() {}
  // Several file inputs: the feed chooses which input's next message it
  // needs (a merge by stamp), and the caller reads that one. next_input()
  // returns it, or -1 once every input has ended and all is fed.
  virtual bool reads_in_order() const { return false; }
  virtual int next_input() { return -1; }
  // Input `input` has ended (its end-of-stream marker, its file's end).
  virtual void input_ended(uint32_t input) { (void)input; }
  // Messages given to the feed (a batch counts its lines): checked +
  // rejected + dropped.
  virtual uint64_t received() const { return stats().accepted + stats().rejected; }
  // Messages dropped before a monitor saw them, by reason ("late": 3): the
  // synchronizer's. The counters line's "dropped".
  virtual void add_dropped(io::JsonObject& out) const { (void)out; }
  // Of those, the ones the run meant to check and could not (late): such a
  // run is not a clean pass (exit 3).
  virtual uint64_t lost() const { return 0; }
  virtual const PipelineStats& stats() const = 0;
  virtual uint64_t violations() const = 0;
  // Prints "N more errors were not shown" if output was cut short.
  virtual void finish_report() = 0;
  // Counters of its own beyond PipelineStats (per-input sync counters).
  virtual void add_stats(io::JsonObject& out) const { (void)out; }
};

}  // namespace rvc::runtime
