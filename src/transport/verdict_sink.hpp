// Sinks that store verdicts as typed messages on a timeline (mcap:) rather
// than as JSON payloads: VerdictOutputs hands them each verdict as a CDR sample
// of rvc_msgs/msg/Verdict and the time it is about, instead of calling put().
#pragma once

#include <cstdint>
#include <string_view>

namespace rvc::transport {

class VerdictSink {
 public:
  virtual ~VerdictSink() = default;
  // One verdict: `cdr` is a sample of rvc_msgs/msg/Verdict (CDR, little-endian,
  // with its 4-byte encapsulation header); `log_time_ns` the time of the step it
  // is about. Throws std::runtime_error when it cannot be written.
  virtual void put_verdict(std::string_view cdr, uint64_t log_time_ns) = 0;
};

}  // namespace rvc::transport
