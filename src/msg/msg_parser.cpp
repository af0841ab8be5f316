#include "msg/msg_parser.hpp"

#include "msg/msg_values.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <set>

namespace rvc::msg {

namespace {

struct PrimName {
  const char* name;
  Prim prim;
};
constexpr PrimName kPrims[] = {
    {"bool", Prim::Bool},       {"byte", Prim::Byte},       {"char", Prim::Char},
    {"int8", Prim::Int8},       {"uint8", Prim::UInt8},     {"int16", Prim::Int16},
    {"uint16", Prim::UInt16},   {"int32", Prim::Int32},     {"uint32", Prim::UInt32},
    {"int64", Prim::Int64},     {"uint64", Prim::UInt64},   {"float32", Prim::Float32},
    {"float64", Prim::Float64}, {"string", Prim::String},   {"wstring", Prim::WString},
};

bool is_ident_start(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
bool is_ident(char c) { return is_ident_start(c) || (c >= '0' && c <= '9') || c == '_'; }
bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r'; }

class LineParser {
 public:
  LineParser(std::string_view package, std::string_view line, const std::string& source, int line_no)
      : package_(package), line_(line), source_(source), line_no_(line_no) {}

  [[noreturn]] void fail(size_t pos, const std::string& what) const {
    throw MsgError(source_ + ":" + std::to_string(line_no_) + ":" + std::to_string(pos + 1) + ": " + what);
  }

  // The line without its comment; '#' inside a quoted value is text.
  static std::string_view strip_comment(std::string_view line) {
    char quote = 0;
    for (size_t i = 0; i < line.size(); ++i) {
      char c = line[i];
      if (quote) {
        if (c == '\\') ++i;
        else if (c == quote) quote = 0;
      } else if (c == '"' || c == '\'') {
        quote = c;
      } else if (c == '#') {
        return line.substr(0, i);
      }
    }
    return line;
  }

  void skip_space() {
    while (pos_ < line_.size() && is_space(line_[pos_])) ++pos_;
  }

  uint32_t parse_count(size_t at, std::string_view digits, const char* what) const {
    uint64_t v = 0;
    auto [p, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), v);
    if (digits.empty() || p != digits.data() + digits.size() || (ec != std::errc() && ec != std::errc::result_out_of_range) ||
        (ec == std::errc() && v == 0))
      fail(at, std::string("expected a positive ") + what + ", got '" + std::string(digits) + "'");
    if (ec == std::errc::result_out_of_range || v > kMaxArraySize)
      fail(at, std::string("the ") + what + " " + std::string(digits) + " is over rvc's limit of " +
                   std::to_string(kMaxArraySize) + " (docs/ros2-types.md)");
    return static_cast<uint32_t>(v);
  }

  FieldType parse_type() {
    size_t start = pos_;
    while (pos_ < line_.size() && !is_space(line_[pos_])) ++pos_;
    std::string_view token = line_.substr(start, pos_ - start);
    FieldType t;
    // array suffix
    std::string_view base = token;
    if (size_t open = token.find('['); open != std::string_view::npos) {
      if (token.back() != ']') fail(start + token.size() - 1, "expected ']' to close the array size");
      std::string_view inside = token.substr(open + 1, token.size() - open - 2);
      base = token.substr(0, open);
      if (inside.empty()) {
        t.array = ArrayKind::Unbounded;
      } else if (inside.substr(0, 2) == "<=") {
        t.array = ArrayKind::Bounded;
        t.array_size = parse_count(start + open + 3, inside.substr(2), "array bound");
      } else {
        t.array = ArrayKind::Fixed;
        t.array_size = parse_count(start + open + 1, inside, "array size");
      }
    }
    // bounded string
    if (size_t le = base.find("<="); le != std::string_view::npos) {
      std::string_view b = base.substr(0, le);
      if (b != "string" && b != "wstring") fail(start, "only strings have a bound ('<='): '" + std::string(b) + "'");
      t.string_bound = parse_count(start + le + 2, base.substr(le + 2), "string bound");
      base = b;
    }
    if (base.empty()) fail(start, "expected a type");
    for (const auto& p : kPrims) {
      if (base == p.name) {
        t.prim = p.prim;
        return t;
      }
    }
    t.prim = Prim::Message;
    std::string pkg, name;
    if (base == "time" || base == "duration") {  // ROS 1 built-ins, as rosbags reads them
      t.type_name = std::string("builtin_interfaces/msg/") + (base == "time" ? "Time" : "Duration");
    } else if (base == "Header") {  // ROS 1 shorthand
      t.type_name = "std_msgs/msg/Header";
    } else if (base.find('/') != std::string_view::npos || base.find("::") != std::string_view::npos) {
      std::string kind;
      if (!split_type_name(base, pkg, kind, name)) fail(start, "not a message type name: '" + std::string(base) + "'");
      t.type_name = pkg + "/" + kind + "/" + name;
    } else {
      for (char c : base)
        if (!is_ident(c)) fail(start, "not a type: '" + std::string(base) + "'");
      t.type_name = std::string(package_) + "/msg/" + std::string(base);
    }
    return t;
  }

  std::string parse_name() {
    size_t start = pos_;
    if (pos_ >= line_.size()) fail(pos_, "expected a field name after the type");
    if (!is_ident_start(line_[pos_])) fail(pos_, std::string("a field name starts with a letter, not '") + line_[pos_] + "'");
    while (pos_ < line_.size() && is_ident(line_[pos_])) ++pos_;
    return std::string(line_.substr(start, pos_ - start));
  }

  static std::string unquote(std::string_view v) {
    if (v.size() >= 2 && (v.front() == '"' || v.front() == '\'') && v.back() == v.front()) {
      std::string out;
      for (size_t i = 1; i + 1 < v.size(); ++i) {
        if (v[i] == '\\' && i + 2 < v.size()) ++i;
        out += v[i];
      }
      return out;
    }
    return std::string(v);
  }

  // Returns false for a blank or comment-only line.
  bool parse(MessageType& out, std::set<std::string>& names) {
    line_ = strip_comment(line_);
    skip_space();
    if (pos_ >= line_.size()) return false;
    size_t type_at = pos_;
    FieldType type = parse_type();
    skip_space();
    size_t name_at = pos_;
    std::string name = parse_name();
    skip_space();
    if (!names.insert(name).second) fail(name_at, "'" + name + "' is defined twice");
    if (pos_ < line_.size() && line_[pos_] == '=') {  // constant
      ++pos_;
      skip_space();
      if (type.prim == Prim::Message || type.array != ArrayKind::None)
        fail(type_at, "a constant has a primitive, non-array type");
      size_t value_at = pos_;
      std::string_view raw = line_.substr(pos_);
      while (!raw.empty() && is_space(raw.back())) raw.remove_suffix(1);
      if (raw.empty()) fail(value_at, "expected the value of constant '" + name + "'");
      Constant c;
      c.name = name;
      c.prim = type.prim;
      c.line = line_no_;
      if (type.prim == Prim::String || type.prim == Prim::WString) {
        c.text = unquote(raw);
      } else {
        // As rosidl reads it ("0x10", "+5", "TRUE"); the text kept is the value's JSON
        // ("16", "5", "true"): exact for 64-bit integers, read again by typed specs.
        std::string error;
        if (!rosidl_value(type, raw, c.text, error)) fail(value_at, error);
        c.number = c.text == "true" ? 1 : c.text == "false" ? 0 : std::strtod(c.text.c_str(), nullptr);
      }
      out.constants.push_back(std::move(c));
      return true;
    }
    Field f;
    f.name = std::move(name);
    f.type = std::move(type);
    f.line = line_no_;
    std::string_view rest = line_.substr(pos_);
    while (!rest.empty() && is_space(rest.back())) rest.remove_suffix(1);
    if (!rest.empty()) {
      if (f.type.prim == Prim::Message) fail(pos_, "a field of a message type has no default value");
      std::string error;
      if (!rosidl_value(f.type, rest, f.default_json, error)) fail(pos_, error);
      f.default_text = std::string(rest);
    }
    out.fields.push_back(std::move(f));
    return true;
  }

 private:
  std::string_view package_;
  std::string_view line_;
  const std::string& source_;
  int line_no_;
  size_t pos_ = 0;
};

}  // namespace

bool split_type_name(std::string_view text, std::string& package, std::string& kind, std::string& name) {
  std::vector<std::string_view> parts;
  std::string_view sep = text.find("::") != std::string_view::npos ? "::" : "/";
  size_t start = 0;
  while (true) {
    size_t at = text.find(sep, start);
    parts.push_back(text.substr(start, at == std::string_view::npos ? std::string_view::npos : at - start));
    if (at == std::string_view::npos) break;
    start = at + sep.size();
  }
  // pkg/Name, pkg/msg/Name, pkg::msg::Name, pkg::msg::dds_::Name_ (and srv for msg)
  std::string_view k = "msg";
  if (parts.size() == 4 && (parts[1] == "msg" || parts[1] == "srv") && parts[2] == "dds_" && !parts[3].empty() &&
      parts[3].back() == '_') {
    k = parts[1];
    parts = {parts[0], parts[3].substr(0, parts[3].size() - 1)};
  } else if (parts.size() == 3 && (parts[1] == "msg" || parts[1] == "srv")) {
    k = parts[1];
    parts = {parts[0], parts[2]};
  }
  if (parts.size() != 2) return false;
  for (auto p : parts) {
    if (p.empty() || !is_ident_start(p[0])) return false;
    for (char c : p)
      if (!is_ident(c)) return false;
  }
  package = std::string(parts[0]);
  kind = std::string(k);
  name = std::string(parts[1]);
  return true;
}

bool split_type_name(std::string_view text, std::string& package, std::string& name) {
  std::string kind;
  return split_type_name(text, package, kind, name) && kind == "msg";
}

MessageType parse_msg(std::string_view package, std::string_view name, std::string_view text,
                      const std::string& source) {
  MessageType out;
  out.package = std::string(package);
  out.name = std::string(name);
  out.source = source;
  std::set<std::string> names;
  int line_no = 0;
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    ++line_no;
    LineParser(package, text.substr(start, end - start), source, line_no).parse(out, names);
    start = end + 1;
  }
  return out;
}

}  // namespace rvc::msg
