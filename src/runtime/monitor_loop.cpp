#include "runtime/monitor_loop.hpp"

#include <cstdio>
#include <stdexcept>
#include <vector>

#include "io/json_writer.hpp"
#include "transport/frame_queue.hpp"

namespace rvc::runtime {
namespace {

// Wall-clock seconds (shared by processes on one host): benchmarks compute
// "first publish to last verdict" from replay's started_at and our done_at.
double wall_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// Closes the queue, then stops the source, however run() is left.
class Shutdown {
 public:
  Shutdown(transport::FrameQueue& queue, transport::Source& source) : queue_(queue), source_(source) {}
  ~Shutdown() { now(); }
  void now() {
    if (done_) return;
    done_ = true;
    queue_.close();
    source_.stop();
  }

 private:
  transport::FrameQueue& queue_;
  transport::Source& source_;
  bool done_ = false;
};

}  // namespace

const char* to_string(EndReason reason) {
  switch (reason) {
    case EndReason::EndOfStream: return "eos";
    case EndReason::Stopped: return "signal";
    case EndReason::IdleTimeout: return "idle-timeout";
    case EndReason::SourceClosed: return "source-closed";
    case EndReason::Failed: return "error";
  }
  return "unknown";
}

std::string MonitorLoop::stats_json() const {
  const PipelineStats& p = pipeline_.stats();
  return io::JsonObject()
      .add("input", options_.input)
      .add("received", counters_.received)
      .add("checked", p.accepted)
      .add("rejected", p.rejected)
      .add("warnings", p.warnings)
      .add("gaps", counters_.gaps)
      .add("duplicates", counters_.duplicates)
      .add("last_seq", counters_.last_seq)
      .add("publishers", counters_.publishers())
      .add("publisher_restarts", counters_.restarts)
      .add("verdicts", outputs_.count())
      .add("violations", pipeline_.checker().violations())
      .add("eos", eos_)
      .add_fixed("first_at", first_at_, 6)
      .add_fixed("done_at", wall_now(), 6)
      .str();
}

void MonitorLoop::publish_stats() {
  std::string js = stats_json();
  std::fprintf(stderr, "%s\n", js.c_str());
  if (stats_sink_) stats_sink_->put(js, 0);
}

void MonitorLoop::process(transport::Source& source) {
  counters_.expect(options_.publishers);
  transport::FrameQueue queue(options_.queue_capacity);
  Shutdown shutdown(queue, source);
  source.start([&queue](const transport::Frame& f) { queue.push(f); });

  using clock = std::chrono::steady_clock;
  const auto idle_limit = std::chrono::duration<double>(options_.idle_timeout);
  auto last_message = clock::now(), last_stats = clock::now();
  std::vector<transport::OwnedFrame> batch;
  size_t count = 0;
  for (;;) {
    if (options_.stop_requested()) {
      end_ = EndReason::Stopped;
      break;
    }
    if (!queue.pop_batch(batch, count, 100)) {
      end_ = EndReason::SourceClosed;
      break;
    }
    const auto now = clock::now();
    if (count == 0) {
      outputs_.idle();
      if (options_.idle_timeout > 0 && now - last_message > idle_limit) {
        end_ = EndReason::IdleTimeout;
        break;
      }
    } else {
      last_message = now;
      if (first_at_ == 0) first_at_ = wall_now();
      for (size_t i = 0; i < count; ++i) {
        const transport::OwnedFrame& f = batch[i];
        if (f.eos) {
          // Several publishers: the stream ends when each has ended.
          if (options_.sequence_numbers) counters_.on_eos(f.seq, f.publisher);
          eos_ = !options_.sequence_numbers ||
                 (counters_.all_ended() && counters_.publishers() >= options_.publishers);
          continue;
        }
        std::string_view payload = f.payload;
        if (options_.sequence_numbers) {
          counters_.on_seq(f.seq, f.publisher);
        } else if (f.seq == 1 && payload.substr(0, io::kUtf8Bom.size()) == io::kUtf8Bom) {
          // A file's byte-order mark, as `rvc check` treats it; on a line of
          // its own it leaves a blank line, which is no message.
          payload.remove_prefix(io::kUtf8Bom.size());
          pipeline_.on_warning(io::LineError{1, 1, io::kBomStartWarning});
          if (payload.find_first_not_of(" \t\r") == std::string_view::npos) continue;
        }
        if (!options_.sequence_numbers) ++counters_.received;
        pipeline_.feed(payload, f.seq ? f.seq : counters_.received);
      }
    }
    // Counters on request or on schedule, also while no message comes.
    if (options_.stats_requested()) publish_stats();
    if (options_.stats_interval > 0 && now - last_stats > std::chrono::duration<double>(options_.stats_interval)) {
      last_stats = now;
      publish_stats();
    }
    if (eos_ && options_.exit_on_eos) {
      end_ = EndReason::EndOfStream;
      break;
    }
  }
  shutdown.now();
}

Outcome MonitorLoop::run(transport::Source& source) {
  Outcome outcome;
  try {
    process(source);
    outputs_.finish();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rvc: error: %s\n", e.what());
    end_ = EndReason::Failed;
    outcome.runtime_failure = true;
  }
  pipeline_.finish_report();
  std::string final_stats = stats_json();  // done_at: last verdict out
  std::fprintf(stderr, "%s\n", final_stats.c_str());
  if (stats_sink_) {
    try {
      stats_sink_->put(final_stats, 0);
      stats_sink_->flush();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rvc: error: %s\n", e.what());
      outcome.runtime_failure = true;
    }
  }
  counters_.rejected = pipeline_.stats().rejected;
  outcome.violated = pipeline_.violated();
  outcome.lost = counters_.gaps > 0 || counters_.duplicates > 0;
  outcome.rejected = pipeline_.stats().rejected > 0;
  // Not a pass: nothing arrived at all, or (when the run was meant to end at
  // the publisher's end-of-stream marker) it ended some other way.
  if (end_ != EndReason::Failed) {
    if (counters_.received == 0 && !eos_) {
      std::fprintf(stderr, "rvc: nothing was received on %s (ended by %s): nothing was checked\n",
                   options_.input.c_str(), to_string(end_));
      outcome.incomplete = true;
    } else if (options_.exit_on_eos && !eos_) {
      std::fprintf(stderr, "rvc: %s ended by %s before the publisher's end-of-stream marker: the stream is incomplete\n",
                   options_.input.c_str(), to_string(end_));
      outcome.incomplete = true;
    }
  }
  return outcome;
}

}  // namespace rvc::runtime
