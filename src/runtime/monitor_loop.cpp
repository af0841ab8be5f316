#include "runtime/monitor_loop.hpp"

#include <sys/prctl.h>

#include <algorithm>
#include <cmath>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <cstdio>
#include <cstdlib>
#include <string_view>
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

// The /clock input's frames (--clock ros=URI), apart from the checked inputs'.
constexpr uint32_t kRosClockInput = UINT32_MAX;

// The longest sleep when nothing is due: how soon a stop signal is seen.
constexpr int kHousekeepingMs = 100;

// Closes the queue, then stops the sources, however run() is left.
class Shutdown {
 public:
  Shutdown(transport::FrameQueue& queue, const std::vector<transport::Source*>& sources)
      : queue_(queue), sources_(sources) {}
  ~Shutdown() { now(); }
  void now() {
    if (done_) return;
    done_ = true;
    queue_.close();
    for (transport::Source* s : sources_) s->stop();
  }

 private:
  transport::FrameQueue& queue_;
  const std::vector<transport::Source*>& sources_;
  bool done_ = false;
};

}  // namespace

std::string nothing_checked(const Feed& feed, uint64_t filtered) {
  const PipelineStats& s = feed.stats();
  io::JsonObject dropped;
  feed.add_dropped(dropped);
  std::string why = std::to_string(feed.received()) + " message" + (feed.received() == 1 ? "" : "s") + " received, " +
                    std::to_string(s.rejected) + " rejected";
  if (filtered) why += ", " + std::to_string(filtered) + " filtered out";
  if (dropped.str() != "{}") why += ", dropped " + dropped.str();
  return why;
}

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

uint64_t MonitorLoop::total(uint64_t transport::SeqCounters::*field) const {
  uint64_t n = 0;
  for (const auto& c : counters_) n += c.*field;
  return n;
}

bool MonitorLoop::ended() const {
  for (bool e : input_eos_)
    if (!e) return false;
  return true;
}

