// Constant and default values in .msg files, read as rosidl reads them
// (rosidl_adapter/parser.py, parse_primitive_value_string and parse_value_string):
//
//   bool      true/false/1/0 in any case ("TRUE", "True", "1")
//   integers  Python's int(): decimal with leading zeros and a sign ("007", "+5"),
//             else int(text, 0): 0x/0o/0b prefixes ("0x10"); '_' between digits;
//             in the type's range
//   floats    Python's float(): decimal, exponent, nan, inf, infinity (any case)
//   strings   the text, its outer quotes removed (an inner unescaped quote is refused)
//   arrays    [a, b, c], each element as above; a fixed array needs exactly its
//             size, a bounded one at most its bound
//
// Each value becomes JSON text (what `rvc msg encode` reads; non-finite floats as
// NaN, Infinity, -Infinity): the encoders write exactly the value rosidl's
// generated code would. A value rosidl refuses is an error here too.
#pragma once

#include <string>
#include <string_view>

#include "msg/msg_types.hpp"

namespace rvc::msg {

// The value of `text` for a field or constant of type `type` as JSON text in
// `json`; false with `error` (what is wrong, without the position) otherwise.
bool rosidl_value(const FieldType& type, std::string_view text, std::string& json, std::string& error);

}  // namespace rvc::msg
