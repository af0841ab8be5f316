#include "io/service_calls.hpp"

#include <cmath>
#include <cstdint>
#include <limits>
#include <tuple>

#include <simdjson.h>

#include "io/json_writer.hpp"

namespace rvc::io {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

bool integer(simdjson::dom::element e, int64_t& out) {
  if (e.is_int64()) return out = int64_t(e), true;
  if (e.is_uint64()) {
    uint64_t u = e;
    if (u > uint64_t(std::numeric_limits<int64_t>::max())) return false;
    return out = int64_t(u), true;
  }
  return false;
}
}  // namespace

bool ServiceCalls::feed(std::string_view json, std::string& error) {
  ++counts_.events;
  thread_local simdjson::dom::parser parser;
  simdjson::dom::element doc;
  auto reject = [&](const std::string& why) {
    ++counts_.rejected;
    error = why;
    return false;
  };
  if (parser.parse(json.data(), json.size()).get(doc) != simdjson::SUCCESS) return reject("not JSON");
  simdjson::dom::element info, stamp, gid, e;
  if (doc["info"].get(info) != simdjson::SUCCESS || !info.is_object())
    return reject("no field 'info' (a service event, pkg/srv/Name_Event, has info, request and response)");
  int64_t type = 0, sec = 0, nanosec = 0, sequence = 0;
  if (info["event_type"].get(e) != simdjson::SUCCESS || !integer(e, type) || type < 0 || type > 3)
    return reject("info.event_type is not 0..3 (REQUEST_SENT, REQUEST_RECEIVED, RESPONSE_SENT, RESPONSE_RECEIVED)");
  if (info["stamp"].get(stamp) != simdjson::SUCCESS || stamp["sec"].get(e) != simdjson::SUCCESS || !integer(e, sec) ||
      stamp["nanosec"].get(e) != simdjson::SUCCESS || !integer(e, nanosec))
    return reject("info.stamp is not a builtin_interfaces/Time (sec, nanosec)");
  if (info["sequence_number"].get(e) != simdjson::SUCCESS || !integer(e, sequence))
    return reject("info.sequence_number is not an integer");
  if (info["client_gid"].get(gid) != simdjson::SUCCESS || !gid.is_array())
    return reject("info.client_gid is not an array");
  auto first_of = [&](const char* field, std::string& out) {
    simdjson::dom::array a;
    out.clear();
    if (doc[field].get_array().get(a) == simdjson::SUCCESS && a.size() > 0) out = simdjson::minify(a.at(0).value());
  };
  if (sec < INT32_MIN || sec > INT32_MAX || nanosec < 0 || nanosec > 999999999)
    return reject("info.stamp is out of range (sec int32, nanosec 0..999999999)");
  const int64_t t_ns = sec * 1000000000 + nanosec;
  const double t = double(t_ns) / 1e9;
  advance(t);  // a response stamped after the request's deadline comes too late
  Key key{simdjson::minify(gid), sequence};
  const bool request = type <= 1;
  auto open = open_.find(key);
  if (request) {
    if (open != open_.end() || done_.count(key)) {
      ++counts_.duplicates;
      return true;
    }
    Call call;
    call.key = key;
    call.request_time = t;
    call.request_ns = t_ns;
    call.sequence = sequence;
    first_of("request", call.request);
    Order order{t, arrivals_++};
    queue_.emplace(order, std::move(call));
    open_.emplace(std::move(key), order);
    // A request stamped before a time already passed (a straggler) may be past its deadline at once.
    if (t + timeout_ > now_) waiting_.insert(order);
    else queue_.at(order).timed_out = true;
    ++counts_.requests;
  } else {
    if (open == open_.end()) {
      if (auto made = done_.find(key); made != done_.end()) {
        // the other side's response of an answered call; a response after the deadline is an orphan
        (made->second.answered ? ++counts_.duplicates : ++counts_.orphans);
      } else {
        ++counts_.orphans;
      }
      return true;
    }
    Call& call = queue_.at(open->second);
    if (call.answered) {
      ++counts_.duplicates;
      return true;
    }
    call.answered = true;
    waiting_.erase(open->second);
    ++counts_.responses;
    call.response_ns = t_ns;
    first_of("response", call.response);
  }
  flush();
  return true;
}

double ServiceCalls::next_deadline() const {
  return waiting_.empty() ? kInf : std::get<0>(*waiting_.begin()) + timeout_;
}

void ServiceCalls::advance(double now) {
  if (!(now > now_)) return;
  now_ = now;
  bool any = false;
  while (!waiting_.empty() && !(std::get<0>(*waiting_.begin()) + timeout_ > now_)) {
    queue_.at(*waiting_.begin()).timed_out = true;
    waiting_.erase(waiting_.begin());
    any = true;
  }
  if (any) flush();
  // Forget calls made long ago: a later event of one of them is then an orphan.
  while (!done_by_time_.empty() && done_by_time_.begin()->first + 4 * timeout_ < now_) {
    done_.erase(done_by_time_.begin()->second);
    done_by_time_.erase(done_by_time_.begin());
  }
}

void ServiceCalls::flush() {
  while (!queue_.empty()) {
    auto it = queue_.begin();
    Call& call = it->second;
    if (!call.answered && !call.timed_out) break;
    double time = call.request_time;
    if (emitted_any_ && !(time > last_time_)) time = std::max(last_time_ + 1e-9, std::nextafter(last_time_, kInf));
    last_time_ = time;
    emitted_any_ = true;
    JsonObject out;
    out.add("time", time).add("request_time", call.request_time).add("answered", call.answered);
    out.add("latency", call.answered ? double(call.response_ns - call.request_ns) / 1e9 : timeout_);
    out.add("sequence_number", call.sequence);
    if (!call.request.empty()) out.add_raw("request", call.request);
    if (!call.response.empty()) out.add_raw("response", call.response);
    (call.answered ? counts_.answered : counts_.unanswered)++;
    done_[call.key] = Made{call.request_time, call.answered};  // a key made is never open again until forgotten
    done_by_time_.emplace(call.request_time, call.key);
    open_.erase(call.key);
    queue_.erase(it);
    emit_(out.str());
  }
}

void ServiceCalls::finish() {
  flush();
  counts_.pending = queue_.size();
}

}  // namespace rvc::io