std::string MonitorLoop::stats_json() const {
  const PipelineStats& p = feed_.stats();
  size_t publishers = 0;
  for (const auto& c : counters_) publishers += c.publishers();
  io::JsonObject out;
  out.add("input", options_.input)
      .add("received", total(&transport::SeqCounters::received))
      .add("checked", p.accepted)
      .add("rejected", p.rejected);
  io::JsonObject dropped;
  feed_.add_dropped(dropped);
  if (failed_in_flight_) {  // the message whose verdict could not be written (one message per frame)
    const uint64_t received = total(&transport::SeqCounters::received), taken = feed_.received() + filtered_;
    if (received > taken) dropped.add("output_failed", received - taken);
  }
  out.add("dropped", dropped)
      .add("warnings", p.warnings)
      .add("by_layout", p.by_layout)
      .add("gaps", total(&transport::SeqCounters::gaps))
      .add("duplicates", total(&transport::SeqCounters::duplicates))
      .add("last_seq", total(&transport::SeqCounters::last_seq))
      .add("publishers", publishers)
      .add("publisher_restarts", total(&transport::SeqCounters::restarts));
  if (options_.join_mid_stream) out.add("before_join", total(&transport::SeqCounters::before_join));
  out
      .add("verdicts", outputs_.count())
      .add("violations", feed_.violations())
      .add("eos", eos_)
      .add("handoff", handoff());
  // Dense time: the last message's stamp (the dashboard's timeline reaches it).
  if (const double t = feed_.last_stamp(); t == t) out.add("stream_time", t);
  if (!options_.input_names.empty()) {
    io::JsonArray inputs;
    for (size_t i = 0; i < counters_.size(); ++i) {
      const auto& c = counters_[i];
      inputs.add(io::JsonObject()
                     .add("name", options_.input_names[i])
                     .add("received", c.received)
                     .add("gaps", c.gaps)
                     .add("duplicates", c.duplicates)
                     .add("last_seq", c.last_seq)
                     .add("publishers", c.publishers())
                     .add("publisher_restarts", c.restarts)
                     .add("eos", static_cast<bool>(input_eos_[i])));
    }
    out.add_raw("inputs", inputs.str());
  }
  if (options_.per_publisher) {
    io::JsonArray by;
    for (const auto& c : counters_)
      c.each_publisher([&](uint64_t id, const transport::SeqCounters::Publisher& p) {
        char hex[17];
        std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(id));
        by.add(io::JsonObject()
                   .add("publisher", std::string(hex))
                   .add("received", p.received)
                   .add("gaps", p.gaps)
                   .add("duplicates", p.duplicates)
                   .add("last_seq", p.last_seq)
                   .add("restarts", p.restarts));
      });
    out.add_raw("by_publisher", by.str());
  }
  if (options_.filter) out.add("filtered", filtered_);
  if (options_.clock != ClockKind::Off) {
    out.add("clock", to_string(clock_.kind())).add("ticks", ticks_).add("late_to_clock", p.late_to_clock);
    if (options_.clock == ClockKind::Ros)
      out.add("clock_messages", clock_messages_)
          .add("clock_backwards", clock_backwards_)
          .add("clock_malformed", clock_malformed_);
    if (!tick_lag_.empty()) {  // microseconds from each deadline to the wake-up that ticked it
      std::vector<float> lag = tick_lag_;
      auto at = [&](double q) {
        auto k = lag.begin() + static_cast<std::ptrdiff_t>(q * static_cast<double>(lag.size() - 1));
        std::nth_element(lag.begin(), k, lag.end());
        return std::round(*k * 1e6);
      };
      io::JsonObject summary;
      summary.add("p50", at(0.5)).add("p99", at(0.99)).add("max", at(1.0));
      out.add("tick_lag_us", summary);
    }
  }
  feed_.add_stats(out);
  return out.add_fixed("first_at", first_at_, 6).add_fixed("done_at", wall_now(), 6).str();
}

LoopHealth MonitorLoop::health(std::chrono::steady_clock::time_point now) const {
  LoopHealth h;
  const PipelineStats& p = feed_.stats();
  h.received = total(&transport::SeqCounters::received);
  h.checked = p.accepted;
  h.rejected = p.rejected;
  h.dropped = feed_.lost();
  h.gaps = total(&transport::SeqCounters::gaps);
  h.duplicates = total(&transport::SeqCounters::duplicates);
  h.verdicts = outputs_.count();
  h.violations = feed_.violations();
  for (size_t i = 0; i < counters_.size(); ++i) {
    LoopHealth::Input in;
    in.name = i < options_.input_names.size() ? options_.input_names[i] : options_.input;
    in.received = counters_[i].received;
    in.silent_for = i < input_last_.size() ? std::chrono::duration<double>(now - input_last_[i]).count() : 0;
    h.inputs.push_back(std::move(in));
  }
  return h;
}

void MonitorLoop::publish_stats() {
  std::string js = stats_json();
  std::fprintf(stderr, "%s\n", js.c_str());
  if (stats_sink_) stats_sink_->put(js, 0);
}

