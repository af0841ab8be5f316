// The monitor's run loop: one or more Sources' frames -> one bounded queue ->
// the engine thread (a Feed: Pipeline, or SyncedPipeline for several inputs)
// -> VerdictOutputs, with loss accounting from publisher
// sequence numbers, counters on request, and an orderly end in every case:
// end-of-stream marker, stop signal, idle timeout, or a failing output.
//
// Shutdown order matters: the queue is closed before the source is stopped
// (Source::stop waits for a transport callback that may be blocked on a full
// queue), on every path out of run(), exceptions included.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "runtime/exit_status.hpp"
#include "runtime/feed.hpp"
#include "runtime/message_filter.hpp"
#include "runtime/ros_clock.hpp"
#include "runtime/stream_clock.hpp"
#include "runtime/verdict_outputs.hpp"
#include "transport/endpoint.hpp"
#include "transport/seq_counter.hpp"

namespace rvc::runtime {

class MonitorLoop;

// What the loop has counted so far, for the monitor's health (the
// /diagnostics output): totals since the start, and how long each input has
// been silent.
struct LoopHealth {
  uint64_t received = 0, checked = 0, rejected = 0, dropped = 0, gaps = 0, duplicates = 0;
  uint64_t verdicts = 0, violations = 0;
  struct Input {
    std::string name;
    uint64_t received = 0;
    double silent_for = 0;  // seconds since its last message (since the start before the first)
  };
  std::vector<Input> inputs;
};

struct LoopOptions {
  std::string input;             // the input's name in the counters line
  // Several inputs: their names (counters per input); empty with one input.
  std::vector<std::string> input_names;
  // The counters line also lists each publisher's share ("by_publisher":
  // id, received, gaps, duplicates, restarts): rmw_zenoh inputs, whose GIDs
  // tell the publishers of a topic apart.
  bool per_publisher = false;
  bool exit_on_eos = false;      // stop at the publisher's end-of-stream marker
  // A publisher's first sequence number past 1 is where this monitor joined
  // it, not a gap (a monitor group's replica started mid-run, docs/fleet.md).
  bool join_mid_stream = false;
  // With exit_on_eos: how many publishers' markers end the stream. A publisher
  // the monitor has not discovered yet when the others end cannot be waited
  // for otherwise (discovery is asynchronous on both DDS and Zenoh).
  size_t publishers = 1;  // per input
  double idle_timeout = 0;       // seconds without any message before giving up; 0: wait forever
  double stats_interval = 0;     // seconds between counter lines; 0: only on request
  size_t queue_capacity = 1 << 14;
  // How frames reach the engine (--handoff, docs/performance.md "Inline hand-off"):
  // Queue: a bounded queue to this thread (the engine), which wakes for them.
  // Inline: the source's own thread checks each frame under the engine's lock
  //   and publishes its verdicts (as a ping's pong answers on its receive
  //   thread): no queue and no wake-up between message and verdict; this
  //   thread keeps the clock, the schedule and the idle flushes.
  // Auto: Inline when every source allows it (Source::handler_may_block:
  //   Zenoh), else Queue.
  enum class Handoff { Auto, Queue, Inline };
  Handoff handoff = Handoff::Auto;
  // Frames carry a publisher's sequence numbers (loss accounting). A file's
  // frames carry line numbers instead: blank lines are not lost messages.
  bool sequence_numbers = true;
  // In front of the monitor (--allow/--deny/--project; may be null): a frame
  // is filtered by its own key (Zenoh) or else by its input's key_of_input.
  MessageFilter* filter = nullptr;
  std::vector<std::string> key_of_input;
  // The counters (JSON) every `record_interval` seconds and once at the end,
  // for the results store (apart from stats_interval, which prints them).
  std::function<void(const std::string&)> on_record;
  double record_interval = 1;
  // Called on the engine thread at least every ~100 ms while the loop runs
  // (the /diagnostics output publishes from it); may read loop.health().
  std::function<void(const MonitorLoop& loop, std::chrono::steady_clock::time_point now)> on_tick;
  // Dense time on a clock (--clock, --tick; docs/semantics.md "Ticks"): while
  // no message comes, the loop sleeps until the feed's next deadline on
  // this clock and ticks there. Off: the monitors move only with messages.
  ClockKind clock = ClockKind::Off;
  // ClockKind::Ros: the /clock input and the rosgraph_msgs/Clock type its
  // samples are read with. Not checked by the properties, not counted as a
  // checked input: only its own counters (clock_messages, clock_backwards).
  transport::Source* ros_clock = nullptr;
  const msg::MessageType* ros_clock_type = nullptr;
  double tick_bound = 0;  // --tick: at most this many seconds between ticks (0: deadlines only)
  // A file input: at its end, a tick at its last stamp reports the last
  // message's own verdicts (as `rvc check` does).
  bool tick_at_end = false;
  TimeSource time = TimeSource::system();
  std::function<bool()> stop_requested = [] { return false; };   // e.g. SIGINT/SIGTERM seen
  std::function<bool()> stats_requested = [] { return false; };  // e.g. SIGUSR1 seen (true once)
};

// Why a run checked nothing, for its message: "3 messages received, 0
// rejected, dropped {"unmatched":3}".
std::string nothing_checked(const Feed& feed, uint64_t filtered = 0);

// Why the loop ended.
enum class EndReason { EndOfStream, Stopped, IdleTimeout, SourceClosed, Failed };
const char* to_string(EndReason reason);

class MonitorLoop {
 public:
  // `stats_sink` (may be null) also receives every counters line.
  MonitorLoop(Feed& feed, VerdictOutputs& outputs, transport::Sink* stats_sink, LoopOptions options)
      : feed_(feed), outputs_(outputs), stats_sink_(stats_sink), options_(std::move(options)) {}

