#include "msg/idl_parser.hpp"

#include "msg/msg_values.hpp"

#include <cctype>
#include <charconv>
#include <map>
#include <set>

namespace rvc::msg {

namespace {

struct Token {
  enum Kind { Ident, Number, String, Char, Punct, End } kind = End;
  std::string text;
  int line = 0, col = 0;
};

// Splits IDL text into tokens; comments and preprocessor lines are dropped.
class Lexer {
 public:
  Lexer(std::string_view text, const std::string& source) : text_(text), source_(source) {}

  // "#pragma keylist Type key1 key2": the keys of Type (the older DDS way to write @key).
  struct Keylist {
    std::string type;
    std::vector<std::string> keys;
    int line = 0;
  };
  std::vector<Keylist> keylists;

  std::vector<Token> run() {
    std::vector<Token> out;
    bool line_start = true;
    while (i_ < text_.size()) {
      char c = text_[i_];
      if (c == '\n') {
        advance();
        line_start = true;
        continue;
      }
      if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
        advance();
        continue;
      }
      if (c == '#' && line_start) {  // #include, #pragma keylist, ...: a line of its own
        size_t from = i_;
        int line = line_;
        while (i_ < text_.size() && text_[i_] != '\n') advance();
        pragma(text_.substr(from, i_ - from), line);
        continue;
      }
      line_start = false;
      if (c == '/' && peek(1) == '/') {
        while (i_ < text_.size() && text_[i_] != '\n') advance();
        continue;
      }
      if (c == '/' && peek(1) == '*') {
        int line = line_, col = col_;
        advance(), advance();
        while (i_ < text_.size() && !(text_[i_] == '*' && peek(1) == '/')) advance();
        if (i_ >= text_.size()) fail(line, col, "comment not closed ('*/' missing)");
        advance(), advance();
        continue;
      }
      Token t;
      t.line = line_;
      t.col = col_;
      if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
        t.kind = Token::Ident;
        while (i_ < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[i_])) || text_[i_] == '_'))
          t.text += take();
      } else if (std::isdigit(static_cast<unsigned char>(c)) || (c == '.' && std::isdigit(static_cast<unsigned char>(peek(1))))) {
        t.kind = Token::Number;
        while (i_ < text_.size()) {
          char d = text_[i_];
          bool exp_sign = (d == '+' || d == '-') && !t.text.empty() && (t.text.back() == 'e' || t.text.back() == 'E') &&
                          t.text.rfind("0x", 0) != 0;
          if (!(std::isalnum(static_cast<unsigned char>(d)) || d == '.' || exp_sign)) break;
          t.text += take();
        }
      } else if (c == '"' || c == '\'') {
        t.kind = c == '"' ? Token::String : Token::Char;
        advance();
        while (i_ < text_.size() && text_[i_] != c && text_[i_] != '\n') {
          if (text_[i_] == '\\' && i_ + 1 < text_.size()) {
            advance();
            char e = take();
            t.text += e == 'n' ? '\n' : e == 't' ? '\t' : e;
          } else {
            t.text += take();
          }
        }
        if (i_ >= text_.size() || text_[i_] != c) fail(t.line, t.col, "literal not closed");
        advance();
      } else if (c == ':' && peek(1) == ':') {
        t.kind = Token::Punct;
        t.text = "::";
        advance(), advance();
      } else {
        t.kind = Token::Punct;
        t.text = std::string(1, take());
      }
      out.push_back(std::move(t));
    }
    Token end;
    end.line = line_;
    end.col = col_;
    out.push_back(end);
    return out;
  }

 private:
  void pragma(std::string_view line, int line_no) {
    std::vector<std::string> words;
    std::string word;
    for (char c : line.substr(1)) {
      if (c == ' ' || c == '\t' || c == '\r' || c == ',') {
        if (!word.empty()) words.push_back(std::move(word));
        word.clear();
      } else {
        word += c;
      }
    }
    if (!word.empty()) words.push_back(std::move(word));
    if (words.size() >= 3 && words[0] == "pragma" && words[1] == "keylist")
      keylists.push_back({words[2], std::vector<std::string>(words.begin() + 3, words.end()), line_no});
  }
  char peek(size_t ahead) const { return i_ + ahead < text_.size() ? text_[i_ + ahead] : '\0'; }
  void advance() {
    if (text_[i_] == '\n') {
      ++line_;
      col_ = 1;
    } else {
      ++col_;
    }
    ++i_;
  }
  char take() {
    char c = text_[i_];
    advance();
    return c;
  }
  [[noreturn]] void fail(int line, int col, const std::string& what) const {
    throw MsgError(source_ + ":" + std::to_string(line) + ":" + std::to_string(col) + ": " + what);
  }

  std::string_view text_;
  const std::string& source_;
  size_t i_ = 0;
  int line_ = 1, col_ = 1;
};