void MonitorLoop::handle(const transport::Frame& f) {
  transport::SeqCounters& counters = counters_[f.input];
  if (f.input < input_last_.size()) input_last_[f.input] = batch_at_;
  if (f.eos) {
    // Several publishers: the input ends when each has ended.
    if (options_.sequence_numbers) counters.on_eos(f.seq, f.publisher);
    input_eos_[f.input] = !options_.sequence_numbers ||
                          (counters.all_ended() && counters.publishers() >= options_.publishers);
    if (input_eos_[f.input]) feed_.input_ended(f.input);
    if (!eos_ && ended()) {
      eos_ = true;
      feed_.end_of_input();
    }
    return;
  }
  std::string_view payload = f.payload;
  if (options_.sequence_numbers) {
    counters.on_seq(f.seq, f.publisher);
  } else if (f.seq == 1 && payload.substr(0, io::kUtf8Bom.size()) == io::kUtf8Bom) {
    // A file's byte-order mark, as `rvc check` treats it; on a line of
    // its own it leaves a blank line, which is no message.
    payload.remove_prefix(io::kUtf8Bom.size());
    feed_.warn(io::LineError{1, 1, io::kBomStartWarning});
    if (payload.find_first_not_of(" \t\r") == std::string_view::npos) return;
  }
  if (!options_.sequence_numbers) ++counters.received;
  if (options_.filter) {  // after loss accounting: a filtered message was not lost
    std::string_view key = f.key;
    if (key.empty() && f.input < options_.key_of_input.size()) key = options_.key_of_input[f.input];
    if (!options_.filter->admits(key)) {
      ++filtered_;
      return;
    }
    if (options_.filter->projecting() && options_.filter->project(payload, projected_)) payload = projected_;
  }
  try {
    feed_.feed_keyed(f.input, f.key, payload, f.seq ? f.seq : counters.received);
  } catch (...) {
    failed_in_flight_ = true;  // counted in stats_json(), whatever ends the run
    throw;
  }
}

void MonitorLoop::on_schedule(std::chrono::steady_clock::time_point now) {
  // Counters on request or on schedule, also while no message comes.
  if (options_.stats_requested()) publish_stats();
  if (options_.stats_interval > 0 && now - last_stats_ >= std::chrono::duration<double>(options_.stats_interval)) {
    last_stats_ = now;
    publish_stats();
  }
  if (options_.on_record && now - last_record_ >= std::chrono::duration<double>(options_.record_interval)) {
    last_record_ = now;
    options_.on_record(stats_json());
  }
  if (options_.on_tick) options_.on_tick(*this, now);
}

void MonitorLoop::follow_stamps(std::chrono::steady_clock::time_point now) {
  // Off, or ROS time, which messages do not set (follow_ros_clock).
  if (options_.clock == ClockKind::Off || options_.clock == ClockKind::Ros) return;
  const double stamp = feed_.last_stamp();
  if (std::isnan(stamp) || (clock_.running() && stamp == clock_stamp_)) return;
  clock_stamp_ = stamp;
  clock_.on_message(stamp, now);
  if (!clock_said_ && clock_.running()) {  // said once, when it starts
    clock_said_ = true;
    std::fprintf(stderr, "rvc monitor: dense time on the %s clock%s%s: ticks at the properties' deadlines%s\n",
                 to_string(clock_.kind()), clock_.reason().empty() ? "" : " (",
                 clock_.reason().empty() ? "" : (clock_.reason() + ")").c_str(),
                 options_.tick_bound > 0 ? " and at least every --tick" : "");
  }
}

void MonitorLoop::follow_ros_clock(std::string_view payload, std::chrono::steady_clock::time_point now) {
  ++clock_messages_;
  double t = 0;
  std::string error;
  if (!ros_clock_reader_->read(payload, t, error)) {
    if (clock_malformed_++ == 0)  // said once: a wrong type would say it 1000 times a second
      std::fprintf(stderr, "rvc monitor: warning: a /clock message is no rosgraph_msgs/Clock (%s): ignored\n",
                   error.c_str());
    return;
  }
  const bool was_running = clock_.running();
  if (!clock_.set_ros_time(t)) {
    if (clock_backwards_++ == 0)
      std::fprintf(stderr,
                   "rvc monitor: warning: /clock went back from %.9g to %.9g s (a simulator reset or a looped bag?): "
                   "ignored, ROS time stays until /clock passes it again\n",
                   clock_.now(now), t);
    return;
  }
  if (!was_running)
    std::fprintf(stderr, "rvc monitor: dense time on the ros clock (/clock, from %.9g s): ticks at the properties' "
                         "deadlines as /clock passes them\n", t);
  run_ticks(now, false);
}

