#include "io/cdr_codec.hpp"

#include <simdjson.h>

#include <algorithm>
#include <cmath>
#include <charconv>
#include <cstring>
#include <limits>

#include "io/cdr_cursor.hpp"
#include "io/json_writer.hpp"

namespace rvc::io {

using msg::ArrayKind;
using msg::Field;
using msg::FieldType;
using msg::MessageType;
using msg::Prim;

namespace {

constexpr size_t kHeader = 4;

template <typename T>
T byteswap(T v) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  std::memcpy(&v, b, sizeof(T));
  return v;
}

constexpr bool kHostLittle = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

// Floats as the JSON writer prints them, but -0.0 keeps its sign and NaN and
// the infinities are the bare words NaN, Infinity and -Infinity (as Python's
// json module writes and reads them, and rvc's JSON readers accept): a sample
// decoded and encoded again gives back the same bytes (a NaN's sign and
// payload aside), and `rvc check` on `rvc echo` output gives the typed verdicts.
void append_float(std::string& out, double v) {
  if (v == 0 && std::signbit(v)) out += "-0.0";
  else if (!std::isfinite(v)) out += non_finite_word(v);
  else append_number(out, v);
}

// simdjson's DOM refuses the words NaN, Infinity and -Infinity: outside
// strings they become strings no field can hold (a NUL first), which
// Writer::floating reads back as the numbers. False when there are none.
constexpr std::string_view kNonFinite[] = {"NaN", "Infinity", "-Infinity"};
constexpr std::string_view kNonFiniteSentinel[] = {"\"\\u0000NaN\"", "\"\\u0000Infinity\"", "\"\\u0000-Infinity\""};

bool non_finite_as_strings(std::string_view json, std::string& out) {
  out.clear();
  bool found = false, in_string = false;
  for (size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    if (in_string) {
      out += c;
      if (c == '\\' && i + 1 < json.size()) out += json[++i];  // an escape: the next byte cannot end the string
      else if (c == '"') in_string = false;
      continue;
    }
    bool replaced = false;
    for (size_t k = 0; k < 3 && !replaced; ++k) {
      if (json.substr(i, kNonFinite[k].size()) != kNonFinite[k]) continue;
      out += kNonFiniteSentinel[k];
      i += kNonFinite[k].size() - 1;
      replaced = found = true;
    }
    if (replaced) continue;
    out += c;
    in_string = c == '"';
  }
  return found;
}

// The number a sentinel string stands for, or false.
bool sentinel_number(simdjson::dom::element v, double& d) {
  std::string_view s;
  if (v.get(s) != simdjson::SUCCESS || s.empty() || s[0] != '\0') return false;
  if (s.substr(1) == "NaN") return d = std::numeric_limits<double>::quiet_NaN(), true;
  if (s.substr(1) == "Infinity") return d = std::numeric_limits<double>::infinity(), true;
  if (s.substr(1) == "-Infinity") return d = -std::numeric_limits<double>::infinity(), true;
  return false;
}

// A value for an error message: a sentinel as the word it was.
std::string shown(simdjson::dom::element v) {
  std::string_view s;
  if (v.get(s) == simdjson::SUCCESS && !s.empty() && s[0] == '\0') return std::string(s.substr(1));
  return simdjson::to_string(v);
}

// Parses JSON text that may hold NaN, Infinity, -Infinity.
simdjson::error_code parse_json(simdjson::dom::parser& parser, std::string_view json, std::string& scratch,
                                simdjson::dom::element& doc) {
  auto e = parser.parse(json.data(), json.size()).get(doc);
  if (e == simdjson::SUCCESS || !non_finite_as_strings(json, scratch)) return e;
  return parser.parse(scratch).get(doc);
}

// ------------------------------------------------------------------ decoding

class Reader {
 public:
  Reader(std::string& out, CdrCursor& in) : in_(in), out_(out) {}

