#include "io/json_decoder.hpp"

#include "spec/exact_time.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <cstring>

#include "io/field_tests.hpp"
#include "io/raw_key.hpp"
#include "io/quant_settle.hpp"

namespace rvc::io {

using simdjson::ondemand::json_type;
using FOp = spec::FieldTest::Op;

namespace {

ValueKind kind_of(json_type t) {
  switch (t) {
    case json_type::array: return ValueKind::Array;
    case json_type::object: return ValueKind::Object;
    case json_type::number: return ValueKind::Number;
    case json_type::string: return ValueKind::String;
    case json_type::boolean: return ValueKind::Bool;
    case json_type::null: return ValueKind::Null;
  }
  return ValueKind::Null;
}

const char* type_name(json_type t) { return value_kind_name(kind_of(t)); }

bool raw_has_backslash(simdjson::ondemand::raw_json_string raw) {
  const char* k = reinterpret_cast<const char*>(raw.raw());
  return std::memchr(k, '\\', raw_key_length(k)) != nullptr;
}

// A field's key for an error message (raw bytes, escapes shown as written).
// (Take the raw key before unescaped_key(): that one consumes it.)
std::string key_text(simdjson::ondemand::raw_json_string raw) {
  const char* k = reinterpret_cast<const char*>(raw.raw());
  return std::string(k, raw_key_length(k));
}

// Raw JSON key == name (no escapes in name)? Keys are short: a byte loop
// beats a call to memcmp.
inline bool key_is(simdjson::ondemand::raw_json_string raw, const std::string& name) {
  const char* k = reinterpret_cast<const char*>(raw.raw());
  const size_t n = name.size();
  for (size_t i = 0; i < n; ++i)
    if (k[i] != name[i]) return false;
  return k[n] == '"';
}

// NaN, Infinity, -Infinity: the words `rvc echo` and `rvc msg decode` write
// for a non-finite float (as Python's json module does), which simdjson does
// not read as numbers. The value is such a word: its number, else false.
[[gnu::cold, gnu::noinline]] bool non_finite_text(std::string_view token, double& d) {
  while (!token.empty() && json_space(token.back())) token.remove_suffix(1);
  if (token == "NaN") return d = std::numeric_limits<double>::quiet_NaN(), true;
  if (token == "Infinity") return d = std::numeric_limits<double>::infinity(), true;
  if (token == "-Infinity") return d = -std::numeric_limits<double>::infinity(), true;
  return false;
}

inline bool non_finite(simdjson::ondemand::value& value, double& d) { return non_finite_text(value.raw_json_token(), d); }

// Reads a value no property tests, only to check that it is well-formed:
// simdjson's on-demand API skips unread values without validating them, and
// a message must be rejected for malformed JSON whatever the properties read
// (else adding a property would change another one's verdicts). Numbers are
// read as the tested path reads them (get_double), so both agree on what a
// number is. Returns the error, or SUCCESS.
simdjson::error_code validate(simdjson::ondemand::value value, int depth = 0) {
  if (depth > 1024) return simdjson::DEPTH_ERROR;  // simdjson's own default limit
  json_type type;
  double d;
  if (auto err = value.type().get(type)) return non_finite(value, d) ? simdjson::SUCCESS : err;
  switch (type) {
    case json_type::number: {
      auto err = value.get_double().get(d);
      return err && non_finite(value, d) ? simdjson::SUCCESS : err;
    }
    case json_type::string: {
      std::string_view s;
      return value.get_string().get(s);
    }
    case json_type::boolean: {
      bool b;
      return value.get_bool().get(b);
    }
    case json_type::null: {
      bool is_null = false;
      if (auto err = value.is_null().get(is_null)) return err;
      return is_null ? simdjson::SUCCESS : simdjson::INCORRECT_TYPE;  // "nul", "nulx"
    }
    case json_type::array: {
      simdjson::ondemand::array array;
      if (auto err = value.get_array().get(array)) return err;
      for (auto element : array) {
        simdjson::ondemand::value v;
        if (auto err = std::move(element).get(v)) return err;
        if (auto err = validate(v, depth + 1)) return err;
      }
      return simdjson::SUCCESS;
    }
    case json_type::object: {
      simdjson::ondemand::object object;
      if (auto err = value.get_object().get(object)) return err;
      for (auto field_result : object) {
        simdjson::ondemand::field field;
        if (auto err = std::move(field_result).get(field)) return err;
        std::string_view key;
        if (auto err = field.unescaped_key().get(key)) return err;
        if (auto err = validate(field.value(), depth + 1)) return err;
      }
      return simdjson::SUCCESS;
    }
  }
  return simdjson::INCORRECT_TYPE;
}

}  // namespace

JsonDecoder::JsonDecoder(const engine::AtomTable& atoms, DecoderOptions options)
    : atoms_(atoms), options_(std::move(options)), current_(atoms.size(), 0), next_(atoms.size(), 0) {
  if (options_.robustness) {
    margin_.assign(atoms.size(), -std::numeric_limits<double>::infinity());
    next_margin_ = margin_;
  }
  const auto& tests = atoms_.tests();
  for (size_t id = 0; id < tests.size(); ++id) {
    if (tests[id].is_timed()) continue;  // timing atoms and aggregates: the runtime's (engine/timed)
    KeyNode* node = &root_;
    for (const std::string& part : tests[id].path) {
      if (spec::is_every_part(part)) node->quant_ids.push_back(static_cast<int>(id));  // the array's
      node = child(*node, part);
    }
    node->tests.push_back(static_cast<int>(id));
    if (tests[id].is_quantified() && folds_.empty()) folds_.resize(tests.size());
    if (tests[id].op == FOp::Present) presence_tests_.push_back(static_cast<int>(id));
    if (tests[id].op == FOp::Bind && bound_.empty()) bound_.assign(tests.size(), 0), next_bound_ = bound_;
  }
  if (options_.need_time) {
    KeyNode* t = &root_;  // a path, as in specs: "header.stamp"
    size_t start = 0;
    for (size_t dot; (dot = options_.time_field.find('.', start)) != std::string::npos; start = dot + 1)
      t = child(*t, options_.time_field.substr(start, dot - start));
    t = child(*t, options_.time_field.substr(start));
    t->time_part = 1;
    for (const char* sec : {"sec", "secs"}) child(*t, sec)->time_part = 2;
    for (const char* nsec : {"nanosec", "nsecs"}) child(*t, nsec)->time_part = 3;
  }
  prepare(root_);
}

namespace {

// The raw key at k equals `seen`'s key: it is followed by its closing quote.
// Short keys compare as one masked 8-byte load: simdjson's buffers carry
// SIMDJSON_PADDING readable bytes past the text, so the load stays inside.
inline bool seen_key_is(const char* k, const std::string& key, uint64_t word, uint64_t mask) {
  if (mask) {
    uint64_t w;
    std::memcpy(&w, k, sizeof w);
    return (w & mask) == word;
  }
  const size_t n = key.size();
  for (size_t i = 0; i < n; ++i)
    if (k[i] != key[i]) return false;
  return k[n] == '"';
}

}  // namespace

void JsonDecoder::remember(KeyNode& node, size_t position, simdjson::ondemand::raw_json_string raw,
                           KeyNode* target) {
  // The raw key runs up to its closing quote (escaped quotes are preceded by a backslash).
  const char* k = reinterpret_cast<const char*>(raw.raw());
  const size_t n = raw_key_length(k);
  if (position > 64 || n > 64) return;  // odd messages: don't let the cache grow
  // A key with escapes must take the unescaping path every time.
  if (std::memchr(k, '\\', n) != nullptr) return;
  if (node.by_position.size() <= position) node.by_position.resize(position + 1, KeyNode::Seen{"\x01", nullptr});
  KeyNode::Seen seen{std::string(k, n), target};
  if (n + 1 <= sizeof(uint64_t)) {
    const std::string quoted = seen.key + '"';
    std::memcpy(&seen.word, quoted.data(), quoted.size());  // the rest stays 0, as the mask's
    seen.mask = quoted.size() == 8 ? ~uint64_t{0} : (uint64_t{1} << (8 * quoted.size())) - 1;
  }
  node.by_position[position] = std::move(seen);
}

void JsonDecoder::prepare(KeyNode& node) {
  for (KeyNode& c : node.children) prepare(c);
  for (KeyNode& c : node.children) {
    if (spec::is_every_part(c.name)) {
      c.is_index = true;  // not a key
      node.each = &c;
      // An element read once can feed one subtree: "[*]" and "[N]" of one array cannot both be tested.
      for (const KeyNode& other : node.children)
        if (spec::is_index_part(other.name))
          throw std::invalid_argument("an array quantifier over \"" + node.name + "[*]\" and a test of its element \"" +
                                   node.name + other.name + "\" in one run are not supported yet (JSON input)");
      continue;
    }
    c.is_index = spec::is_index_part(c.name);
    if (!c.is_index) continue;
    const uint32_t i = spec::index_of_part(c.name);
    if (node.by_index.size() <= i) node.by_index.resize(i + 1, nullptr);
    node.by_index[i] = &c;  // children are complete: the pointers stay valid
  }
  for (KeyNode& c : node.children) node.any_escaped_child = node.any_escaped_child || !c.raw_comparable;
  node.raw_comparable = node.name.find_first_of("\"\\") == std::string::npos;
  if (node.tests.empty() || !node.children.empty() || node.time_part) return;
  for (int id : node.tests)  // each element's tests fold (apply_value): no fast path
    if (atoms_.tests()[id].is_quantified()) return;
  bool all_bool = true, all_number = true;
  for (int id : node.tests) {
    const spec::FieldTest& t = atoms_.tests()[id];
    bool lit_bool = t.value.kind == spec::Literal::Kind::Bool, lit_num = t.value.kind == spec::Literal::Kind::Number;
    bool is_bool = t.op == FOp::Truthy || t.op == FOp::Present || ((t.op == FOp::Eq || t.op == FOp::Ne) && lit_bool);
    bool is_num = t.op == FOp::Present || ((t.op == FOp::Eq || t.op == FOp::Ne) && lit_num) || t.op == FOp::Lt ||
                  t.op == FOp::Le || t.op == FOp::Gt || t.op == FOp::Ge;
    all_bool = all_bool && is_bool;
    all_number = all_number && is_num;
    if (is_bool) {
      uint8_t on_true = 1, on_false = 0;  // Truthy, Eq true, Ne false
      if (t.op == FOp::Present) on_false = 1;
      else if ((t.op == FOp::Eq && !t.value.b) || (t.op == FOp::Ne && t.value.b)) on_true = 0, on_false = 1;
      node.bool_tests.push_back({id, on_true, on_false});
    }
  }
  node.kind = all_bool ? Kind::Bool : all_number ? Kind::Number : Kind::General;
  node.number_rest = node.tests;
  if (node.kind == Kind::Number && options_.threshold_index)
    node.thresholds.build(node.tests, atoms_.tests(), node.number_rest);
}

// Returns false when the value is not of the expected type: the caller then
// takes the general path, which handles (and reports) every other case.
__attribute__((always_inline)) inline bool JsonDecoder::fast_path(KeyNode& node, simdjson::ondemand::value& value) {
  if (node.kind == Kind::Bool) {
    bool b;
    if (value.get_bool().get(b)) return false;
    bool_tests(node, b);
    return true;
  }
  double d;
  if (value.get_double().get(d)) return false;
  if (std::fabs(d) >= spec::kTwo53) [[unlikely]] {  // maybe an integer a double cannot hold: its text decides
    number_tests_from_text(node, value.raw_json_token(), d);
    return true;
  }
  number_tests(node, d);
  return true;
}

void JsonDecoder::number_tests_exact(const KeyNode& node, const FieldValue& v) {
  for (int id : node.tests) next_[id] = static_cast<uint8_t>(compare_test(atoms_.tests()[id].op, v, atoms_.tests()[id].value));
}

void JsonDecoder::number_tests_from_text(const KeyNode& node, std::string_view token, double d) {
  FieldValue v;
  set_json_number(v, token, d);
  number_tests_exact(node, v);
}

JsonDecoder::KeyNode* JsonDecoder::child(KeyNode& parent, const std::string& name) {
  for (KeyNode& c : parent.children)
    if (c.name == name) return &c;
  KeyNode node;
  node.name = name;
  parent.children.push_back(std::move(node));
  return &parent.children.back();
}

// The message is malformed JSON (not merely unusable): the reader re-reads
// it and reports it. `field`: where, if known.
bool JsonDecoder::invalid(std::string& error, simdjson::error_code err, const std::string& field) {
  error = field.empty() ? std::string("invalid JSON: ") + simdjson::error_message(err)
                        : "invalid JSON in field \"" + field + "\": " + simdjson::error_message(err);
  malformed_ = true;
  return false;
}

// Every message starts from the committed values: a field it lacks keeps its value.
void JsonDecoder::begin_message() {
  std::copy(current_.begin(), current_.end(), next_.begin());  // (memcpy of no atoms: null pointers)
  std::copy(bound_.begin(), bound_.end(), next_bound_.begin());
  for (int id : presence_tests_) next_[id] = 0;
  if (options_.robustness) {
    std::copy(margin_.begin(), margin_.end(), next_margin_.begin());
    for (int id : presence_tests_) next_margin_[id] = -std::numeric_limits<double>::infinity();
  }
  saw_time_ = false;
  malformed_ = false;
  ++generation_;
}

bool JsonDecoder::decode(simdjson::ondemand::object object, std::string& error, std::vector<std::string>* warnings) {
  begin_message();
  if (!decode_object(object, root_, error, warnings)) return false;
  if (options_.need_time && !saw_time_) {
    error = "missing time field \"" + options_.time_field + "\" (dense time needs one in every message)";
    return false;
  }
  if (options_.strict && !check_missing(root_, "", error)) return false;
  time_ns_ = next_time_ns_;
  return true;
}

bool JsonDecoder::read_time_text(std::string_view text, const std::string& name, int64_t& ns,
                                 std::string& error) const {
  switch (spec::parse_seconds(text, ns)) {
    case spec::SecondsStatus::Ok: return true;
    case spec::SecondsStatus::OutOfRange:
      while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r' || text.back() == '\n'))
        text.remove_suffix(1);
      error = "time field \"" + name + "\" is " + std::string(text.substr(0, 40)) +
              " s: beyond the range of exact time (+-9223372036.854775807 s, int64 nanoseconds)";
      return false;
    case spec::SecondsStatus::Malformed: break;
  }
  error = "time field \"" + name + "\" is not a number of seconds";
  return false;
}

// A Time {sec, nanosec}: sec exactly (as ns) plus nanosec, an integer count.
bool JsonDecoder::combine_time(std::string& error) {
  if (!(std::fabs(time_nsec_) < 9.2e18) ||
      __builtin_add_overflow(time_sec_ns_, static_cast<int64_t>(std::llround(time_nsec_)), &next_time_ns_)) {
    error = "time field \"" + options_.time_field + "\" is beyond the range of exact time (+-9223372036.854775807 s)";
    return false;
  }
  saw_time_ = true;
  return true;
}

bool JsonDecoder::decode_object(simdjson::ondemand::object object, KeyNode& node, std::string& error,
                                std::vector<std::string>* warnings) {
  const bool robustness = options_.robustness;
  size_t position = 0;
  for (auto field_result : object) {
    simdjson::ondemand::field field;
    if (auto err = std::move(field_result).get(field)) {
      return invalid(error, err);
    }
    // Compare the raw key bytes (no unescaping, no copy); names that contain
    // a quote or backslash fall back to comparing the unescaped key.
    simdjson::ondemand::raw_json_string raw = field.key();
    KeyNode* target = nullptr;
    bool known = false;
    if (position < node.by_position.size()) {
      const auto& seen = node.by_position[position];
      if (seen_key_is(reinterpret_cast<const char*>(raw.raw()), seen.key, seen.word, seen.mask)) {
        target = seen.target;
        known = true;
      }
    }
    if (!known) {
      for (KeyNode& c : node.children) {
        if (c.raw_comparable && !c.is_index && key_is(raw, c.name)) { target = &c; break; }
      }
      // A key written with escapes ("\u0070") is compared unescaped.
      if (!target && (node.any_escaped_child || raw_has_backslash(raw))) {
        std::string_view key;
        if (auto err = field.unescaped_key().get(key)) {
          return invalid(error, err);
        }
        for (KeyNode& c : node.children)
          if (!c.is_index && c.name == key) { target = &c; break; }
      }
      remember(node, position, raw, target);
    }
    ++position;
    simdjson::ondemand::value value = field.value();
    if (!target) {  // a field no test reads: only checked to be well-formed
      if (auto err = validate(value)) {
        return invalid(error, err, key_text(raw));
      }
      continue;
    }
    // Fields tested only as Booleans or only as numbers (most): read here,
    // without the general path's call; anything unexpected goes there.
    if (target->kind != Kind::General && !robustness) {
      target->seen = generation_;
      if (fast_path(*target, value)) continue;
    }
    if (!decode_value(*target, value, error, warnings)) return false;
  }
  return true;
}

// One value of a field (or array element) some test reads: its tests, its
// nested fields and elements, and the time.
bool JsonDecoder::decode_value(KeyNode& target, simdjson::ondemand::value value, std::string& error,
                               std::vector<std::string>* warnings) {
  target.seen = generation_;
  if (target.kind != Kind::General && !options_.robustness && fast_path(target, value)) return true;
  json_type type;
  if (auto err = value.type().get(type)) {
    double d;
    if (!non_finite(value, d)) return invalid(error, err);
    if (target.time_part) {
      error = "time field \"" + options_.time_field + "\" is not a finite number";
      return false;
    }
    // A non-finite float: a number to the tests (IEEE 754: NaN compares false but for !=).
    if (!target.tests.empty() && !apply_value(target, FieldValue{ValueKind::Number, false, d, {}, {}}, error, warnings))
      return false;
    return true;
  }
  if (!target.quant_ids.empty() && type != json_type::array) {
    if (!not_an_array(target, kind_of(type), error, warnings)) return false;
    if (auto err = validate(value)) return invalid(error, err, target.name);
    return true;
  }
  if (target.time_part == 1) {
    double t;
    if (type == json_type::object) {  // a builtin_interfaces/Time: its parts come as its children
      saw_sec_ = false;
      time_sec_ns_ = 0;
      time_nsec_ = 0;
    } else if (type != json_type::number) {
      error = "time field \"" + options_.time_field + "\" must be a number of seconds or a Time {sec, nanosec}, not " +
              type_name(type);
      return false;
    } else {
      // Exactly from its text: a double would round epoch stamps to ~240 ns.
      if (!read_time_text(value.raw_json_token(), options_.time_field, next_time_ns_, error)) return false;
      saw_time_ = true;
      (void)t;
    }
    // The time field may also be tested by atoms; re-reading a number is cheap.
  } else if (target.time_part >= 2) {
    double part;
    if (type != json_type::number || value.get_double().get(part)) {
      error = "time field \"" + options_.time_field + "." + target.name + "\" must be a number, not " + type_name(type);
      return false;
    }
    if (target.time_part == 2) {
      if (!read_time_text(value.raw_json_token(), options_.time_field + ".sec", time_sec_ns_, error)) return false;
      saw_sec_ = true;
    } else {
      time_nsec_ = part;
    }
  }
  if (type == json_type::object && !target.children.empty()) {
    simdjson::ondemand::object inner;
    if (auto err = value.get_object().get(inner)) {
      return invalid(error, err);
    }
    if (!decode_object(inner, target, error, warnings)) return false;
    for (int id : target.tests)
      if (atoms_.tests()[id].op == FOp::Present) {
        next_[id] = 1;
        if (options_.robustness) next_margin_[id] = std::numeric_limits<double>::infinity();
      }
    if (target.time_part == 1) {
      if (!saw_sec_) {
        error = "time field \"" + options_.time_field + "\" is an object without \"sec\" (a Time is {sec, nanosec})";
        return false;
      }
      if (!combine_time(error)) return false;
    }
    return true;
  }
  if (type == json_type::array && (!target.by_index.empty() || target.each)) {  // {ranges[0] < 0.5}
    simdjson::ondemand::array elements;
    if (auto err = value.get_array().get(elements)) {
      return invalid(error, err);
    }
    if (!decode_array(elements, target, error, warnings)) return false;
    for (int id : target.tests)
      if (atoms_.tests()[id].op == FOp::Present) {
        next_[id] = 1;
        if (options_.robustness) next_margin_[id] = std::numeric_limits<double>::infinity();
      }
    return true;
  }
  if (!target.tests.empty() && !apply_tests(target, value, type, error, warnings)) return false;
  // apply_tests reads scalars of tested fields; what it did not read (a
  // field only its children are tested on, arrays, objects, null) must
  // still be well-formed.
  if (target.tests.empty() || type == json_type::array || type == json_type::object || type == json_type::null) {
    if (auto err = validate(value)) {
      return invalid(error, err, target.name);
    }
  }
  return true;
}

// The elements of an array some tests index: each tested element decoded as a
// value, the others only checked. An element the array does not have keeps
// its tests' values, like a missing field.
bool JsonDecoder::decode_array(simdjson::ondemand::array elements, KeyNode& node, std::string& error,
                               std::vector<std::string>* warnings) {
  if (node.each) {  // every element into "[*]", its quantifiers folded
    for (int id : node.quant_ids) quant_start(atoms_.tests()[id], folds_[id]);
    uint32_t n = 0;
    for (auto element : elements) {
      simdjson::ondemand::value v;
      if (auto err = std::move(element).get(v)) return invalid(error, err, node.name);
      element_index_ = n;
      if (!decode_value(*node.each, v, error, warnings)) return false;
      for (int id : node.quant_ids) quant_element_done(folds_[id], n);
      ++n;
    }
    return finish_quantifiers(node, n, error, warnings);
  }
  size_t i = 0;
  for (auto element : elements) {
    simdjson::ondemand::value v;
    if (auto err = std::move(element).get(v)) {
      return invalid(error, err, node.name);
    }
    KeyNode* child = i < node.by_index.size() ? node.by_index[i] : nullptr;
    ++i;
    if (!child) {
      if (auto err = validate(v)) {
        return invalid(error, err, node.name);
      }
      continue;
    }
    if (!decode_value(*child, v, error, warnings)) return false;
  }
  return true;
}

bool JsonDecoder::apply_tests(KeyNode& node, simdjson::ondemand::value value, json_type type, std::string& error,
                              std::vector<std::string>* warnings) {
  bool b = false;
  double d = 0;
  std::string_view s;
  simdjson::error_code err = simdjson::SUCCESS;
  if (type == json_type::boolean) err = value.get_bool().get(b);
  else if (type == json_type::number && (err = value.get_double().get(d)) && non_finite(value, d)) err = simdjson::SUCCESS;
  else if (type == json_type::string) err = value.get_string().get(s);
  if (err) {
    error = std::string("invalid JSON value for field \"") + node.name + "\": " + simdjson::error_message(err);
    malformed_ = true;
    return false;
  }
  FieldValue v{kind_of(type), b, d, s, {}};
  if (type == json_type::number) set_json_number(v, value.raw_json_token(), d);
  return apply_value(node, v, error, warnings);
}

// A scalar's tests, whatever its type (a type a test cannot use leaves that
// test's value as it was, with a warning; in strict mode it rejects the message).
bool JsonDecoder::apply_value(KeyNode& node, const FieldValue& v, std::string& error,
                              std::vector<std::string>* warnings) {
  for (int id : node.tests) {
    const spec::FieldTest& t = atoms_.tests()[id];
    if (t.is_quantified()) {  // one element of its array: folded, finished by decode_array
      quant_element(t, v, element_index_, folds_[id]);
      continue;
    }
    const int result = evaluate_test(t, v);  // -1: wrong type, the test keeps its previous value
    if (result >= 0) {
      next_[id] = static_cast<uint8_t>(result);
      if (options_.robustness) next_margin_[id] = test_margin(t, v);
      if (t.op == FOp::Bind) next_bound_[id] = bound_ids_.id(v);
      continue;
    }
    if (v.kind == ValueKind::Null && !options_.strict) continue;  // null: no value, like a missing field
    std::string problem = wrong_type_problem(t, v.kind);
    if (options_.strict) {
      error = problem;
      return false;
    }
    if (warnings) warnings->push_back(problem + "; it keeps its previous value");
  }
  return true;
}

// An array's quantifiers after its `elements` elements: their values, or
// (an element without a usable value) the problem, as a wrong-type field.
bool JsonDecoder::finish_quantifiers(const KeyNode& node, uint32_t elements, std::string& error,
                                     std::vector<std::string>* warnings) {
  return settle_quantifiers(node.quant_ids, atoms_.tests(), folds_, elements, next_,
                            options_.robustness ? &next_margin_ : nullptr, options_.strict, error, warnings);
}

// The field an array quantifier reads is no array: its quantifiers keep
// their values (null silently, as a missing field), or strict mode rejects.
bool JsonDecoder::not_an_array(const KeyNode& node, ValueKind kind, std::string& error,
                               std::vector<std::string>* warnings) {
  if (kind == ValueKind::Null && !options_.strict) return true;
  for (int id : node.quant_ids) {
    const std::string problem = not_an_array_problem(atoms_.tests()[id], kind);
    if (options_.strict) {
      error = problem;
      return false;
    }
    if (warnings) warnings->push_back(problem + "; it keeps its previous value");
  }
  return true;
}

bool JsonDecoder::check_missing(const KeyNode& node, const std::string& prefix, std::string& error) const {
  for (const KeyNode& c : node.children) {
    if (&c == node.each) continue;  // elements without the field: the quantifier's fold reports them
    std::string path = prefix.empty() ? c.name : c.is_index ? prefix + c.name : prefix + "." + c.name;
    bool needed = false;
    for (int id : c.tests) needed = needed || atoms_.tests()[id].op != FOp::Present;
    if (c.seen != generation_) {
      if (needed || !c.children.empty()) {
        error = "missing field \"" + path + "\" (strict mode)";
        return false;
      }
      continue;
    }
    if (!c.children.empty() && !check_missing(c, path, error)) return false;
  }
  return true;
}

}  // namespace rvc::io