std::chrono::steady_clock::time_point MonitorLoop::run_ticks(std::chrono::steady_clock::time_point now, bool slept) {
  using clock = std::chrono::steady_clock;
  if (!clock_.running()) return clock::time_point::max();
  bool ticked = false;
  double deadline = feed_.next_deadline();
  auto next = clock_.when(deadline, now);
  // Each deadline reached, in order, each tick exactly at its instant (a
  // burst of them after a long stop of the process, say, is made at once).
  while (next <= now) {
    // A deadline the loop slept for (not one a message's arrival had
    // already passed, such as the message's own instant): how late it woke.
    if (slept && tick_lag_.size() < 65536) tick_lag_.push_back(static_cast<float>(clock_.now(now) - deadline));
    feed_.tick(deadline);
    ++ticks_;
    ticked = true;
    last_tick_ = now;
    const double after = feed_.next_deadline();
    if (!(after > deadline)) {  // the engine promises progress; never spin if it did not
      next = now + std::chrono::milliseconds(1);
      break;
    }
    deadline = after;
    next = clock_.when(deadline, now);
  }
  if (options_.tick_bound > 0) {  // --tick: the fallback bound, a tick at the clock's own now
    const auto bound = std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(options_.tick_bound));
    if (!ticked && now - last_tick_ >= bound) {
      feed_.tick(clock_.now(now));
      ++ticks_;
      ticked = true;
      last_tick_ = now;
      next = clock_.when(feed_.next_deadline(), now);
    }
    next = std::min(next, last_tick_ + bound);
  }
  if (ticked) outputs_.idle();  // the tick's verdicts out now, not at the next idle flush
  return next;
}

std::chrono::steady_clock::time_point MonitorLoop::wake_at(std::chrono::steady_clock::time_point now,
                                                           std::chrono::steady_clock::time_point next_tick,
                                                           std::chrono::steady_clock::time_point last_message) const {
  using clock = std::chrono::steady_clock;
  auto after = [](double seconds) {
    return std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(seconds));
  };
  // Stop signals and the feed's and outputs' idle work (flushes, sync
  // health) are looked at this often when nothing else is due.
  auto wake = std::min(next_tick, now + std::chrono::milliseconds(kHousekeepingMs));
  if (options_.stats_interval > 0) wake = std::min(wake, last_stats_ + after(options_.stats_interval));
  if (options_.on_record) wake = std::min(wake, last_record_ + after(options_.record_interval));
  if (options_.idle_timeout > 0) wake = std::min(wake, last_message + after(options_.idle_timeout));
  return wake;
}

void MonitorLoop::arrive(const transport::Frame& f, std::chrono::steady_clock::time_point now) {
  if (f.input == kRosClockInput) {
    // In arrival order with the data: a message after a /clock message is
    // checked after that clock's ticks. /clock is no data: a simulator's
    // clock running on does not hold off --idle-timeout while the checked
    // inputs are silent.
    if (!f.eos) follow_ros_clock(f.payload, now);
    return;
  }
  last_message_ = now;
  if (first_at_ == 0) first_at_ = wall_now();
  handle(f);
}

