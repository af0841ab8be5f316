#include "runtime/ros_clock.hpp"

namespace rvc::runtime {

bool RosClockReader::read(std::string_view payload, double& seconds, std::string& error) {
  const bool cdr = !payload.empty() && payload.front() == '\0';
  return (cdr ? cdr_ : json_).read(payload, seconds, error) == TimeFieldReader::Result::Ok;
}

}  // namespace rvc::runtime