  // `select`: the fields to write (null: all). Unselected fields are read
  // and checked with emit_ off.
  bool message(const MessageType& type, const CdrSelection* select = nullptr) {
    if (type.fields.empty()) {  // an empty message is one uint8 on the wire
      uint8_t ignored;
      if (!in_.read(ignored)) return false;
      put("{}");
      return true;
    }
    put('{');
    bool first = true;
    const bool emitting = emit_;
    for (const Field& f : type.fields) {
      const CdrSelection* below = nullptr;
      if (emitting && select && !select->all()) {
        below = select->find(f.name);
        emit_ = below != nullptr;
      }
      if (emit_) {
        if (!first) out_ += ',';
        first = false;
        // Field names are identifiers (the .msg parser checks): no escaping needed.
        out_ += '"';
        out_ += f.name;
        out_ += "\":";
      }
      in_.push(&f.name);
      if (!(f.type.prim == Prim::Message && f.type.array == ArrayKind::None ? message(*f.type.message, below)
                                                                             : field(f.type)))
        return false;
      in_.pop();
      emit_ = emitting;
    }
    put('}');
    return true;
  }

 private:
  void put(char c) {
    if (emit_) out_ += c;
  }
  void put(std::string_view text) {
    if (emit_) out_ += text;
  }

  template <typename T>
  bool integer() {
    T v{};
    if (!in_.read(v)) return false;
    if (!emit_) return true;
    char buf[24];
    auto [end, ec] = std::to_chars(buf, buf + sizeof buf, v);
    out_.append(buf, end);
    return true;
  }

  bool scalar(const FieldType& t) {
    switch (t.prim) {
      case Prim::Bool: {
        bool v = false;
        if (!in_.boolean(v)) return false;
        put(v ? "true" : "false");
        return true;
      }
      case Prim::Byte: case Prim::Char: case Prim::UInt8: return integer<uint8_t>();
      case Prim::Int8: return integer<int8_t>();
      case Prim::Int16: return integer<int16_t>();
      case Prim::UInt16: return integer<uint16_t>();
      case Prim::Int32: return integer<int32_t>();
      case Prim::UInt32: return integer<uint32_t>();
      case Prim::Int64: return integer<int64_t>();
      case Prim::UInt64: return integer<uint64_t>();
      case Prim::Float32: {
        float v;
        if (!in_.read(v)) return false;
        if (emit_) append_float(out_, static_cast<double>(v));
        return true;
      }
      case Prim::Float64: {
        double v;
        if (!in_.read(v)) return false;
        if (emit_) append_float(out_, v);
        return true;
      }
      case Prim::String: {
        std::string_view text;
        if (!in_.string(text, t.string_bound)) return false;
        if (emit_) append_json_string(out_, text);
        return true;
      }
      case Prim::WString: return in_.fail("wstring fields are not supported");
      case Prim::Message: return message(*t.message);
    }
    return in_.fail("unknown type");
  }

  bool field(const FieldType& t) {
    if (t.array == ArrayKind::None) return scalar(t);
    uint32_t n = t.array_size;
    if (t.array == ArrayKind::Unbounded && !in_.count(n, cdr_min_size(t))) return false;
    if (t.array == ArrayKind::Bounded && !in_.count(n, cdr_min_size(t), t.array_size)) return false;
    put('[');
    for (uint32_t i = 0; i < n; ++i) {
      if (i) put(',');
      in_.push_index(i);
      if (!scalar(t)) return false;
      in_.pop();
    }
    put(']');
    return true;
  }

  CdrCursor& in_;
  std::string& out_;
  bool emit_ = true;  // write what is read (off inside fields no one selected)
};

// ------------------------------------------------------------------ encoding

class Writer {
 public:
  Writer(std::string& out, bool big_endian, std::string& error)
      : out_(out), swap_(big_endian == kHostLittle), error_(error) {}

  bool message(const MessageType& type, simdjson::dom::element value, bool present) {
    simdjson::dom::object obj;
    if (present) {
      if (value.get(obj) != simdjson::SUCCESS) return fail("expected an object for " + type.full_name());
      for (auto member : obj) {  // every key must be a field
        bool known = false;
        for (const Field& f : type.fields) known = known || f.name == member.key;
        if (!known) return fail("unknown field '" + std::string(member.key) + "' (not in " + type.full_name() + ")");
      }
    }
    if (type.fields.empty()) {
      put<uint8_t>(0);
      return true;
    }
    for (const Field& f : type.fields) {
      size_t path_size = path_.size();
      if (!path_.empty()) path_ += '.';
      path_ += f.name;
      simdjson::dom::element v;
      bool has = present && obj[f.name].get(v) == simdjson::SUCCESS;
      if (!has && !f.default_json.empty()) {
        if (!default_doc(f, v)) return false;
        has = true;
      }
      if (!field(f.type, v, has)) return false;
      path_.resize(path_size);
    }
    return true;
  }

