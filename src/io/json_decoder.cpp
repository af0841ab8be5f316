#include "io/json_decoder.hpp"

namespace rvc::io {

using simdjson::ondemand::json_type;
using FOp = spec::FieldTest::Op;

namespace {

const char* type_name(json_type t) {
  switch (t) {
    case json_type::array: return "an array";
    case json_type::object: return "an object";
    case json_type::number: return "a number";
    case json_type::string: return "a string";
    case json_type::boolean: return "a Boolean";
    case json_type::null: return "null";
  }
  return "a value";
}

const char* expected_for(const spec::FieldTest& t) {
  if (t.op == FOp::Truthy) return "a Boolean or number";
  switch (t.value.kind) {
    case spec::Literal::Kind::Bool: return "a Boolean";
    case spec::Literal::Kind::Number: return "a number";
    case spec::Literal::Kind::String: return "a string";
  }
  return "a value";
}

}  // namespace

JsonDecoder::JsonDecoder(const engine::AtomTable& atoms, DecoderOptions options)
    : atoms_(atoms), options_(std::move(options)), current_(atoms.size(), 0), next_(atoms.size(), 0) {
  const auto& tests = atoms_.tests();
  for (size_t id = 0; id < tests.size(); ++id) {
    KeyNode* node = &root_;
    for (const std::string& part : tests[id].path) node = child(*node, part);
    node->tests.push_back(static_cast<int>(id));
    if (tests[id].op == FOp::Present) presence_tests_.push_back(static_cast<int>(id));
  }
  if (options_.need_time) child(root_, options_.time_field)->is_time = true;
}

JsonDecoder::KeyNode* JsonDecoder::child(KeyNode& parent, const std::string& name) {
  for (KeyNode& c : parent.children)
    if (c.name == name) return &c;
  parent.children.push_back(KeyNode{name, {}, {}, false, 0});
  return &parent.children.back();
}

bool JsonDecoder::decode(simdjson::ondemand::object object, std::string& error, std::vector<std::string>* warnings) {
  next_ = current_;
  for (int id : presence_tests_) next_[id] = 0;
  saw_time_ = false;
  ++generation_;
  if (!decode_object(object, root_, error, warnings)) return false;
  if (options_.need_time && !saw_time_) {
    error = "missing time field \"" + options_.time_field + "\" (dense time needs one in every message)";
    return false;
  }
  if (options_.strict && !check_missing(root_, "", error)) return false;
  time_ = next_time_;
  return true;
}

bool JsonDecoder::decode_object(simdjson::ondemand::object object, KeyNode& node, std::string& error,
                                std::vector<std::string>* warnings) {
  for (auto field : object) {
    std::string_view key;
    if (auto err = field.unescaped_key().get(key)) {
      error = std::string("invalid JSON: ") + simdjson::error_message(err);
      return false;
    }
    KeyNode* target = nullptr;
    for (KeyNode& c : node.children)
      if (c.name == key) { target = &c; break; }
    if (!target) continue;  // fields no test reads are skipped by the iterator, unparsed
    simdjson::ondemand::value value;
    if (auto err = field.value().get(value)) {
      error = std::string("invalid JSON: ") + simdjson::error_message(err);
      return false;
    }
    json_type type;
    if (auto err = value.type().get(type)) {
      error = std::string("invalid JSON: ") + simdjson::error_message(err);
      return false;
    }
    target->seen = generation_;
    if (target->is_time && &node == &root_) {
      double t;
      if (type != json_type::number || value.get_double().get(t)) {
        error = "time field \"" + options_.time_field + "\" must be a number, not " + type_name(type);
        return false;
      }
      saw_time_ = true;
      next_time_ = t;
      // The time field may also be tested by atoms; re-reading a number is cheap.
    }
    if (type == json_type::object && !target->children.empty()) {
      simdjson::ondemand::object inner;
      if (auto err = value.get_object().get(inner)) {
        error = std::string("invalid JSON: ") + simdjson::error_message(err);
        return false;
      }
      if (!decode_object(inner, *target, error, warnings)) return false;
      for (int id : target->tests)
        if (atoms_.tests()[id].op == FOp::Present) next_[id] = 1;
      continue;
    }
    if (!target->tests.empty() && !apply_tests(*target, value, type, error, warnings)) return false;
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
  else if (type == json_type::number) err = value.get_double().get(d);
  else if (type == json_type::string) err = value.get_string().get(s);
  if (err) {
    error = std::string("invalid JSON value for field \"") + node.name + "\": " + simdjson::error_message(err);
    return false;
  }
  for (int id : node.tests) {
    const spec::FieldTest& t = atoms_.tests()[id];
    int result = -1;  // -1: wrong type, the test keeps its previous value
    const auto lit = t.value.kind;
    switch (t.op) {
      case FOp::Present:
      case FOp::Bind: result = 1; break;
      case FOp::Truthy:
        if (type == json_type::boolean) result = b;
        else if (type == json_type::number) result = d != 0;
        else if (type == json_type::null) result = 0;  // Reelay reads null as false
        break;
      case FOp::Eq:
      case FOp::Ne: {
        int eq = -1;
        if (lit == spec::Literal::Kind::Bool && type == json_type::boolean) eq = b == t.value.b;
        else if (lit == spec::Literal::Kind::Number && type == json_type::number) eq = d == t.value.number;
        else if (lit == spec::Literal::Kind::String && type == json_type::string) eq = s == t.value.text;
        if (eq >= 0) result = t.op == FOp::Eq ? eq : !eq;
        break;
      }
      case FOp::Lt: if (type == json_type::number) result = d < t.value.number; break;
      case FOp::Le: if (type == json_type::number) result = d <= t.value.number; break;
      case FOp::Gt: if (type == json_type::number) result = d > t.value.number; break;
      case FOp::Ge: if (type == json_type::number) result = d >= t.value.number; break;
    }
    if (result >= 0) {
      next_[id] = static_cast<uint8_t>(result);
      continue;
    }
    if (type == json_type::null && !options_.strict) continue;  // null: no value, like a missing field
    std::string problem = "field \"" + t.key() + "\" is " + type_name(type) + ", but {" + t.to_string() + "} needs " +
                          expected_for(t);
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
    std::string path = prefix.empty() ? c.name : prefix + "." + c.name;
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
