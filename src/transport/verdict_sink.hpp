// Sinks that store verdicts as typed messages on a timeline (mcap:) rather
// than as JSON payloads: VerdictOutputs hands them each verdict as a CDR sample
// of rvc_msgs/msg/Verdict and the time it is about, instead of calling put().
#pragma once

#include <cstdint>
#include <string_view>

namespace rvc::transport {

// An input message copied beside the verdicts (mcap:PATH?inputs=1): a bag's
// message with its topic's type and definition as the bag records them.
struct InputMessage {
  std::string_view topic;
  std::string_view type;              // "pkg/msg/Name"; "" for JSON messages without one
  std::string_view message_encoding;  // "cdr", "json"
  std::string_view schema_encoding;   // "ros2msg", "ros2idl", "jsonschema"; "" when there is none
  std::string_view schema;            // the definition's text
  std::string_view data;              // the message's bytes, copied unchanged
  uint64_t log_time_ns = 0;
};

class VerdictSink {
 public:
  virtual ~VerdictSink() = default;
  // Whether this sink copies the input messages too (put_input).
  virtual bool wants_inputs() const { return false; }
  // One input message, after the verdicts of its step. Throws as put_verdict.
  virtual void put_input(const InputMessage& message) { (void)message; }
  // One verdict: `cdr` is a sample of rvc_msgs/msg/Verdict (CDR, little-endian,
  // with its 4-byte encapsulation header); `log_time_ns` the time of the step it
  // is about. Throws std::runtime_error when it cannot be written.
  virtual void put_verdict(std::string_view cdr, uint64_t log_time_ns) = 0;
};

}  // namespace rvc::transport