struct Annotation {
  std::string name;                          // "key", "default", "verbatim", ...
  std::map<std::string, std::string> params;  // value=..., or "" for a single unnamed value
};

std::string join(const std::vector<std::string>& parts, size_t n, const std::string& sep) {
  std::string out;
  for (size_t i = 0; i < n && i < parts.size(); ++i) out += (i ? sep : "") + parts[i];
  return out;
}

class Parser {
 public:
  Parser(std::vector<Token> tokens, const std::string& source) : t_(std::move(tokens)), source_(source) {}

  std::vector<MessageType> run() {
    while (!at_end()) definition();
    // Constants: a ROS 2 struct's `Name_Constants` module, and for plain IDL
    // the constants of the module the struct is declared in.
    for (size_t i = 0; i < out_.size(); ++i) {
      const std::string& scope = struct_scope_[i];
      auto add = [&](const std::string& key) {
        auto it = constants_.find(key);
        if (it == constants_.end()) return;
        for (const auto& c : it->second)
          if (!out_[i].constant(c.name)) out_[i].constants.push_back(c);
      };
      add((scope.empty() ? "" : scope + "::") + out_[i].name + "_Constants");
      add(scope);
    }
    return std::move(out_);
  }

 private:
  // --- tokens ---
  const Token& cur() const { return t_[p_]; }
  bool at_end() const { return cur().kind == Token::End; }
  bool is(const char* text) const { return cur().kind != Token::String && cur().kind != Token::Char && cur().text == text; }
  bool accept(const char* text) {
    if (!is(text)) return false;
    ++p_;
    return true;
  }
  [[noreturn]] void fail(const Token& at, const std::string& what) const {
    throw MsgError(source_ + ":" + std::to_string(at.line) + ":" + std::to_string(at.col) + ": " + what);
  }
  std::string describe(const Token& t) const { return t.kind == Token::End ? "the end of the file" : "'" + t.text + "'"; }
  void expect(const char* text) {
    if (!accept(text)) fail(cur(), std::string("expected '") + text + "', got " + describe(cur()));
  }
  std::string ident(const char* what) {
    if (cur().kind != Token::Ident) fail(cur(), std::string("expected ") + what + ", got " + describe(cur()));
    return t_[p_++].text;
  }
  // a, a::b, ::a::b (the leading '::' is dropped: names are resolved from the top anyway)
  std::string scoped_name(const char* what) {
    accept("::");
    std::string name = ident(what);
    while (accept("::")) name += "::" + ident(what);
    return name;
  }

  // --- annotations ---
  std::vector<Annotation> annotations() {
    std::vector<Annotation> out;
    while (accept("@")) {
      Annotation a;
      a.name = scoped_name("an annotation name");
      if (accept("(")) {
        std::string key, value;
        int depth = 0;
        auto flush = [&] {
          if (!value.empty() || !key.empty()) a.params[key] = value;
          key.clear();
          value.clear();
        };
        while (!(depth == 0 && is(")"))) {
          if (at_end()) fail(cur(), "annotation @" + a.name + " not closed (')' missing)");
          const Token& tok = t_[p_++];
          if (tok.kind == Token::Punct && tok.text == "(") ++depth;
          if (tok.kind == Token::Punct && tok.text == ")") --depth;
          if (depth == 0 && tok.kind == Token::Punct && tok.text == ",") {
            flush();
          } else if (depth == 0 && tok.kind == Token::Punct && tok.text == "=" && key.empty()) {
            key = value;
            value.clear();
          } else if (tok.kind == Token::String) {
            value += "\"" + tok.text + "\"";
          } else {
            value += tok.text;
          }
        }
        expect(")");
        flush();
      }
      out.push_back(std::move(a));
    }
    return out;
  }

