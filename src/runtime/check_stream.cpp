#include "runtime/check_stream.hpp"

#include "runtime/monitor_loop.hpp"

#include <sys/stat.h>

#include <cstdio>
#include <exception>

namespace rvc::runtime {

Outcome run_check(Feed& feed, VerdictOutputs& outputs, const std::function<void(Outcome&)>& read) {
  Outcome outcome;
  try {
    read(outcome);
    feed.end_of_input();
    feed.settle();  // bounded future: the verdicts the stream's end decides
    outputs.finish();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rvc: error: %s\n", e.what());
    outcome.runtime_failure = true;
  }
  feed.finish_report();
  outcome.violated = feed.violations() > 0;
  outcome.rejected = outcome.rejected || feed.stats().rejected > 0;
  outcome.dropped = feed.lost() > 0;
  // A run that checked nothing (an empty trace, every message rejected or
  // unmatched) is no pass: exit 6, as the monitor's.
  if (!outcome.runtime_failure && feed.stats().accepted == 0) {
    std::fprintf(stderr, "rvc: nothing was checked: %s\n", nothing_checked(feed).c_str());
    outcome.incomplete = true;
  }
  return outcome;
}

void add_run_counters(io::JsonObject& out, const Feed& feed, uint64_t verdicts) {
  const PipelineStats& s = feed.stats();
  io::JsonObject dropped;
  feed.add_dropped(dropped);
  out.add("received", feed.received())
      .add("checked", s.accepted)
      .add("rejected", s.rejected)
      .add("dropped", dropped)
      .add("warnings", s.warnings)
      .add("verdicts", verdicts)
      .add("violations", feed.violations());
  // Dense time: the last message's stamp (the dashboard's timeline reaches it).
  if (const double t = feed.last_stamp(); t == t) out.add("stream_time", t);
}

Outcome check_stream(int fd, Pipeline& pipeline, VerdictOutputs& outputs, io::ReaderOptions reader, bool live,
                     bool tick_at_end) {
  if (live) reader.after_chunk = [&outputs] { outputs.idle(); };
  return run_check(pipeline, outputs, [&](Outcome& outcome) {
    std::string error;
    if (!io::read_jsonl(fd, pipeline, reader, error)) {
      std::fprintf(stderr, "rvc: error: %s\n", error.c_str());
      outcome.runtime_failure = true;
      return;
    }
    if (tick_at_end) pipeline.tick(pipeline.last_stamp());  // NaN (nothing taken): no tick
  });
}

bool same_regular_file(const std::string& a, const std::string& b) {
  struct stat sa, sb;
  if ((a == "-" ? ::fstat(0, &sa) : ::stat(a.c_str(), &sa)) != 0 || ::stat(b.c_str(), &sb) != 0) return false;
  return S_ISREG(sa.st_mode) && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

}  // namespace rvc::runtime