void MonitorLoop::process(const std::vector<transport::Source*>& sources) {
  counters_.assign(sources.size(), transport::SeqCounters{});
  input_eos_.assign(sources.size(), false);
  input_last_.assign(sources.size(), std::chrono::steady_clock::now());
  for (auto& c : counters_) {
    c.expect(options_.publishers);
    if (options_.join_mid_stream) c.join_mid_stream();
  }
  last_stats_ = last_record_ = last_tick_ = last_message_ = std::chrono::steady_clock::now();
  clock_ = StreamClock(options_.clock, options_.time);
  // Deadlines are met to the timer's precision: the kernel may defer a
  // sleeping thread's wake-up by its timer slack (50 us by default); 1 us
  // on this thread (the engine's) costs nothing while it sleeps.
  if (options_.clock != ClockKind::Off) ::prctl(PR_SET_TIMERSLACK, 1000UL, 0, 0, 0);
  if (feed_.reads_in_order()) return process_in_order(sources);
  // RVC_HANDOFF=sleep (benchmarks only: bench/network_bench.py measures the
  // two side by side) is the hand-off as it was before 2026-11-27: the engine
  // thread sleeps at once when the queue is empty, and a DDS source takes its
  // samples on its own waitset thread.
  const char* handoff = std::getenv("RVC_HANDOFF");
  const bool legacy = handoff && std::string_view(handoff) == "sleep";
  std::vector<transport::Source*> started = sources;
  const bool ros_clock = options_.clock == ClockKind::Ros && options_.ros_clock;
  if (ros_clock) {
    ros_clock_reader_ = std::make_unique<RosClockReader>(*options_.ros_clock_type);
    started.push_back(options_.ros_clock);
  }
  const bool may_inline =
      std::all_of(started.begin(), started.end(), [](const transport::Source* s) { return s->handler_may_block(); });
  using Handoff = LoopOptions::Handoff;
  if (options_.handoff == Handoff::Inline && !may_inline)
    throw std::runtime_error("--handoff inline: an input's transport thread must not block (DDS, files): "
                             "use --handoff queue (or auto)");
  if (may_inline && !legacy && options_.handoff != Handoff::Queue) return process_inline(started, sources.size());

  transport::FrameQueue queue(options_.queue_capacity,
                              legacy ? std::chrono::microseconds(0) : transport::FrameQueue::kSpin);
  Shutdown shutdown(queue, started);
  for (size_t i = 0; i < started.size(); ++i) {
    const auto input = ros_clock && i == sources.size() ? kRosClockInput : static_cast<uint32_t>(i);
    // A source that never blocks its transport thread fills the queue by
    // itself (DDS); the others push, blocking while it is full.
    if (auto* feeder = legacy ? nullptr : dynamic_cast<transport::QueueFeeder*>(started[i])) {
      feeder->start_into(queue, input);
      continue;
    }
    started[i]->start([&queue, input](const transport::Frame& f) {
      transport::Frame tagged = f;
      tagged.input = input;
      queue.push(tagged);
    });
  }

  using clock = std::chrono::steady_clock;
  const auto idle_limit = std::chrono::duration<double>(options_.idle_timeout);
  auto next_tick = clock::time_point::max();
  std::vector<transport::OwnedFrame> batch;
  size_t count = 0;
  for (;;) {
    if (options_.stop_requested()) {
      end_ = EndReason::Stopped;
      break;
    }
    // No polling period: the wait ends at a message, at the next tick's
    // deadline, or at the next scheduled duty, whichever comes first.
    if (!queue.pop_batch_until(batch, count, wake_at(clock::now(), next_tick, last_message_))) {
      end_ = EndReason::SourceClosed;
      break;
    }
    const auto now = clock::now();
    if (count == 0) {
      feed_.idle();
      outputs_.idle();
      if (options_.idle_timeout > 0 && now - last_message_ >= idle_limit) {
        end_ = EndReason::IdleTimeout;
        break;
      }
    } else {
      batch_at_ = now;
      for (size_t i = 0; i < count; ++i) {
        const transport::OwnedFrame& o = batch[i];
        transport::Frame f;
        f.payload = o.payload;
        f.seq = o.seq;
        f.eos = o.eos;
        f.publisher = o.publisher;
        f.input = o.input;
        f.key = o.key;
        arrive(f, now);
      }
      follow_stamps(now);
    }
    next_tick = run_ticks(now, count == 0);
    on_schedule(now);
    if (eos_ && options_.exit_on_eos) {
      end_ = EndReason::EndOfStream;
      break;
    }
  }
  shutdown.now();
}

