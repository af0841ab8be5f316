// Parser of OMG IDL message definitions, the subset ROS 2 and plain DDS
// systems write for data types: modules, structs, typedefs, enums, constants,
// sequences (bounded and not), bounded strings, one-dimensional arrays and
// annotations (@key, @default, @verbatim ... are read and skipped, @default
// is kept as the field's default). Preprocessor lines (#include, #pragma
// keylist) are skipped: nested types are found by the TypeRegistry.
//
// Naming: a struct in `module pkg { module msg { ... } }` is the ROS 2 type
// pkg/msg/Name (DDS name pkg::msg::dds_::Name_, constants from its
// `Name_Constants` module), exactly as rosidl generates .idl from .msg. Any
// other struct is a plain DDS type named by its scoped IDL name
// ("KeyedSeq", "vehicle::Speed"), which is also its DDS type name.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "msg/msg_types.hpp"

namespace rvc::msg {

// Every struct of `text`, in the order defined, unlinked: nested message
// fields carry type_name ("pkg/msg/Name" or a scoped IDL name) only.
// Throws MsgError naming `source`, the line and the column.
std::vector<MessageType> parse_idl(std::string_view text, const std::string& source);

}  // namespace rvc::msg