  // Subscribes, checks, publishes; returns what happened. Never throws for a
  // failure while running (an output that cannot be written): that ends the
  // run with runtime_failure set and the reason printed.
  Outcome run(transport::Source& source) { return run(std::vector<transport::Source*>{&source}); }
  // Several inputs: frames of sources[i] are input i (LoopOptions::input_names).
  Outcome run(const std::vector<transport::Source*>& sources);

  // The counters as one JSON object (also printed to stderr on request).
  std::string stats_json() const;
  const transport::SeqCounters& counters(size_t input = 0) const { return counters_[input]; }
  EndReason end_reason() const { return end_; }
  // The counters and each input's silence at `now` (engine thread).
  LoopHealth health(std::chrono::steady_clock::time_point now) const;
  uint64_t ticks() const { return ticks_; }
  // How this run's frames reached the engine, in the counters line: "queue",
  // "inline" (LoopOptions::Handoff) or "read" (files read by this thread).
  const char* handoff() const { return handoff_; }
  // The counters printed at the end of run().
  const std::string& final_stats() const { return final_stats_; }

 private:
  void publish_stats();
  void process(const std::vector<transport::Source*>& sources);
  // Files merged by stamp (Feed::reads_in_order): read on this thread, each
  // the next message of the input the feed asks for.
  void process_in_order(const std::vector<transport::Source*>& sources);
  // Handoff::Inline: each source's thread handles its frames under a lock.
  void process_inline(const std::vector<transport::Source*>& started, size_t checked_inputs);
  // One frame as it arrives, on either path; `now`: its arrival.
  void arrive(const transport::Frame& frame, std::chrono::steady_clock::time_point now);
  void handle(const transport::Frame& frame);  // one frame of either path
  // Counters on request or on schedule; false once the run should end.
  void on_schedule(std::chrono::steady_clock::time_point now);
  // The clock: after a batch (the feed's newest stamp) and on every wake-up.
  void follow_stamps(std::chrono::steady_clock::time_point now);
  // One /clock message (ClockKind::Ros): moves the clock and ticks through
  // every deadline it reached.
  void follow_ros_clock(std::string_view payload, std::chrono::steady_clock::time_point now);
  // Ticks at every deadline the clock has reached (and at --tick's bound);
  // returns when the next tick is due (steady max: none). `slept`: the wait
  // ended with no message (at a deadline, or a duty).
  std::chrono::steady_clock::time_point run_ticks(std::chrono::steady_clock::time_point now, bool slept);
  // The first of the scheduled duties (counters, record, idle timeout) and
  // the next tick: how long the loop may sleep when no message comes.
  std::chrono::steady_clock::time_point wake_at(std::chrono::steady_clock::time_point now,
                                                std::chrono::steady_clock::time_point next_tick,
                                                std::chrono::steady_clock::time_point last_message) const;
  bool ended() const;  // every input's publishers sent their end-of-stream markers
  uint64_t total(uint64_t transport::SeqCounters::*field) const;

  Feed& feed_;
  VerdictOutputs& outputs_;
  transport::Sink* stats_sink_;
  LoopOptions options_;
  std::vector<transport::SeqCounters> counters_ = std::vector<transport::SeqCounters>(1);
  std::vector<bool> input_eos_ = std::vector<bool>(1);
  std::vector<std::chrono::steady_clock::time_point> input_last_ =
      std::vector<std::chrono::steady_clock::time_point>(1, std::chrono::steady_clock::now());
  std::chrono::steady_clock::time_point batch_at_{};  // when the frames being handled arrived
  bool eos_ = false;
  EndReason end_ = EndReason::SourceClosed;
  std::string final_stats_;
  uint64_t filtered_ = 0;   // messages the filter kept from the monitor
  // An output failed while a message was being checked (a verdict it made
  // could not be written): that message was received but neither checked
  // nor rejected; it is counted as dropped ("output_failed").
  bool failed_in_flight_ = false;
  std::string projected_;   // the message as the filter projected it
  std::chrono::steady_clock::time_point last_stats_{}, last_record_{};
  StreamClock clock_{ClockKind::Off};
  double clock_stamp_ = 0;  // the feed's stamp the clock was last set from
  bool clock_said_ = false;
  std::unique_ptr<RosClockReader> ros_clock_reader_;
  uint64_t clock_messages_ = 0, clock_backwards_ = 0, clock_malformed_ = 0;
  uint64_t ticks_ = 0;      // ticks made (each at a deadline or at --tick's bound)
  // How late each deadline tick the loop slept for was on the clock
  // (seconds): the engine thread's wake-up, summarized in the counters as
  // tick_lag_us (the first 65,536).
  std::vector<float> tick_lag_;
  std::chrono::steady_clock::time_point last_tick_{};
  const char* handoff_ = "queue";
  std::chrono::steady_clock::time_point last_message_{};  // for --idle-timeout and the idle flushes
  double first_at_ = 0;  // wall clock of the first message (benchmarks compare across processes)
};

}  // namespace rvc::runtime