  // --- definitions ---
  void definition() {
    annotations();
    const Token& at = cur();
    if (accept("module")) {
      // Definitions nest by recursion: a bound keeps hostile input from exhausting the stack.
      if (scope_.size() >= 64) fail(at, "modules nested deeper than 64 levels");
      scope_.push_back(ident("a module name"));
      expect("{");
      while (!is("}")) {
        if (at_end()) fail(cur(), "module " + scope_.back() + " not closed ('}' missing)");
        definition();
      }
      expect("}");
      expect(";");
      scope_.pop_back();
    } else if (accept("struct")) {
      structure();
    } else if (accept("typedef")) {
      typedef_();
    } else if (accept("const")) {
      constant();
    } else if (accept("enum")) {
      enumeration();
    } else if (is("union") || is("interface") || is("valuetype") || is("exception") || is("bitset") ||
               is("bitmask") || is("native")) {
      fail(at, "'" + at.text + "' definitions are not supported (rvc reads structs, typedefs, enums and constants)");
    } else if (accept(";")) {
    } else {
      fail(at, "expected a definition (module, struct, typedef, const, enum), got " + describe(at));
    }
  }

  std::string scoped(const std::string& name) const {
    return scope_.empty() ? name : join(scope_, scope_.size(), "::") + "::" + name;
  }
  // ROS 2 IDL: module pkg { module msg { ... } } (or srv, for the structs of a service)
  bool ros_scope() const { return scope_.size() == 2 && (scope_[1] == "msg" || scope_[1] == "srv"); }

  void structure() {
    const Token& name_at = cur();
    std::string name = ident("a struct name");
    if (accept(";")) return;  // forward declaration
    if (is(":")) fail(cur(), "struct inheritance is not supported: write the base's members into " + name);
    expect("{");
    MessageType m;
    m.name = name;
    m.source = source_;
    if (ros_scope()) {
      m.package = scope_[0];
      m.kind = scope_[1];
    } else {
      m.package = scope_.empty() ? "" : scope_[0];
      m.idl_name = scoped(name);
    }
    std::string key = m.full_name();
    if (structs_.count(scoped(name)) || types_.count(scoped(name)))
      fail(name_at, "'" + scoped(name) + "' is defined twice");
    std::set<std::string> names;
    while (!accept("}")) {
      if (at_end()) fail(cur(), "struct " + name + " not closed ('}' missing)");
      member(m, names);
    }
    expect(";");
    structs_[scoped(name)] = key;
    struct_scope_.push_back(join(scope_, scope_.size(), "::"));
    out_.push_back(std::move(m));
  }

  void member(MessageType& m, std::set<std::string>& names) {
    std::vector<Annotation> notes = annotations();
    const Token& type_at = cur();
    FieldType type = type_spec();
    std::vector<Constant> enum_constants = last_enum_constants_;
    do {
      const Token& name_at = cur();
      Field f;
      f.name = ident("a member name");
      f.type = type;
      f.line = name_at.line;
      if (!names.insert(f.name).second) fail(name_at, "'" + f.name + "' is defined twice in " + m.name);
      if (is("[")) {
        if (f.type.array != ArrayKind::None)
          fail(cur(), "'" + f.name + "': an array of a sequence or of an array typedef is not supported");
        f.type.array = ArrayKind::Fixed;
        f.type.array_size = array_size();
        if (is("[")) fail(cur(), "'" + f.name + "': multi-dimensional arrays are not supported");
      }
      for (const auto& a : notes) {
        if (a.name == "key" && (a.params.empty() || a.params.begin()->second != "FALSE")) m.keys.push_back(f.name);
        if (a.name != "default") continue;
        auto v = a.params.count("value") ? a.params.at("value") : a.params.count("") ? a.params.at("") : "";
        if (f.type.prim == Prim::Message) fail(type_at, "'" + f.name + "': a member of a struct type has no @default");
        std::string error;
        if (!rosidl_value(f.type, v, f.default_json, error)) fail(name_at, "'" + f.name + "': @default: " + error);
        f.default_text = v;
      }
      m.fields.push_back(std::move(f));
    } while (accept(","));
    expect(";");
    for (const auto& c : enum_constants)  // an enum's values name its values in specs: {state == MRM}
      if (!m.constant(c.name)) m.constants.push_back(c);
  }

