// The message types rosidl makes of one ROS 2 service definition (.srv: the
// request's fields, a line "---", the response's fields):
//   pkg/srv/Name_Request, pkg/srv/Name_Response, and (Iron on, for service
//   introspection) pkg/srv/Name_Event:
//     service_msgs/msg/ServiceEventInfo info
//     Name_Request[<=1] request
//     Name_Response[<=1] response
// DDS names them pkg::srv::dds_::Name_Request_ etc.
#pragma once

#include <string>
#include <string_view>

#include "msg/msg_types.hpp"

namespace rvc::msg {

enum class ServicePart { Request, Response, Event };

// "AddTwoInts_Request" gives {"AddTwoInts", Request}; false if `name` ends in
// none of _Request, _Response, _Event.
bool split_service_part(std::string_view name, std::string& service, ServicePart& part);

// True if `text` has a line "---" (a .srv, not a .msg).
bool is_srv_text(std::string_view text);

// The request (before "---") or response (after it) part of a .srv text, with
// the other part's lines left blank so that errors name the .srv's own line
// numbers. Throws MsgError (naming `source`) if there is no "---" line or more than one.
std::string srv_part(std::string_view text, ServicePart part, const std::string& source);

// pkg/srv/<service>_Event, unlinked: its fields name ServiceEventInfo and the
// request and response types, which the registry resolves.
MessageType service_event_type(const std::string& package, const std::string& service, const std::string& source);

// The wire layout of a request or reply sample on rmw_cyclonedds' rq/<svc>Request
// and rr/<svc>Reply topics: `type` (pkg/srv/Name_Request or _Response) with two
// leading members, uint64 client_guid and int64 sequence_number (the 16-byte
// request header), under the same DDS type name. A reader needs these members
// in its descriptor: CycloneDDS checks each received sample against the
// reader's ops and drops one whose header bytes are no valid first field
// (docs/services.md). Nested types stay those of `type` (it must outlive this).
MessageType with_request_header(const MessageType& type);

}  // namespace rvc::msg
