#include "msg/msg_types.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace rvc::msg {

size_t prim_size(Prim p) {
  switch (p) {
    case Prim::Bool: case Prim::Byte: case Prim::Char: case Prim::Int8: case Prim::UInt8: return 1;
    case Prim::Int16: case Prim::UInt16: return 2;
    case Prim::Int32: case Prim::UInt32: case Prim::Float32: return 4;
    case Prim::Int64: case Prim::UInt64: case Prim::Float64: return 8;
    default: return 0;
  }
}

const char* prim_name(Prim p) {
  switch (p) {
    case Prim::Bool: return "bool";
    case Prim::Byte: return "byte";
    case Prim::Char: return "char";
    case Prim::Int8: return "int8";
    case Prim::UInt8: return "uint8";
    case Prim::Int16: return "int16";
    case Prim::UInt16: return "uint16";
    case Prim::Int32: return "int32";
    case Prim::UInt32: return "uint32";
    case Prim::Int64: return "int64";
    case Prim::UInt64: return "uint64";
    case Prim::Float32: return "float32";
    case Prim::Float64: return "float64";
    case Prim::String: return "string";
    case Prim::WString: return "wstring";
    case Prim::Message: return "message";
  }
  return "?";
}

bool prim_is_integer(Prim p) {
  switch (p) {
    case Prim::Int8: case Prim::UInt8: case Prim::Int16: case Prim::UInt16:
    case Prim::Int32: case Prim::UInt32: case Prim::Int64: case Prim::UInt64: return true;
    default: return false;
  }
}

bool prim_is_float(Prim p) { return p == Prim::Float32 || p == Prim::Float64; }

bool prim_value(Prim prim, std::string_view text, double& value, std::string& error) {
  std::string s(text);
  if (prim == Prim::Bool) {
    if (s == "true" || s == "True" || s == "TRUE" || s == "1") return value = 1, true;
    if (s == "false" || s == "False" || s == "FALSE" || s == "0") return value = 0, true;
    error = "a bool constant is true or false, not '" + s + "'";
    return false;
  }
  char* end = nullptr;
  errno = 0;
  double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || errno == ERANGE) {
    error = std::string("not a ") + prim_name(prim) + " value: '" + s + "'";
    return false;
  }
  if (prim_is_integer(prim) || prim == Prim::Byte || prim == Prim::Char) {
    if (std::floor(v) != v) {
      error = std::string("not an integer for ") + prim_name(prim) + ": '" + s + "'";
      return false;
    }
    double lo = 0, hi = 0;
    switch (prim) {
      case Prim::Int8: lo = -128; hi = 127; break;
      case Prim::UInt8: case Prim::Byte: case Prim::Char: lo = 0; hi = 255; break;
      case Prim::Int16: lo = -32768; hi = 32767; break;
      case Prim::UInt16: lo = 0; hi = 65535; break;
      case Prim::Int32: lo = -2147483648.0; hi = 2147483647.0; break;
      case Prim::UInt32: lo = 0; hi = 4294967295.0; break;
      case Prim::Int64: lo = -9223372036854775808.0; hi = 9223372036854775807.0; break;
      default: lo = 0; hi = 18446744073709551615.0; break;
    }
    if (v < lo || v > hi) {
      error = s + " does not fit in " + prim_name(prim);
      return false;
    }
  }
  value = v;
  return true;
}

std::string FieldType::to_string() const {
  std::string s = prim == Prim::Message ? type_name : prim_name(prim);
  // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on "[" + to_string(n).
  if (string_bound) s.append("<=").append(std::to_string(string_bound));
  switch (array) {
    case ArrayKind::None: break;
    case ArrayKind::Fixed: s.append("[").append(std::to_string(array_size)).append("]"); break;
    case ArrayKind::Bounded: s.append("[<=").append(std::to_string(array_size)).append("]"); break;
    case ArrayKind::Unbounded: s += "[]"; break;
  }
  return s;
}

const Constant* MessageType::constant(const std::string& constant_name) const {
  for (const auto& c : constants)
    if (c.name == constant_name) return &c;
  return nullptr;
}

}  // namespace rvc::msg