  uint32_t array_size() {
    expect("[");
    const Token& at = cur();
    double v = const_number(Prim::UInt32);
    if (v < 1) fail(at, "an array size is positive");
    limit(at, v, "array size");
    expect("]");
    return static_cast<uint32_t>(v);
  }

  void limit(const Token& at, double size, const char* what) {
    if (size > kMaxArraySize)
      fail(at, std::string("the ") + what + " " + std::to_string(static_cast<uint64_t>(size)) + " is over rvc's limit of " +
                   std::to_string(kMaxArraySize) + " (docs/ros2-types.md)");
  }

  // A type specifier: primitive, string<N>, sequence<T, N>, or a scoped name.
  FieldType type_spec() {
    last_enum_constants_.clear();
    const Token& at = cur();
    FieldType t;
    if (accept("sequence")) {
      expect("<");
      // Refused before recursing, so sequence<sequence<... cannot exhaust the stack.
      if (is("sequence")) fail(at, "sequences of sequences or of arrays are not supported");
      FieldType inner = type_spec();
      if (inner.array != ArrayKind::None)
        fail(at, "sequences of sequences or of arrays are not supported");
      inner.array = ArrayKind::Unbounded;
      if (accept(",")) {
        inner.array = ArrayKind::Bounded;
        const Token& bound_at = cur();
        inner.array_size = static_cast<uint32_t>(const_number(Prim::UInt32));
        if (inner.array_size == 0) fail(at, "a sequence bound is positive");
        limit(bound_at, inner.array_size, "sequence bound");
      }
      expect(">");
      return inner;
    }
    if (is("string") || is("wstring")) {
      t.prim = cur().text == "string" ? Prim::String : Prim::WString;
      ++p_;
      if (accept("<")) {
        const Token& bound_at = cur();
        t.string_bound = static_cast<uint32_t>(const_number(Prim::UInt32));
        if (t.string_bound == 0) fail(at, "a string bound is positive");
        limit(bound_at, t.string_bound, "string bound");
        expect(">");
      }
      return t;
    }
    if (accept("unsigned")) {
      if (accept("short")) return t.prim = Prim::UInt16, t;
      if (accept("long")) return t.prim = accept("long") ? Prim::UInt64 : Prim::UInt32, t;
      fail(cur(), "expected 'short' or 'long' after 'unsigned'");
    }
    if (accept("long")) {
      if (accept("double")) fail(at, "long double is not supported (no ROS 2 or CDR mapping rvc reads)");
      return t.prim = accept("long") ? Prim::Int64 : Prim::Int32, t;
    }
    // IDL char is a C char (signed, as idlc flags it); rosidl writes a .msg char as uint8.
    static const std::map<std::string, Prim> kPrims = {
        {"boolean", Prim::Bool},  {"octet", Prim::Byte},    {"char", Prim::Int8},      {"short", Prim::Int16},
        {"int8", Prim::Int8},     {"uint8", Prim::UInt8},   {"int16", Prim::Int16},    {"uint16", Prim::UInt16},
        {"int32", Prim::Int32},   {"uint32", Prim::UInt32}, {"int64", Prim::Int64},    {"uint64", Prim::UInt64},
        {"float", Prim::Float32}, {"double", Prim::Float64}};
    if (cur().kind == Token::Ident) {
      auto it = kPrims.find(cur().text);
      if (it != kPrims.end()) {
        ++p_;
        return t.prim = it->second, t;
      }
      if (is("wchar") || is("any") || is("fixed") || is("map"))
        fail(at, "'" + at.text + "' is not supported (no ROS 2 mapping rvc reads)");
    }
    std::string name = scoped_name("a type");
    // Innermost scope first, as IDL resolves names.
    for (size_t n = scope_.size() + 1; n-- > 0;) {
      std::string candidate = n ? join(scope_, n, "::") + "::" + name : name;
      if (auto a = types_.find(candidate); a != types_.end()) {
        auto e = enum_values_.find(candidate);
        last_enum_constants_ = e == enum_values_.end() ? std::vector<Constant>{} : e->second;
        return a->second;
      }
      if (auto s = structs_.find(candidate); s != structs_.end()) {
        t.prim = Prim::Message;
        t.type_name = s->second;
        return t;
      }
    }
    // Defined elsewhere (another file, a bag's other schema): ROS 2 pkg::msg::Name
    // or a plain scoped name, found by the registry.
    t.prim = Prim::Message;
    size_t msg = name.find("::msg::");
    if (msg == std::string::npos) msg = name.find("::srv::");
    if (msg != std::string::npos && name.find("::", msg + 7) == std::string::npos)
      t.type_name = name.substr(0, msg) + "/" + name.substr(msg + 2, 3) + "/" + name.substr(msg + 7);
    else
      t.type_name = name;
    return t;
  }

