// Service calls from service introspection events: ROS 2 (Iron on) publishes
// each service's events on <service>/_service_event as pkg/srv/Name_Event
// (info.event_type REQUEST_SENT 0, REQUEST_RECEIVED 1, RESPONSE_SENT 2,
// RESPONSE_RECEIVED 3; info.stamp; info.client_gid + info.sequence_number name
// the call; request[] / response[] hold the message when introspection
// carries contents). ServiceCalls turns them into one JSON object per call:
//   {"time": T, "request_time": t, "answered": true, "latency": s,
//    "sequence_number": n, "request": {...}, "response": {...}}
// A call starts at its first request event and is answered by its first
// response event (client and server side events of one call are one call). A
// request with no response by request time + timeout is a call with
// "answered": false and "latency": timeout, made when the clock passes that
// deadline. Calls come out in the order of their request times, each as soon
// as it and every earlier call is decided; "time" is the request time, moved
// just after the previous call's (1 ns or the next double) if the request
// came later than that call was made (a straggler), so times always increase.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>

namespace rvc::io {

struct ServiceCallCounts {
  uint64_t events = 0;       // lines read
  uint64_t requests = 0;     // calls started
  uint64_t responses = 0;    // response events that answered a call
  uint64_t answered = 0;     // calls made with a response
  uint64_t unanswered = 0;   // calls made at their deadline
  uint64_t duplicates = 0;   // a second request or response event of a call (the other side's)
  uint64_t orphans = 0;      // responses to no request seen (recording started mid-call, or after its deadline)
  uint64_t rejected = 0;     // lines that are no service event
  uint64_t pending = 0;      // set by finish(): requests whose deadline the input never reached
};

class ServiceCalls {
 public:
  using Emit = std::function<void(const std::string& call_json)>;
  ServiceCalls(double timeout, Emit emit) : timeout_(timeout), emit_(std::move(emit)) {}

  // One event as JSON (as `rvc echo`/`rvc msg decode` print a pkg/srv/Name_Event).
  // False with `error` set if it is none (counted in rejected).
  bool feed(std::string_view json, std::string& error);
  // The clock reached `now` (seconds, the events' stamps' clock): calls whose deadline passed are made.
  void advance(double now);
  // The latest time the input has shown (-inf before any event).
  double now() const { return now_; }
  // When the next unanswered call is due (+inf if none).
  double next_deadline() const;
  // End of input: calls decided are made; requests still within their timeout are counted as pending.
  void finish();
  const ServiceCallCounts& counts() const { return counts_; }

 private:
  using Key = std::pair<std::string, int64_t>;             // client_gid as JSON text, sequence number
  using Order = std::tuple<double, uint64_t>;               // request time, arrival
  struct Call {
    Key key;
    double request_time = 0;  // seconds
    int64_t request_ns = 0, response_ns = 0;  // the stamps, exact: latency = their difference
    int64_t sequence = 0;
    std::string request;   // JSON object or empty
    std::string response;  // JSON object or empty
    bool answered = false;
    bool timed_out = false;
  };
  struct Made {
    double request_time;
    bool answered;
  };
  void flush();

  double timeout_;
  Emit emit_;
  double now_ = -std::numeric_limits<double>::infinity();
  double last_time_ = 0;
  bool emitted_any_ = false;
  uint64_t arrivals_ = 0;
  // Every event costs O(log n) in the calls open, whatever their number
  // (issue 36: a scan of every open call per event made 40,000 pending calls
  // take 50 s): the calls by request time, their keys, the unanswered ones by
  // deadline (request time + the one timeout: request-time order), and the
  // calls made by request time, to forget them.
  std::map<Order, Call> queue_;            // calls not made yet, by request time
  std::map<Key, Order> open_;              // their keys
  std::set<Order> waiting_;                // calls in queue_ neither answered nor timed out: by deadline
  std::map<Key, Made> done_;               // calls made: a later event of one is a duplicate (or, unanswered, an orphan)
  std::set<std::pair<double, Key>> done_by_time_;  // done_'s keys by request time
  ServiceCallCounts counts_;
};

}  // namespace rvc::io