void MonitorLoop::process_inline(const std::vector<transport::Source*>& started, size_t checked_inputs) {
  using clock = std::chrono::steady_clock;
  // Buffered outputs (a file, stdout, the results store) are flushed once no
  // message came for this long: as the queue's engine flushes when it finds
  // the queue empty, without a flush per message in a steady stream.
  constexpr auto kFlushAfter = std::chrono::milliseconds(1);
  handoff_ = "inline";
  std::mutex engine;  // the feed, the outputs, the counters and the clock
  std::condition_variable wake;
  bool closed = false, poke = false, dirty = false;
  std::exception_ptr failure;  // an output failed on a source's thread: the run ends with it
  auto next_tick = clock::time_point::max();
  auto planned = clock::time_point::max();  // when this thread means to wake next
  std::unique_lock<std::mutex> lock(engine, std::defer_lock);

  // However this function is left: no handler runs past this point, then
  // the sources stop (stop() waits for a handler that may be waiting for
  // the lock: it is released first).
  struct Stop {
    std::unique_lock<std::mutex>& lock;
    bool& closed;
    const std::vector<transport::Source*>& sources;
    ~Stop() {
      if (!lock.owns_lock()) lock.lock();
      closed = true;
      lock.unlock();
      for (transport::Source* s : sources) s->stop();
    }
  } stop{lock, closed, started};

  for (size_t i = 0; i < started.size(); ++i) {
    const auto input = i == checked_inputs ? kRosClockInput : static_cast<uint32_t>(i);
    started[i]->start([&, input](const transport::Frame& f) {
      std::unique_lock<std::mutex> held(engine);
      if (closed || failure) return;
      const auto now = clock::now();
      try {
        transport::Frame tagged = f;
        tagged.input = input;
        batch_at_ = now;
        arrive(tagged, now);
        if (input != kRosClockInput) follow_stamps(now);
        next_tick = run_ticks(now, false);
        dirty = true;
      } catch (...) {
        failure = std::current_exception();
      }
      // This thread wakes the loop only when it has to: the run ends, or
      // the loop sleeps past a new deadline or past the next flush.
      if (failure || (eos_ && options_.exit_on_eos) || std::min(next_tick, now + kFlushAfter) < planned) {
        poke = true;
        held.unlock();
        wake.notify_one();
      }
    });
  }
  lock.lock();

  const auto idle_limit = std::chrono::duration<double>(options_.idle_timeout);
  for (;;) {
    if (failure) std::rethrow_exception(failure);
    if (options_.stop_requested()) {
      end_ = EndReason::Stopped;
      break;
    }
    if (eos_ && options_.exit_on_eos) {
      end_ = EndReason::EndOfStream;
      break;
    }
    planned = wake_at(clock::now(), next_tick, last_message_);
    if (dirty) planned = std::min(planned, last_message_ + kFlushAfter);
    poke = false;
    const bool poked = wake.wait_until(lock, planned, [&] { return poke; });
    if (failure || (eos_ && options_.exit_on_eos)) continue;
    const auto now = clock::now();
    if (now - last_message_ >= kFlushAfter) {
      feed_.idle();
      outputs_.idle();
      dirty = false;
      if (options_.idle_timeout > 0 && now - last_message_ >= idle_limit) {
        end_ = EndReason::IdleTimeout;
        break;
      }
    }
    next_tick = run_ticks(now, !poked);
    on_schedule(now);
  }
}