  void typedef_() {
    FieldType type = type_spec();
    do {
      std::string name = ident("a typedef name");
      FieldType t = type;
      if (is("[")) {
        if (t.array != ArrayKind::None) fail(cur(), "'" + name + "': an array of a sequence is not supported");
        t.array = ArrayKind::Fixed;
        t.array_size = array_size();
        if (is("[")) fail(cur(), "'" + name + "': multi-dimensional arrays are not supported");
      }
      types_[scoped(name)] = t;
      if (!last_enum_constants_.empty()) enum_values_[scoped(name)] = last_enum_constants_;
    } while (accept(","));
    expect(";");
  }

  void enumeration() {
    std::string name = ident("an enum name");
    expect("{");
    std::vector<Constant> values;
    double next = 0;
    do {
      std::vector<Annotation> notes = annotations();
      const Token& at = cur();
      Constant c;
      c.name = ident("an enumerator");
      for (const auto& a : notes)
        if (a.name == "value" && !a.params.empty()) {
          std::string error;
          if (!prim_value(Prim::UInt32, a.params.begin()->second, next, error)) fail(at, error);
        }
      c.prim = Prim::UInt32;
      c.number = next++;
      c.text = std::to_string(static_cast<uint64_t>(c.number));
      c.line = at.line;
      values.push_back(std::move(c));
    } while (accept(","));
    expect("}");
    expect(";");
    FieldType t;
    t.prim = Prim::UInt32;  // XCDR1 writes an enum as 32 bits
    types_[scoped(name)] = t;
    enum_values_[scoped(name)] = values;
    for (auto& c : values) constants_[join(scope_, scope_.size(), "::")].push_back(c);
  }

  void constant() {
    FieldType type = type_spec();
    if (type.array != ArrayKind::None || type.prim == Prim::Message)
      fail(cur(), "a constant has a primitive or string type");
    const Token& name_at = cur();
    Constant c;
    c.name = ident("a constant name");
    c.prim = type.prim;
    c.line = name_at.line;
    expect("=");
    const Token& value_at = cur();
    if (type.prim == Prim::String || type.prim == Prim::WString) {
      if (cur().kind != Token::String) fail(value_at, "expected a string literal for " + c.name);
      c.text = t_[p_++].text;
    } else {
      c.number = const_number(type.prim, &c.text);
    }
    expect(";");
    std::string scope = join(scope_, scope_.size(), "::");
    constant_values_[scoped(c.name)] = c;
    constants_[scope].push_back(std::move(c));
  }

