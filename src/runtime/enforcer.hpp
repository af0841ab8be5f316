// The enforcer (`rvc monitor --on-violation PROPERTY=URI:PAYLOAD`): when a
// property becomes violated, publish a command — a hazard-lights or
// emergency-stop message — on an endpoint of its own. It runs on the engine
// thread inside the verdict callback, so the command leaves in the same
// step as the violating message's verdict: no queue in between.
//
// One command per violation, not per verdict: only a change to false (or a
// first verdict that is false) fires, and `debounce` seconds of wall clock
// must pass between two commands of the same action (a flapping property
// does not flood the actuator).
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "engine/checker.hpp"
#include "msg/msg_types.hpp"
#include "transport/endpoint.hpp"
#include "transport/transport_options.hpp"

namespace rvc::runtime {

struct EnforceAction {
  std::string property;
  std::string uri;      // zenoh:KEY, dds:TOPIC, file:PATH, -
  std::string payload;  // JSON text (a CDR sample of command_type on typed endpoints)
};

// "PROPERTY=URI:PAYLOAD", e.g. p1=zenoh:vehicle/hazard:{"on":true}: the URI is
// the scheme and one name (a key or topic, which hold no ':'); everything
// after the next ':' is the payload. Throws std::invalid_argument naming the
// problem.
EnforceAction parse_enforce_action(const std::string& text);

class Enforcer {
 public:
  // Opens every action's endpoint. `command_type` (may be null): the
  // commands' ROS 2 type; their JSON payloads are encoded as CDR samples of
  // it for dds:/zenoh: endpoints (and checked here, before anything runs).
  // Throws std::invalid_argument for a payload that does not fit the type.
  Enforcer(std::vector<EnforceAction> actions, const transport::TransportOptions& transports, double debounce,
           const msg::MessageType* command_type);
  ~Enforcer();

  // Every verdict (a VerdictOutputs observer).
  void on_verdict(const engine::Verdict& verdict);
  // Waits for this many subscribers on each network endpoint (false: not in time).
  bool wait_subscribers(size_t count, std::chrono::milliseconds timeout, std::string& which);
  void finish();  // end-of-stream markers (none for typed zenoh commands), flush

  uint64_t commands() const { return commands_; }
  uint64_t debounced() const { return debounced_; }

 private:
  struct Action {
    EnforceAction spec;
    std::string sample;  // what is published
    std::unique_ptr<transport::Sink> sink;
    std::chrono::steady_clock::time_point last{};
    bool fired = false;
    uint64_t sent = 0;  // this endpoint's sequence numbers (its subscribers count losses)
    // Typed commands on zenoh: end without a marker. Its empty payload would reach ROS 2 subscribers
    // through zenoh-bridge-ros2dds as an empty, malformed sample (docs/zenoh.md).
    bool eos = true;
  };
  std::vector<Action> actions_;
  std::unordered_map<std::string, bool> last_value_;  // property -> last verdict
  double debounce_;
  uint64_t commands_ = 0, debounced_ = 0;
};

}  // namespace rvc::runtime
