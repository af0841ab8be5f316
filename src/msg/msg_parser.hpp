// Parser of ROS 2 .msg definitions (the rosidl message format): one field or
// constant per line, '#' comments, arrays T[] / T[N] / T[<=N], bounded strings
// string<=N, defaults "T name value" and constants "T NAME=value".
#pragma once

#include <string>
#include <string_view>

#include "msg/msg_types.hpp"

namespace rvc::msg {

// Parses the definition of `package`/`name`. Nested types written without a
// package ("Point") are taken from `package`. Throws MsgError naming
// `source`, the line and the column.
MessageType parse_msg(std::string_view package, std::string_view name, std::string_view text,
                      const std::string& source);

// "pkg/msg/Name", "pkg/Name", "pkg::msg::Name" and the DDS form
// "pkg::msg::dds_::Name_" all give {"pkg", "Name"}; false if `text` is none of them.
bool split_type_name(std::string_view text, std::string& package, std::string& name);
// The same, and also the types of a service: "pkg/srv/Name_Request",
// "pkg::srv::Name_Event", "pkg::srv::dds_::Name_Response_" give kind "srv";
// every other accepted form gives kind "msg".
bool split_type_name(std::string_view text, std::string& package, std::string& kind, std::string& name);

}  // namespace rvc::msg
