// The monitor's run loop: a Source's frames -> a bounded queue -> the engine
// thread (Pipeline) -> VerdictOutputs, with loss accounting from publisher
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
#include <string>

#include "runtime/exit_status.hpp"
#include "runtime/pipeline.hpp"
#include "runtime/verdict_outputs.hpp"
#include "transport/endpoint.hpp"
#include "transport/seq_counter.hpp"

namespace rvc::runtime {

struct LoopOptions {
  std::string input;             // the input's name in the counters line
  bool exit_on_eos = false;      // stop at the publisher's end-of-stream marker
  // With exit_on_eos: how many publishers' markers end the stream. A publisher
  // the monitor has not discovered yet when the others end cannot be waited
  // for otherwise (discovery is asynchronous on both DDS and Zenoh).
  size_t publishers = 1;
  double idle_timeout = 0;       // seconds without any message before giving up; 0: wait forever
  double stats_interval = 0;     // seconds between counter lines; 0: only on request
  size_t queue_capacity = 1 << 14;
  // Frames carry a publisher's sequence numbers (loss accounting). A file's
  // frames carry line numbers instead: blank lines are not lost messages.
  bool sequence_numbers = true;
  std::function<bool()> stop_requested = [] { return false; };   // e.g. SIGINT/SIGTERM seen
  std::function<bool()> stats_requested = [] { return false; };  // e.g. SIGUSR1 seen (true once)
};

// Why the loop ended.
enum class EndReason { EndOfStream, Stopped, IdleTimeout, SourceClosed, Failed };
const char* to_string(EndReason reason);

class MonitorLoop {
 public:
  // `stats_sink` (may be null) also receives every counters line.
  MonitorLoop(Pipeline& pipeline, VerdictOutputs& outputs, transport::Sink* stats_sink, LoopOptions options)
      : pipeline_(pipeline), outputs_(outputs), stats_sink_(stats_sink), options_(std::move(options)) {}

  // Subscribes, checks, publishes; returns what happened. Never throws for a
  // failure while running (an output that cannot be written): that ends the
  // run with runtime_failure set and the reason printed.
  Outcome run(transport::Source& source);

  // The counters as one JSON object (also printed to stderr on request).
  std::string stats_json() const;
  const transport::SeqCounters& counters() const { return counters_; }
  EndReason end_reason() const { return end_; }

 private:
  void publish_stats();
  void process(transport::Source& source);

  Pipeline& pipeline_;
  VerdictOutputs& outputs_;
  transport::Sink* stats_sink_;
  LoopOptions options_;
  transport::SeqCounters counters_;
  bool eos_ = false;
  EndReason end_ = EndReason::SourceClosed;
  double first_at_ = 0;  // wall clock of the first message (benchmarks compare across processes)
};

}  // namespace rvc::runtime
