#include "runtime/service_call_feed.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "io/cdr_codec.hpp"

namespace rvc::runtime {

ServiceCallFeed::ServiceCallFeed(Pipeline& inner, const msg::MessageType* event_type, double timeout,
                                 size_t max_reported)
    : inner_(inner),
      type_(event_type),
      calls_(timeout, [this](const std::string& call) { inner_.feed_input(0, call, ++made_); }),
      max_reported_(max_reported) {}

void ServiceCallFeed::feed_input(uint32_t, std::string_view payload, uint64_t position) {
  std::string_view json = payload;
  if (type_) {
    json_.clear();
    io::CdrError cdr;
    if (!io::cdr_to_json(*type_, payload, json_, cdr)) {
      json_ = "not a CDR sample of " + type_->full_name() + ": " + cdr.to_string();
      // counted as a rejected event, as ServiceCalls counts a line that is no event
      calls_.feed("", error_);
      error_ = json_;
      if (calls_.counts().rejected <= max_reported_)
        std::fprintf(stderr, "rvc: service event %llu: %s (skipped)\n", static_cast<unsigned long long>(position),
                     error_.c_str());
      return;
    }
    json = json_;
  }
  if (!calls_.feed(json, error_) && calls_.counts().rejected <= max_reported_)
    std::fprintf(stderr, "rvc: service event %llu: %s (skipped)\n", static_cast<unsigned long long>(position),
                 error_.c_str());
}

double ServiceCallFeed::next_deadline() { return std::min(inner_.next_deadline(), calls_.next_deadline()); }

void ServiceCallFeed::tick(double stream_now) {
  calls_.advance(stream_now);  // unanswered calls due by now are made (and checked) first
  inner_.tick(stream_now);
}

double ServiceCallFeed::last_stamp() const {
  const double now = calls_.now();
  return std::isfinite(now) ? now : std::numeric_limits<double>::quiet_NaN();
}

void ServiceCallFeed::end_of_input() {
  calls_.finish();
  inner_.end_of_input();
}

uint64_t ServiceCallFeed::pending_events() const {
  const auto& c = calls_.counts();
  return c.requests + c.responses - paired();
}

void ServiceCallFeed::add_dropped(io::JsonObject& out) const {
  const auto& c = calls_.counts();
  if (c.duplicates) out.add("duplicate", c.duplicates);
  if (c.orphans) out.add("orphan", c.orphans);
  if (const uint64_t p = pending_events()) out.add("pending", p);
}

const PipelineStats& ServiceCallFeed::stats() const {
  stats_ = inner_.stats();
  stats_.rejected += calls_.counts().rejected;
  return stats_;
}

void ServiceCallFeed::finish_report() {
  calls_.finish();  // the counts of calls still undecided
  const auto& c = calls_.counts();
  std::fprintf(stderr,
               "rvc: %llu service events: %llu calls (%llu answered, %llu unanswered) from %llu of them, %llu "
               "duplicate, %llu responses to no request seen, %llu events of calls still within their timeout at the end, "
               "%llu rejected\n",
               (unsigned long long)c.events, (unsigned long long)(c.answered + c.unanswered),
               (unsigned long long)c.answered, (unsigned long long)c.unanswered, (unsigned long long)paired(),
               (unsigned long long)c.duplicates, (unsigned long long)c.orphans, (unsigned long long)pending_events(),
               (unsigned long long)c.rejected);
  inner_.finish_report();
}

io::JsonObject ServiceCallFeed::call_counts() const {
  const auto& c = calls_.counts();
  io::JsonObject calls;
  calls.add("events", c.events)
      .add("paired", paired())
      .add("calls", c.answered + c.unanswered)
      .add("answered", c.answered)
      .add("unanswered", c.unanswered)
      .add("pending_calls", c.requests - c.answered - c.unanswered);
  return calls;
}

void ServiceCallFeed::add_stats(io::JsonObject& out) const {
  out.add("calls", call_counts());
  inner_.add_stats(out);
}

}  // namespace rvc::runtime
