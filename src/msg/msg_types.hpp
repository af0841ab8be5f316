// ROS 2 message types as read from .msg definitions at run time: the fields
// (in wire order) and constants of one message, with nested message types
// resolved to pointers into the TypeRegistry that owns them.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace rvc::msg {

enum class Prim : uint8_t {
  Bool, Byte, Char, Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Float32, Float64,
  String, WString,
  Message,  // a nested message type
};

// Size and alignment of a primitive in CDR (strings and messages: 0).
size_t prim_size(Prim p);
const char* prim_name(Prim p);
bool prim_is_integer(Prim p);
bool prim_is_float(Prim p);
// The value of a constant or default of type `prim` written as `text`
// (numbers, and true/false/True/False/1/0 for bool), range-checked for
// integers. False with `error` set when it is not one.
bool prim_value(Prim prim, std::string_view text, double& value, std::string& error);

enum class ArrayKind : uint8_t { None, Fixed, Bounded, Unbounded };

// The largest array size, array or sequence bound and string bound a
// definition may write (T[N], T[<=N], string<=N; IDL T name[N],
// sequence<T, N>, string<N>): larger ones are refused where they are
// written. 16 Mi elements; a sample is at most 4 GiB on the wire anyway.
inline constexpr uint32_t kMaxArraySize = uint32_t{1} << 24;
// The largest smallest sample of a type (every fixed array filled, every
// sequence and string empty): a type over it is refused when it is linked,
// naming the field, since encoding even its default sample would allocate
// that much (int32[16777216] of a nested type in a fixed array of 16 Mi...).
inline constexpr uint64_t kMaxFixedBytes = uint64_t{1} << 26;  // 64 MiB

struct MessageType;

struct FieldType {
  Prim prim = Prim::Int32;
  std::string type_name;                // Message: "pkg/msg/Name" (or "pkg/srv/Name_Request")
  const MessageType* message = nullptr; // Message: set by TypeRegistry::resolve
  uint32_t string_bound = 0;            // string<=N; 0: unbounded
  ArrayKind array = ArrayKind::None;
  uint32_t array_size = 0;              // Fixed: the size; Bounded: the bound
  std::string to_string() const;        // as written in a .msg: "uint8[<=4]"
};

struct Field {
  std::string name;
  FieldType type;
  std::string default_text;  // "float64 x 1.5": "1.5" (as written; empty: none)
  // The default as JSON text, read as rosidl reads it (msg_values.hpp): "bool b TRUE"
  // gives "true", "int32[] a [0x10, +5]" gives "[16,5]". Empty: none.
  std::string default_json;
  int line = 0;
};

struct Constant {
  std::string name;
  Prim prim = Prim::Int32;
  std::string text;          // the value as written (strings unquoted)
  double number = 0;         // numeric and bool constants
  int line = 0;
};

struct MessageType {
  std::string package, name;     // "geometry_msgs", "Twist"; a service's "AddTwoInts_Request"
  // "msg", or "srv" for the types of a service (Name_Request, Name_Response,
  // Name_Event): the middle of "pkg/srv/Name_Request" and of its DDS name
  // "pkg::srv::dds_::Name_Request_".
  std::string kind = "msg";
  // Types from a plain DDS .idl (not in a module pkg::msg): the scoped IDL
  // name ("KeyedSeq", "vehicle::Speed"), which is both its DDS type name and
  // what --type names it by. Empty for ROS 2 types.
  std::string idl_name;
  std::vector<Field> fields;     // in wire order; empty messages carry one uint8 on the wire
  std::vector<Constant> constants;
  // DDS key members (IDL @key or #pragma keylist; ROS 2 types have none):
  // top-level field names, in the order given.
  std::vector<std::string> keys;
  std::string source;            // where the definition came from (file path, "bundled", "mcap schema")
  // Bytes of its smallest sample (fixed arrays filled, sequences and strings
  // empty; alignment not counted), set when linked: at most kMaxFixedBytes.
  uint64_t fixed_bytes = 0;

  std::string full_name() const { return idl_name.empty() ? package + "/" + kind + "/" + name : idl_name; }
  const Constant* constant(const std::string& constant_name) const;
};

// A definition that cannot be read or a type that cannot be resolved: names
// the source, line and column.
class MsgError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace rvc::msg
