// ROS time for `rvc monitor --clock ros=URI` (use_sim_time): the seconds a
// /clock message (rosgraph_msgs/Clock) carries. A dds: topic delivers typed
// samples, CDR; so does rmw_zenoh on a zenoh: key. A zenoh: key or a file
// may carry JSON instead, as `rvc echo` prints a Clock:
// {"clock":{"sec":S,"nanosec":N}}, or {"clock":SECONDS}. The two are told
// apart by the first byte: a CDR sample starts with its encapsulation
// header (0x00), a JSON text never does.
#pragma once

#include <string>
#include <string_view>

#include "msg/msg_types.hpp"
#include "runtime/time_field_reader.hpp"

namespace rvc::runtime {

class RosClockReader {
 public:
  // `clock_type`: rosgraph_msgs/msg/Clock, resolved by the caller's registry.
  explicit RosClockReader(const msg::MessageType& clock_type) : cdr_("clock", &clock_type), json_("clock", nullptr) {}
  // The time in seconds; false with `error` for a payload that is no Clock.
  bool read(std::string_view payload, double& seconds, std::string& error);

 private:
  TimeFieldReader cdr_, json_;
};

}  // namespace rvc::runtime
