// ROS 2 /diagnostics messages (diagnostic_msgs/msg/DiagnosticArray), as
// diagnostic_updater publishes them and rqt_robot_monitor, Foxglove and
// Autoware's diagnostic graph aggregator read them. rvc writes them for
// property verdicts, for its own health and for `rvc hz`; this is the one
// place that knows the message's shape.
//
// The CDR form goes through the bundled definitions (src/msg/definitions/
// diagnostic_msgs) and the generic JSON -> CDR codec, so it is the same
// encoder every typed output uses.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace rvc::msg {
struct MessageType;
}

namespace rvc::io {

// diagnostic_msgs/msg/DiagnosticStatus levels (a byte on the wire).
enum class DiagLevel : uint8_t { Ok = 0, Warn = 1, Error = 2, Stale = 3 };
const char* to_string(DiagLevel level);  // "OK", "WARN", "ERROR", "STALE"

struct DiagStatus {
  DiagLevel level = DiagLevel::Ok;
  std::string name;         // "rvc: <monitor>/<property>", as diagnostic_updater names "<node>: <task>"
  std::string message;      // one line for a human
  std::string hardware_id;  // what the status is about (a host, a topic)
  std::vector<std::pair<std::string, std::string>> values;  // key/value pairs shown beside it
};

// The DiagnosticArray type's name on DDS (ROS 2 naming) and in ROS 2 form.
inline constexpr std::string_view kDiagnosticArrayType = "diagnostic_msgs/msg/DiagnosticArray";
inline constexpr std::string_view kDiagnosticArrayDdsType = "diagnostic_msgs::msg::dds_::DiagnosticArray_";

// The array as JSON, in the shape rvc's CDR codec reads and writes
// ({"header":{"stamp":{"sec":..,"nanosec":..},"frame_id":..},"status":[...]}).
// `stamp`: seconds since the epoch (split into sec/nanosec; negative or
// non-finite stamps are written as 0).
std::string diagnostic_array_json(double stamp, const std::vector<DiagStatus>& statuses,
                                  std::string_view frame_id = "");

// The same as one CDR sample (little-endian XCDR1 with its 4-byte header),
// ready for a DDS writer of kDiagnosticArrayDdsType or a Zenoh payload as
// rmw_zenoh carries it. Throws std::runtime_error if the encoder refuses it
// (which would be a bug: every field is built here).
std::string diagnostic_array_cdr(double stamp, const std::vector<DiagStatus>& statuses,
                                 std::string_view frame_id = "");

// The bundled DiagnosticArray type (resolved once), for a DDS writer of it.
const msg::MessageType& diagnostic_array_type();

}  // namespace rvc::io