 private:
  bool fail(const std::string& what) {
    error_ = path_.empty() ? what : "field " + path_ + ": " + what;
    return false;
  }

  // The .msg default of a field: its JSON text as the parser read it the rosidl way
  // (msg/msg_values.hpp: "1.5", "true", "\"text\"", "[16,5]", "NaN").
  bool default_doc(const Field& f, simdjson::dom::element& v) {
    defaults_.push_back(std::make_unique<simdjson::dom::parser>());
    std::string scratch;
    if (parse_json(*defaults_.back(), f.default_json, scratch, v) == simdjson::SUCCESS) return true;
    return fail("its default " + f.default_text + " does not read as JSON");  // the parser wrote it: never
  }

  void align(size_t n) {
    while ((out_.size() - kHeader) % n) out_.push_back('\0');
  }

  template <typename T>
  void put(T v) {
    align(sizeof(T));
    if (swap_ && sizeof(T) > 1) v = byteswap(v);
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    out_.append(b, sizeof(T));
  }

  template <typename T>
  bool integer(simdjson::dom::element v, bool has) {
    if (!has) {
      put<T>(0);
      return true;
    }
    int64_t i;
    uint64_t u;
    double d;
    if (v.get(i) == simdjson::SUCCESS) {
      if constexpr (std::is_signed_v<T>) {
        if (i < std::numeric_limits<T>::min() || i > std::numeric_limits<T>::max()) return range(v);
      } else {
        if (i < 0 || static_cast<uint64_t>(i) > std::numeric_limits<T>::max()) return range(v);
      }
      put<T>(static_cast<T>(i));
      return true;
    }
    if (v.get(u) == simdjson::SUCCESS) {
      if (u > static_cast<uint64_t>(std::numeric_limits<T>::max())) return range(v);
      put<T>(static_cast<T>(u));
      return true;
    }
    if (v.get(d) == simdjson::SUCCESS) return fail("expected an integer, got " + simdjson::to_string(v));
    if (v.is_bool()) return fail("expected an integer, got a bool");
    return fail("expected an integer, got " + shown(v));
  }

  bool range(simdjson::dom::element v) { return fail(simdjson::to_string(v) + " is out of range"); }

  template <typename T>
  bool floating(simdjson::dom::element v, bool has) {
    double d = 0;
    if (has) {
      // NaN, Infinity, -Infinity (as cdr_to_json writes them); null as NaN (as it wrote them before).
      if (v.is_null()) d = std::numeric_limits<double>::quiet_NaN();
      else if (!sentinel_number(v, d) && v.get(d) != simdjson::SUCCESS) return fail("expected a number, got " + shown(v));
    }
    put<T>(static_cast<T>(d));
    return true;
  }

  bool scalar(const FieldType& t, simdjson::dom::element v, bool has) {
    switch (t.prim) {
      case Prim::Bool: {
        bool b = false;
        if (has && v.get(b) != simdjson::SUCCESS) return fail("expected true or false, got " + shown(v));
        put<uint8_t>(b ? 1 : 0);
        return true;
      }
      case Prim::Byte: case Prim::Char: case Prim::UInt8: return integer<uint8_t>(v, has);
      case Prim::Int8: return integer<int8_t>(v, has);
      case Prim::Int16: return integer<int16_t>(v, has);
      case Prim::UInt16: return integer<uint16_t>(v, has);
      case Prim::Int32: return integer<int32_t>(v, has);
      case Prim::UInt32: return integer<uint32_t>(v, has);
      case Prim::Int64: return integer<int64_t>(v, has);
      case Prim::UInt64: return integer<uint64_t>(v, has);
      case Prim::Float32: return floating<float>(v, has);
      case Prim::Float64: return floating<double>(v, has);
      case Prim::String: {
        std::string_view s;
        if (has && v.get(s) != simdjson::SUCCESS) return fail("expected a string, got " + simdjson::to_string(v));
        if (double ignored; has && sentinel_number(v, ignored)) return fail("expected a string, got " + shown(v));
        if (s.find('\0') != std::string_view::npos) return fail("a string cannot hold a NUL");
        if (t.string_bound && s.size() > t.string_bound)
          return fail("string of " + std::to_string(s.size()) + " bytes over its bound " + std::to_string(t.string_bound));
        put<uint32_t>(static_cast<uint32_t>(s.size() + 1));
        out_.append(s.data(), s.size());
        out_.push_back('\0');
        return true;
      }
      case Prim::WString: return fail("wstring fields are not supported");
      case Prim::Message: return message(*t.message, v, has);
    }
    return fail("unknown type");
  }