  // "0x1F" / "-0x1F" as decimal text; a malformed or out-of-range literal is
  // an error at its position (std::stoll would throw past the parser).
  std::string hex_value(const Token& at, const std::string& literal) {
    const bool negative = !literal.empty() && literal[0] == '-';
    const size_t x = literal.find_first_of("xX");
    const char* first = literal.data() + x + 1;
    const char* last = literal.data() + literal.size();
    unsigned long long magnitude = 0;
    auto [end, ec] = std::from_chars(first, last, magnitude, 16);
    if (x != (negative ? 2u : 1u) || literal[x - 1] != '0' || first == last || end != last)
      fail(at, "malformed hexadecimal literal '" + literal + "'");
    if (ec == std::errc::result_out_of_range || magnitude > (negative ? 1ull << 63 : ~0ull))
      fail(at, "hexadecimal literal '" + literal + "' does not fit in 64 bits");
    return negative ? "-" + std::to_string(magnitude) : std::to_string(magnitude);
  }

  // A constant expression: a literal, TRUE/FALSE, an earlier constant, with
  // an optional sign. (No arithmetic: rosidl and DDS data types need none.)
  double const_number(Prim prim, std::string* text = nullptr) {
    const Token& at = cur();
    std::string sign;
    if (accept("-")) sign = "-";
    else accept("+");
    std::string value;
    if (cur().kind == Token::Number) {
      value = sign + t_[p_++].text;
      if (value.find("0x") != std::string::npos || value.find("0X") != std::string::npos)
        value = hex_value(at, value);
      else if (!value.empty() && (value.back() == 'd' || value.back() == 'D'))
        value.pop_back();  // fixed-point suffix
    } else if (cur().kind == Token::Char) {
      value = std::to_string(static_cast<unsigned char>(t_[p_++].text.c_str()[0]));
    } else if (is("TRUE") || is("FALSE")) {
      value = t_[p_++].text;
    } else if (cur().kind == Token::Ident || is("::")) {
      std::string name = scoped_name("a value");
      const Constant* c = nullptr;
      for (size_t n = scope_.size() + 1; n-- > 0 && !c;) {
        auto it = constant_values_.find(n ? join(scope_, n, "::") + "::" + name : name);
        if (it != constant_values_.end()) c = &it->second;
      }
      if (!c) fail(at, "unknown constant '" + name + "'");
      value = sign == "-" ? (c->text[0] == '-' ? c->text.substr(1) : "-" + c->text) : c->text;
    } else {
      fail(at, "expected a value, got " + describe(at));
    }
    double v = 0;
    std::string error;
    if (!prim_value(prim, value, v, error)) fail(at, error);
    if (text) *text = value;
    return v;
  }

  std::vector<Token> t_;
  size_t p_ = 0;
  const std::string& source_;
  std::vector<std::string> scope_;
  std::vector<MessageType> out_;
  std::vector<std::string> struct_scope_;                        // per out_ entry: its module path
  std::map<std::string, std::string> structs_;                   // scoped name -> registry name
  std::map<std::string, FieldType> types_;                       // typedefs and enums by scoped name
  std::map<std::string, std::vector<Constant>> enum_values_;     // enum (or its typedef) -> enumerators
  std::map<std::string, std::vector<Constant>> constants_;       // module path -> constants declared in it
  std::map<std::string, Constant> constant_values_;              // scoped name -> constant
  std::vector<Constant> last_enum_constants_;                    // enumerators of the last type_spec()
};

}  // namespace

std::vector<MessageType> parse_idl(std::string_view text, const std::string& source) {
  Lexer lexer(text, source);
  std::vector<MessageType> types = Parser(lexer.run(), source).run();
  for (const auto& k : lexer.keylists) {
    MessageType* target = nullptr;
    for (auto& t : types) {
      std::string scoped = t.idl_name.empty() ? t.package + "::" + t.kind + "::" + t.name : t.idl_name;
      if (scoped == k.type || t.name == k.type) target = &t;
    }
    auto fail = [&](const std::string& what) {
      throw MsgError(source + ":" + std::to_string(k.line) + ":1: #pragma keylist " + k.type + ": " + what);
    };
    if (!target) fail("no struct of that name in this file");
    for (const auto& key : k.keys) {
      bool found = false;
      for (const auto& f : target->fields) found = found || f.name == key;
      if (!found) fail("no member '" + key + "' (only top-level members can be keys here)");
      target->keys.push_back(key);
    }
  }
  return types;
}

}  // namespace rvc::msg
