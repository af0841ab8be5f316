#include "runtime/service_call_feed.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "io/cdr_codec.hpp"

namespace rvc::runtime {

std::string not_a_service_event(const msg::MessageType& type, const std::string& what) {
  auto has = [&](const char* name, const char* type_suffix) {
    for (const auto& f : type.fields)
      if (f.name == name)
        return type_suffix == nullptr || (f.type.type_name.size() >= std::strlen(type_suffix) &&
                                          f.type.type_name.ends_with(type_suffix));
    return false;
  };
  if (has("info", "ServiceEventInfo") && has("request", nullptr) && has("response", nullptr)) return "";
  return "--calls pairs the events of a service (pkg/srv/Name_Event: info, request, response, on "
         "/SERVICE/_service_event); " + what + " is " + type.full_name() + ", not a service event type";
}

ServiceCallFeed::ServiceCallFeed(Pipeline& inner, const msg::MessageType* event_type, double timeout,
                                 size_t max_reported)
    : inner_(inner),
      type_(event_type),
      calls_(timeout, [this](const std::string& call) { inner_.feed_input(0, call, ++made_); }),
      max_reported_(max_reported) {}

ServiceCallFeed::ServiceCallFeed(Pipeline& inner, const msg::MessageType& request_type,
                                 const msg::MessageType& response_type, double timeout, size_t max_reported)
    : ServiceCallFeed(inner, nullptr, timeout, max_reported) {
  request_type_ = &request_type;
  response_type_ = &response_type;
}

void ServiceCallFeed::reject(uint64_t position) {
  const std::string why = error_;
  calls_.feed("", error_);  // counted as a rejected event, as ServiceCalls counts a line that is no event
  if (calls_.counts().rejected <= max_reported_)
    std::fprintf(stderr, "rvc: service event %llu: %s (skipped)\n", static_cast<unsigned long long>(position),
                 why.c_str());
}

bool ServiceCallFeed::wire_event(uint32_t input, std::string_view payload) {
  const bool request = input == 0;
  const msg::MessageType& type = request ? *request_type_ : *response_type_;
  constexpr size_t kEncapsulation = 4, kHeader = 16;
  if (payload.size() < kEncapsulation + kHeader) {
    error_ = std::string(request ? "request" : "reply") + " sample of " + std::to_string(payload.size()) +
             " bytes: shorter than the encapsulation and the 16-byte request header";
    return false;
  }
  const bool little = payload[1] & 1;  // CDR_LE 00 01, CDR_BE 00 00
  auto read64 = [&](size_t at) {
    uint64_t v = 0;
    for (size_t i = 0; i < 8; ++i) {
      const uint64_t byte = static_cast<unsigned char>(payload[at + i]);
      v |= little ? byte << (8 * i) : byte << (8 * (7 - i));
    }
    return v;
  };
  const uint64_t guid = read64(kEncapsulation);
  const int64_t seq = static_cast<int64_t>(read64(kEncapsulation + 8));
  // The fields follow the header; alignment counts from the encapsulation's
  // end, and 16 keeps it, so the sample without the header decodes as the type.
  std::string sample(payload.substr(0, kEncapsulation));
  sample.append(payload.substr(kEncapsulation + kHeader));
  body_.clear();
  io::CdrError cdr;
  if (!io::cdr_to_json(type, sample, body_, cdr)) {
    error_ = "not a " + std::string(request ? "request" : "reply") + " sample of " + type.full_name() +
             " after the request header: " + cdr.to_string();
    return false;
  }
  const int64_t now = std::chrono::duration_cast<std::chrono::nanoseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
  json_ = "{\"info\":{\"event_type\":" + std::string(request ? "0" : "2") + ",\"stamp\":{\"sec\":" +
          std::to_string(now / 1000000000) + ",\"nanosec\":" + std::to_string(now % 1000000000) +
          "},\"client_gid\":[" + std::to_string(guid) + "],\"sequence_number\":" + std::to_string(seq) + "},\"" +
          (request ? "request" : "response") + "\":[" + body_ + "]}";
  return true;
}

void ServiceCallFeed::feed_input(uint32_t input, std::string_view payload, uint64_t position) {
  std::string_view json = payload;
  if (request_type_) {
    if (!wire_event(input, payload)) return reject(position);
    json = json_;
  } else if (type_) {
    json_.clear();
    io::CdrError cdr;
    if (!io::cdr_to_json(*type_, payload, json_, cdr)) {
      error_ = "not a CDR sample of " + type_->full_name() + ": " + cdr.to_string();
      return reject(position);
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
