#include "io/bound_values.hpp"

#include <charconv>
#include <cmath>

#include "io/json_writer.hpp"

namespace rvc::io {

uint32_t BoundValues::id(const FieldValue& v) {
  key_.clear();
  switch (v.kind) {
    case ValueKind::String:
      key_.push_back('s');
      key_.append(v.s);
      break;
    case ValueKind::Number: {
      if (v.exact.kind != spec::ExactInt::None && spec::order_int_double(v.exact, v.d) != spec::Equal) {
        key_.push_back('i');  // an integer no double equals: its digits ('n' keys are doubles)
        spec::append_exact(key_, v.exact);
        break;
      }
      char buf[32];
      const double d = v.d == 0 ? 0.0 : v.d;  // -0 is 0
      const auto written = std::to_chars(buf, buf + sizeof buf, d);  // shortest exact text: one key per double
      key_.push_back('n');
      key_.append(buf, written.ptr);
      break;
    }
    case ValueKind::Bool: key_ = v.b ? "b1" : "b0"; break;
    default: return 0;
  }
  auto [it, added] = ids_.try_emplace(key_, static_cast<uint32_t>(ids_.size() + 1));
  if (added) keys_.push_back(&it->first);
  return it->second;
}

std::string BoundValues::json(uint32_t id) const {
  if (id == 0 || id > keys_.size()) return "";
  const std::string& key = *keys_[id - 1];  // kind letter, then the text
  std::string out;
  switch (key[0]) {
    case 's': append_json_string(out, std::string_view(key).substr(1)); break;
    case 'n':
    case 'i':
      out = key.substr(1);
      if (out == "nan" || out == "inf" || out == "-inf") out = non_finite_word(out == "nan" ? NAN : out[0] == '-' ? -INFINITY : INFINITY);
      break;
    default: out = key == "b1" ? "true" : "false"; break;
  }
  return out;
}

}  // namespace rvc::io