void MonitorLoop::process_in_order(const std::vector<transport::Source*>& sources) {
  for (transport::Source* s : sources)
    if (!s->pullable()) throw std::logic_error("inputs merged by stamp must be files");
  handoff_ = "read";
  using clock = std::chrono::steady_clock;
  const auto idle_limit = std::chrono::duration<double>(options_.idle_timeout);
  auto last_message = clock::now();
  uint64_t frames = 0;
  transport::Frame f;
  for (;;) {
    if (options_.stop_requested()) {
      end_ = EndReason::Stopped;
      break;
    }
    const int input = feed_.next_input();
    if (input < 0) {
      end_ = EndReason::EndOfStream;
      break;
    }
    const transport::PullResult r = sources[static_cast<size_t>(input)]->pull(f);
    const auto now = clock::now();
    if (r == transport::PullResult::Wait) {  // stdin or a pipe with nothing yet
      feed_.idle();
      outputs_.idle();
      if (options_.idle_timeout > 0 && now - last_message > idle_limit) {
        end_ = EndReason::IdleTimeout;
        break;
      }
      on_schedule(now);
      continue;
    }
    if (r == transport::PullResult::End) {  // after its end-of-stream frame: cannot be asked for again
      feed_.input_ended(static_cast<uint32_t>(input));
      continue;
    }
    last_message = batch_at_ = now;
    if (first_at_ == 0) first_at_ = wall_now();
    f.input = static_cast<uint32_t>(input);
    handle(f);
    if ((++frames & 1023) == 0) on_schedule(now);
  }
}

Outcome MonitorLoop::run(const std::vector<transport::Source*>& sources) {
  Outcome outcome;
  try {
    process(sources);
    feed_.end_of_input();  // also after a signal or idle timeout: what is held is checked
    // A file's end: its last message's own verdicts (a tick at its stamp).
    if (options_.tick_at_end && end_ == EndReason::EndOfStream) feed_.tick(feed_.last_stamp());
    feed_.settle();  // bounded future: the verdicts the stream's end decides
    outputs_.finish();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rvc: error: %s\n", e.what());
    end_ = EndReason::Failed;
    outcome.runtime_failure = true;
  }
  feed_.finish_report();
  final_stats_ = stats_json();  // done_at: last verdict out
  const std::string& final_stats = final_stats_;
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
  outcome.violated = feed_.violations() > 0;
  outcome.lost = total(&transport::SeqCounters::gaps) > 0 || total(&transport::SeqCounters::duplicates) > 0;
  outcome.rejected = feed_.stats().rejected > 0;
  outcome.dropped = feed_.lost() > 0;
  // Not a pass: nothing arrived at all, or (when the run was meant to end at
  // the publisher's end-of-stream marker) it ended some other way.
  if (end_ != EndReason::Failed) {
    if (total(&transport::SeqCounters::received) == 0) {
      std::string why;  // a transport's reason, such as a publisher with incompatible QoS
      for (const transport::Source* s : sources)
        if (std::string d = s->diagnosis(); !d.empty()) why += "; " + d;
      std::fprintf(stderr, "rvc: nothing was received on %s (ended by %s): nothing was checked%s\n",
                   options_.input.c_str(), to_string(end_), why.c_str());
      outcome.incomplete = true;
    } else if (!options_.input_names.empty() && !eos_ &&
               std::any_of(counters_.begin(), counters_.end(), [](const auto& c) { return c.received == 0; })) {
      for (size_t i = 0; i < counters_.size(); ++i)
        if (counters_[i].received == 0) {
          const std::string d = i < sources.size() ? sources[i]->diagnosis() : std::string();
          std::fprintf(stderr, "rvc: nothing was received on input '%s' (ended by %s): sets needing it never formed%s\n",
                       options_.input_names[i].c_str(), to_string(end_), d.empty() ? "" : ("; " + d).c_str());
        }
      outcome.incomplete = true;
    } else if (options_.exit_on_eos && !eos_) {
      std::fprintf(stderr, "rvc: %s ended by %s before the publisher's end-of-stream marker: the stream is incomplete\n",
                   options_.input.c_str(), to_string(end_));
      outcome.incomplete = true;
    } else if (feed_.stats().accepted == 0) {
      std::fprintf(stderr, "rvc: nothing was checked: %s\n", nothing_checked(feed_, filtered_).c_str());
      outcome.incomplete = true;
    }
  }
  return outcome;
}

}  // namespace rvc::runtime
