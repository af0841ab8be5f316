// `--calls` (rvc monitor, rvc check on a bag): the input is a service's
// introspection events (pkg/srv/Name_Event: CDR samples of a dds:/zenoh:
// topic or a bag, or JSON lines), paired into calls by io::ServiceCalls, and
// the properties check the calls: one JSON object per call, the same ones
// `rvc calls` writes (docs/services.md), fed to an inner JSON Pipeline.
//
// Time: the calls' clock is the events' stamps (info.stamp). A request with no
// response is made "answered": false once that clock passes its deadline:
// when a later event's stamp passes it, or when the monitor loop's clock does
// (next_deadline / tick, the dense-time clock of ARCHITECTURE.md), so a live
// monitor reports an unanswered call at its deadline with no other traffic.
//
// Counts: received = events; each is paired (the request or the response of
// a call made), rejected (no service event) or dropped by reason: duplicate
// (the other side's event of a call), orphan (a response to no request seen,
// or after its deadline), pending (a request, or its response, whose call
// was not decided when the input ended). "checked" counts calls.
#pragma once

#include <cstdint>
#include <string>

#include "io/service_calls.hpp"
#include "msg/msg_types.hpp"
#include "runtime/feed.hpp"
#include "runtime/pipeline.hpp"

namespace rvc::runtime {

// Empty if `type` is a service event type (fields info: ServiceEventInfo,
// request, response); else why not, naming `what` ("topic /chatter"): a
// topic of another type is refused at the start, not blamed on its definition.
std::string not_a_service_event(const msg::MessageType& type, const std::string& what);

class ServiceCallFeed final : public Feed {
 public:
  // `event_type`: the events are CDR samples of this pkg/srv/Name_Event
  // (null: JSON). `inner` is a JSON pipeline of the calls.
  ServiceCallFeed(Pipeline& inner, const msg::MessageType* event_type, double timeout, size_t max_reported = 100);
  // The call itself (rmw_cyclonedds' rq/<svc>Request and rr/<svc>Reply): input 0
  // carries requests, input 1 replies, CDR samples of pkg/srv/Name_Request /
  // _Response each led by the 16-byte request header (uint64 client guid, int64
  // sequence number) after the encapsulation. Each becomes a REQUEST_SENT or
  // RESPONSE_SENT event stamped with its arrival (the system clock when the
  // engine takes it: these samples carry no stamp), so latency is by arrival.
  ServiceCallFeed(Pipeline& inner, const msg::MessageType& request_type, const msg::MessageType& response_type,
                  double timeout, size_t max_reported = 100);

  void feed_input(uint32_t input, std::string_view payload, uint64_t position) override;
  void warn(const io::LineError& warning) override { inner_.warn(warning); }
  double next_deadline() override;
  void tick(double stream_now) override;
  void settle() override { inner_.settle(); }
  double last_stamp() const override;
  void end_of_input() override;
  uint64_t received() const override { return calls_.counts().events; }
  void add_dropped(io::JsonObject& out) const override;
  // Events whose call was never checked (orphans, pending): the run is not a clean pass (exit 3).
  // A duplicate is the other side's event of a call that was checked: it loses nothing.
  uint64_t lost() const override { return calls_.counts().orphans + pending_events(); }
  const PipelineStats& stats() const override;
  uint64_t violations() const override { return inner_.violations(); }
  void finish_report() override;
  void add_stats(io::JsonObject& out) const override;  // "calls": call_counts()
  io::JsonObject call_counts() const;

  const io::ServiceCallCounts& counts() const { return calls_.counts(); }
  // Events of the calls made: a request each, and the response of an answered one.
  uint64_t paired() const { return 2 * calls_.counts().answered + calls_.counts().unanswered; }
  // Events whose call was not decided (its request, and its response if one came).
  uint64_t pending_events() const;

 private:
  // A request or reply sample as a service event (JSON in json_); false with error_.
  bool wire_event(uint32_t input, std::string_view payload);
  void reject(uint64_t position);

  Pipeline& inner_;
  const msg::MessageType* type_;
  const msg::MessageType* request_type_ = nullptr;   // wire mode: both set
  const msg::MessageType* response_type_ = nullptr;
  std::string body_;
  io::ServiceCalls calls_;
  size_t max_reported_;
  uint64_t made_ = 0;  // calls fed to the inner pipeline: their positions
  std::string json_, error_;
  mutable PipelineStats stats_;
};

}  // namespace rvc::runtime
