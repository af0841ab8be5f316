#include "msg/msg_types.hpp"

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

std::string FieldType::to_string() const {
  std::string s = prim == Prim::Message ? type_name : prim_name(prim);
  if (string_bound) s += "<=" + std::to_string(string_bound);
  switch (array) {
    case ArrayKind::None: break;
    case ArrayKind::Fixed: s += "[" + std::to_string(array_size) + "]"; break;
    case ArrayKind::Bounded: s += "[<=" + std::to_string(array_size) + "]"; break;
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