  bool field(const FieldType& t, simdjson::dom::element v, bool has) {
    if (t.array == ArrayKind::None) return scalar(t, v, has);
    simdjson::dom::array arr;
    size_t n = 0;
    if (has) {
      if (v.get(arr) != simdjson::SUCCESS) return fail("expected an array, got " + simdjson::to_string(v));
      n = arr.size();
    }
    if (t.array == ArrayKind::Fixed) {
      if (has && n != t.array_size)
        return fail("expected " + std::to_string(t.array_size) + " elements, got " + std::to_string(n));
      n = t.array_size;
    } else {
      if (t.array == ArrayKind::Bounded && n > t.array_size)
        return fail(std::to_string(n) + " elements over the bound " + std::to_string(t.array_size));
      put<uint32_t>(static_cast<uint32_t>(n));
    }
    size_t path_size = path_.size();
    size_t i = 0;
    if (has) {
      for (auto e : arr) {
        path_ += '[' + std::to_string(i++) + ']';
        if (!scalar(t, e, true)) return false;
        path_.resize(path_size);
      }
    } else {
      for (; i < n; ++i)
        if (!scalar(t, simdjson::dom::element(), false)) return false;
    }
    return true;
  }

  std::string& out_;
  bool swap_;
  std::string& error_;
  std::string path_;
  std::vector<std::unique_ptr<simdjson::dom::parser>> defaults_;
};

}  // namespace

void CdrSelection::add(const std::vector<std::string>& path) {
  CdrSelection* node = this;
  for (const std::string& name : path) {
    if (node->all_) return;
    CdrSelection* next = nullptr;
    for (auto& [n, child] : node->children_)
      if (n == name) next = &child;
    if (!next) {
      node->children_.emplace_back(name, CdrSelection());
      next = &node->children_.back().second;
    }
    node = next;
  }
  node->all_ = true;  // the path ends here: all of it
  node->children_.clear();
}

const CdrSelection* CdrSelection::find(const std::string& name) const {
  for (const auto& [n, child] : children_)
    if (n == name) return &child;
  return nullptr;
}

bool cdr_to_json(const MessageType& type, std::string_view sample, std::string& out, CdrError& error,
                 const CdrSelection* select) {
  CdrCursor in(error);
  if (!in.open(sample)) return false;
  Reader r(out, in);
  return r.message(type, select) && in.finish();
}

bool json_to_cdr(const MessageType& type, std::string_view json, std::string& sample, std::string& error,
                 const CdrWriteOptions& options) {
  simdjson::dom::parser parser;
  simdjson::dom::element doc;
  std::string scratch;
  if (auto e = parse_json(parser, json, scratch, doc); e != simdjson::SUCCESS) {
    error = std::string("not JSON: ") + simdjson::error_message(e);
    // simdjson's DOM refuses integer literals of 20 digits or more.
    if (e == simdjson::NUMBER_ERROR) error += " (write integers beyond 2^64 in exponent form, e.g. 5.9e+20)";
    return false;
  }
  sample.assign({'\0', options.big_endian ? '\0' : '\1', '\0', '\0'});
  Writer w(sample, options.big_endian, error);
  return w.message(type, doc, true);
}

}  // namespace rvc::io
