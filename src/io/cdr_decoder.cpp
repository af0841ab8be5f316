#include "io/cdr_decoder.hpp"

#include "spec/exact_time.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "io/cdr_cursor.hpp"
#include "io/quant_settle.hpp"

namespace rvc::io {

using msg::ArrayKind;
using msg::FieldType;
using msg::MessageType;
using msg::Prim;
using FOp = spec::FieldTest::Op;

namespace {

const msg::Field* field_named(const MessageType& type, const std::string& name) {
  for (const auto& f : type.fields)
    if (f.name == name) return &f;
  return nullptr;
}

bool is_single_message(const FieldType& t) { return t.prim == Prim::Message && t.array == ArrayKind::None; }

bool prim_is_number(Prim p) {
  return p != Prim::Bool && p != Prim::String && p != Prim::WString && p != Prim::Message;
}

bool is_number(const FieldType& t) { return t.array == ArrayKind::None && prim_is_number(t.prim); }

// builtin_interfaces/Time and its look-alikes: an integer sec and nanosec.
bool is_stamp(const FieldType& t) {
  if (!is_single_message(t)) return false;
  const msg::Field* sec = field_named(*t.message, "sec");
  const msg::Field* nanosec = field_named(*t.message, "nanosec");
  return sec && nanosec && is_number(sec->type) && is_number(nanosec->type) && prim_is_integer(sec->type.prim) &&
         prim_is_integer(nanosec->type.prim);
}

std::vector<std::string> split_path(const std::string& path) {
  std::vector<std::string> parts;
  size_t start = 0;
  for (size_t dot; (dot = path.find('.', start)) != std::string::npos; start = dot + 1)
    parts.push_back(path.substr(start, dot - start));
  parts.push_back(path.substr(start));
  return parts;
}

template <typename T>
bool number(CdrCursor& in, double& d) {
  T v{};
  if (!in.read(v)) return false;
  d = static_cast<double>(v);
  return true;
}

// A 64-bit integer: its double and, beyond 2^53, its exact value (compared exactly).
template <typename T>
bool number(CdrCursor& in, FieldValue& out) {
  T v{};
  if (!in.read(v)) return false;
  out.d = static_cast<double>(v);
  out.exact = spec::exact_of(v);
  return true;
}

}  // namespace

CdrDecoder::CdrDecoder(const engine::AtomTable& atoms, const MessageType& type, const DecoderOptions& options)
    : atoms_(atoms), options_(options), current_(atoms.size(), 0), next_(atoms.size(), 0) {
  root_ = std::move(*plan_of(type));
  if (options_.robustness) {  // only then: the typed Boolean path does no margin work
    margin_.assign(atoms.size(), -std::numeric_limits<double>::infinity());
    next_margin_ = margin_;
  }
  const auto& tests = atoms_.tests();
  for (size_t id = 0; id < tests.size(); ++id) {
    if (tests[id].is_timed()) continue;  // timing atoms and aggregates: the runtime's (engine/timed)
    // The checker's end-of-stream marker (bounded future, engine/checker.cpp): a
    // field name starting with a control character, which no message type can
    // have. No sample sets it (it stays false, as a JSON message never has it);
    // Checker::finish() sets it itself.
    if (!tests[id].path.empty() && !tests[id].path[0].empty() && tests[id].path[0][0] == '\x01') continue;
    // The dense time field itself may be tested, but is not a field when it
    // is the time of a type without one: bind_message_type let it through.
    if (options_.need_time && tests[id].path == split_path(options_.time_field) && !field_named(type, tests[id].path[0]))
      continue;
    plan_path(tests[id].path, tests[id].is_quantified() ? static_cast<int>(id) : -1).tests.push_back(static_cast<int>(id));
    if (tests[id].is_quantified() && folds_.empty()) folds_.resize(tests.size());
    if (tests[id].op == FOp::Present) presence_tests_.push_back(static_cast<int>(id));
    if (tests[id].op == FOp::Bind && bound_.empty()) bound_.assign(tests.size(), 0), next_bound_ = bound_;
  }
  if (options_.need_time) plan_time(options_.time_field);
  index_thresholds(root_);
}

void CdrDecoder::index_thresholds(Plan& plan) {
  for (FieldPlan& f : plan.fields) index_thresholds(f);
}

void CdrDecoder::index_thresholds(FieldPlan& f) {
  // Robustness wants every test's margin: no index then; nor for the elements of a quantifier (folded).
  bool quantified = false;
  for (int id : f.tests) quantified = quantified || atoms_.tests()[id].is_quantified();
  if (quantified) f.rest = f.tests;
  else if (options_.threshold_index && !options_.robustness) f.thresholds.build(f.tests, atoms_.tests(), f.rest);
  if (f.below) index_thresholds(*f.below);
  if (f.each) index_thresholds(*f.each);
  for (auto& e : f.elements)
    if (e) index_thresholds(*e);
}

CdrDecoder::~CdrDecoder() = default;

// A plan of a message type with nothing tested yet: every field skipped.
std::unique_ptr<CdrDecoder::Plan> CdrDecoder::plan_of(const MessageType& type) {
  auto plan = std::make_unique<Plan>();
  plan->type = &type;
  plan->fields.resize(type.fields.size());
  for (size_t i = 0; i < type.fields.size(); ++i) {
    plan->fields[i].name = &type.fields[i].name;
    plan->fields[i].type = type.fields[i].type;
  }
  return plan;
}

std::string CdrDecoder::default_time_field(const MessageType& type, const std::string& requested) {
  if (requested != "time" || field_named(type, "time")) return requested;
  if (const msg::Field* h = field_named(type, "header"); h && is_single_message(h->type)) {
    if (const msg::Field* s = field_named(*h->type.message, "stamp"); s && is_stamp(s->type)) return "header.stamp";
  }
  if (const msg::Field* s = field_named(type, "stamp"); s && is_stamp(s->type)) return "stamp";
  // A service event (pkg/srv/Name_Event, docs/services.md): the time of the event.
  if (const msg::Field* i = field_named(type, "info"); i && is_single_message(i->type) &&
                                                       i->type.type_name == "service_msgs/msg/ServiceEventInfo")
    return "info.stamp";
  return requested;
}

// The plan of the field at `path`, creating the nested plans on the way.
// Paths were checked against the type (runtime::bind_message_type); one that
// does not resolve is a programming error here, reported as a MsgError.
CdrDecoder::FieldPlan& CdrDecoder::plan_path(const std::vector<std::string>& path, int quant_id) {
  FieldPlan* found = nullptr;
  for (size_t i = 0; i < path.size(); ++i) {
    if (spec::is_every_part(path[i])) {  // every element of the array reached so far (a quantifier)
      if (!found || found->type.array == ArrayKind::None)
        throw msg::MsgError("'[*]' after a field that is no array");
      if (!found->elements.empty())  // an element is read once: it can feed one plan
        throw msg::MsgError("an array quantifier over '" + *found->name +
                            "[*]' and a test of one of its elements in one run are not supported yet");
      if (!found->each) {
        found->each = std::make_unique<FieldPlan>();
        found->each->type = found->type;
        found->each->type.array = ArrayKind::None;
        found->each->type.array_size = 0;
      }
      if (quant_id >= 0) found->quant_ids.push_back(quant_id);
      found = found->each.get();
      continue;
    }
    if (spec::is_index_part(path[i])) {  // an element of the array reached so far
      if (!found || found->type.array == ArrayKind::None)
        throw msg::MsgError("an index into a field that is no array: " + path[i]);
      if (found->each)
        throw msg::MsgError("an array quantifier over '" + *found->name +
                            "[*]' and a test of one of its elements in one run are not supported yet");
      const uint32_t index = spec::index_of_part(path[i]);
      if (found->elements.size() <= index) found->elements.resize(index + 1);
      if (!found->elements[index]) {
        auto element = std::make_unique<FieldPlan>();
        element->type = found->type;
        element->type.array = ArrayKind::None;
        element->type.array_size = 0;
        found->elements[index] = std::move(element);
      }
      found = found->elements[index].get();
      continue;
    }
    Plan* plan = &root_;
    if (found) {
      if (!is_single_message(found->type)) throw msg::MsgError("field path into a non-message field: " + path[i]);
      if (!found->below) found->below = plan_of(*found->type.message);
      plan = found->below.get();
    }
    FieldPlan* next = nullptr;
    for (auto& f : plan->fields)
      if (*f.name == path[i]) next = &f;
    if (!next) throw msg::MsgError("no field '" + path[i] + "' in " + plan->type->full_name());
    found = next;
  }
  return *found;
}

void CdrDecoder::plan_time(const std::string& time_field) {
  const std::vector<std::string> path = split_path(time_field);
  // Find it first, with an error naming what there is, before planning.
  const MessageType* holder = root_.type;
  const msg::Field* f = nullptr;
  for (size_t i = 0; i < path.size(); ++i) {
    f = holder ? field_named(*holder, path[i]) : nullptr;
    if (!f) {
      throw msg::MsgError("dense time reads field '" + time_field + "' (--time-field), which " +
                          root_.type->full_name() +
                          " does not have: give --time-field a number or a builtin_interfaces/Time field, e.g. "
                          "--time-field stamp or --time-field header.stamp");
    }
    holder = is_single_message(f->type) ? f->type.message : nullptr;
  }
  if (is_number(f->type)) {
    plan_path(path).time = TimeRole::Number;
  } else if (is_stamp(f->type)) {
    auto with = [&](const char* part) {
      std::vector<std::string> p = path;
      p.push_back(part);
      return p;
    };
    plan_path(with("sec")).time = TimeRole::Sec;
    plan_path(with("nanosec")).time = TimeRole::Nanosec;
  } else {
    throw msg::MsgError("dense time field '" + time_field + "' of " + root_.type->full_name() + " is " +
                        f->type.to_string() + ": it must be a number or a builtin_interfaces/Time (sec, nanosec)");
  }
}

bool CdrDecoder::decode(std::string_view sample, std::string& error, std::vector<std::string>* warnings) {
  std::copy(current_.begin(), current_.end(), next_.begin());  // (memcpy of no atoms: null pointers)
  std::copy(bound_.begin(), bound_.end(), next_bound_.begin());
  // Fields are always there, array elements not ({pts[3]: *}): presence is
  // false until the decoder passes the value.
  for (int id : presence_tests_) next_[id] = 0;
  if (options_.robustness) {
    std::copy(margin_.begin(), margin_.end(), next_margin_.begin());
    for (int id : presence_tests_) next_margin_[id] = -std::numeric_limits<double>::infinity();
  }
  malformed_ = false;
  refused_ = false;
  error_ = &error;
  warnings_ = warnings;
  sec_ = nanosec_ = next_time_ = 0;
  time_is_number_ = false;
  CdrError bad;
  CdrCursor in(bad);
  if (!in.open(sample) || !message(in, root_) || !in.finish()) {
    malformed_ = !refused_;
    if (malformed_) error = "bad " + root_.type->full_name() + " sample: " + bad.to_string();
    return false;
  }
  // Exact nanoseconds: sec and nanosec are integers (int32/uint32 in a
  // builtin_interfaces/Time), never summed as doubles of seconds.
  int64_t ns = 0;
  if (time_is_number_) {
    const double t = spec::seconds_to_ns(next_time_);
    if (!(std::fabs(t) < 9.2e18)) {
      error = "time " + std::to_string(next_time_) + " is beyond the range of exact time (+-9223372036.854775807 s)";
      return false;
    }
    ns = static_cast<int64_t>(t);
  }
  int64_t stamp = 0;
  if (!spec::time_to_ns(static_cast<int64_t>(sec_), static_cast<int64_t>(nanosec_), stamp) ||
      __builtin_add_overflow(ns, stamp, &time_ns_)) {
    error = "time is beyond the range of exact time (+-9223372036.854775807 s)";
    return false;
  }
  return true;
}

bool CdrDecoder::message(CdrCursor& in, const Plan& plan) {
  if (plan.fields.empty()) {  // an empty message is one uint8 on the wire
    uint8_t ignored;
    return in.read(ignored);
  }
  for (const FieldPlan& f : plan.fields) {
    in.push(f.name);
    if (!planned_value(in, f)) return false;
    in.pop();
  }
  return true;
}

bool CdrDecoder::planned_value(CdrCursor& in, const FieldPlan& f) {
  if (f.below || !f.elements.empty() || f.each) {
    if (!(f.below ? message(in, *f.below) : indexed_array(in, f))) return false;
    // A message or array with tested parts inside answers only presence (as in JSON).
    for (int id : f.tests)
      if (atoms_.tests()[id].op == FOp::Present) {
        next_[id] = 1;
        if (options_.robustness) next_margin_[id] = std::numeric_limits<double>::infinity();
      }
    return true;
  }
  if (!f.tests.empty() || f.time != TimeRole::None) return tested_field(in, f);
  return skip(in, f.type);
}

// An array some tests index ({ranges[0] < 0.5}): tested elements are read as
// values, the others checked; an element the sample lacks keeps its tests'
// values, like a missing JSON field.
bool CdrDecoder::indexed_array(CdrCursor& in, const FieldPlan& f) {
  const FieldType& t = f.type;
  uint32_t n = t.array_size;
  if (t.array == ArrayKind::Unbounded && !in.count(n, cdr_min_size(t))) return false;
  if (t.array == ArrayKind::Bounded && !in.count(n, cdr_min_size(t), t.array_size)) return false;
  if (f.each) {  // every element read with the "[*]" plan, its quantifiers folded
    for (int id : f.quant_ids) quant_start(atoms_.tests()[id], folds_[id]);
    for (uint32_t i = 0; i < n; ++i) {
      in.push_index(i);
      element_index_ = i;
      if (!planned_value(in, *f.each)) return false;
      for (int id : f.quant_ids) quant_element_done(folds_[id], i);
      in.pop();
    }
    return finish_quantifiers(f, n);
  }
  for (uint32_t i = 0; i < n; ++i) {
    in.push_index(i);
    const FieldPlan* element = i < f.elements.size() ? f.elements[i].get() : nullptr;
    if (!(element ? planned_value(in, *element) : skip_element(in, t))) return false;
    in.pop();
  }
  return true;
}

// A field some test reads (or the time): read its value and evaluate the tests.
bool CdrDecoder::tested_field(CdrCursor& in, const FieldPlan& f) {
  const FieldType& t = f.type;
  FieldValue v;
  if (t.array != ArrayKind::None || t.prim == Prim::Message) {
    if (!skip(in, t)) return false;
    v.kind = t.array != ArrayKind::None ? ValueKind::Array : ValueKind::Object;
    return apply(f, v);
  }
  bool ok = true;
  v.kind = ValueKind::Number;
  switch (t.prim) {
    case Prim::Bool:
      v.kind = ValueKind::Bool;
      ok = in.boolean(v.b);
      break;
    case Prim::Byte: case Prim::Char: case Prim::UInt8: ok = number<uint8_t>(in, v.d); break;
    case Prim::Int8: ok = number<int8_t>(in, v.d); break;
    case Prim::Int16: ok = number<int16_t>(in, v.d); break;
    case Prim::UInt16: ok = number<uint16_t>(in, v.d); break;
    case Prim::Int32: ok = number<int32_t>(in, v.d); break;
    case Prim::UInt32: ok = number<uint32_t>(in, v.d); break;
    case Prim::Int64: ok = number<int64_t>(in, v); break;
    case Prim::UInt64: ok = number<uint64_t>(in, v); break;
    case Prim::Float32: ok = number<float>(in, v.d); break;
    case Prim::Float64: ok = number<double>(in, v.d); break;
    case Prim::String:
      v.kind = ValueKind::String;
      ok = in.string(v.s, t.string_bound);
      break;
    case Prim::WString: return in.fail("wstring fields are not supported");
    case Prim::Message: break;  // handled above
  }
  if (!ok) return false;
  switch (f.time) {
    case TimeRole::None: break;
    case TimeRole::Number: next_time_ = v.d, time_is_number_ = true; break;
    case TimeRole::Sec: sec_ = v.d; break;
    case TimeRole::Nanosec: nanosec_ = v.d; break;
  }
  return apply(f, v);
}

bool CdrDecoder::apply(const FieldPlan& f, const FieldValue& v) {
  const std::vector<int>* ids = &f.tests;
  if (!f.thresholds.empty() && v.kind == ValueKind::Number && std::fabs(v.d) < spec::kTwo53) {
    f.thresholds.apply(v.d, next_.data());  // the grouped comparisons; the loop does the others
    ids = &f.rest;
  }
  for (int id : *ids) {
    const spec::FieldTest& t = atoms_.tests()[id];
    if (t.is_quantified()) {  // one element of its array: folded, finished by indexed_array
      quant_element(t, v, element_index_, folds_[id]);
      continue;
    }
    const int result = evaluate_test(t, v);
    if (result >= 0) {
      next_[id] = static_cast<uint8_t>(result);
      if (options_.robustness) next_margin_[id] = test_margin(t, v);
      if (t.op == FOp::Bind) next_bound_[id] = bound_ids_.id(v);
      continue;
    }
    const std::string problem = wrong_type_problem(t, v.kind);
    if (options_.strict) {
      *error_ = problem;
      refused_ = true;
      return false;
    }
    if (warnings_) warnings_->push_back(problem + "; it keeps its previous value");
  }
  return true;
}

// An array's quantifiers after its `elements` elements (as JsonDecoder's).
bool CdrDecoder::finish_quantifiers(const FieldPlan& f, uint32_t elements) {
  if (settle_quantifiers(f.quant_ids, atoms_.tests(), folds_, elements, next_,
                         options_.robustness ? &next_margin_ : nullptr, options_.strict, *error_, warnings_))
    return true;
  refused_ = true;
  return false;
}

// Fields no test reads are checked, not looked at: fixed-size numbers are
// stepped over, everything that can be malformed is read.
bool CdrDecoder::skip(CdrCursor& in, const FieldType& t) {
  if (t.array == ArrayKind::None) return skip_element(in, t);
  uint32_t n = t.array_size;
  if (t.array == ArrayKind::Unbounded && !in.count(n, cdr_min_size(t))) return false;
  if (t.array == ArrayKind::Bounded && !in.count(n, cdr_min_size(t), t.array_size)) return false;
  // Numbers are stepped over in one go when they are all there; else read
  // one by one, so the error names the element where the sample ends.
  if (prim_is_number(t.prim) && in.has(msg::prim_size(t.prim), n))
    return n == 0 || in.skip(msg::prim_size(t.prim), n);
  for (uint32_t i = 0; i < n; ++i) {
    in.push_index(i);
    if (!skip_element(in, t)) return false;
    in.pop();
  }
  return true;
}

bool CdrDecoder::skip_element(CdrCursor& in, const FieldType& t) {
  switch (t.prim) {
    case Prim::Bool: {
      bool b;
      return in.boolean(b);
    }
    case Prim::String: {
      std::string_view s;
      return in.string(s, t.string_bound);
    }
    case Prim::WString: return in.fail("wstring fields are not supported");
    case Prim::Message: return skip_message(in, *t.message);
    default: return in.skip(msg::prim_size(t.prim), 1);
  }
}

bool CdrDecoder::skip_message(CdrCursor& in, const MessageType& type) {
  if (type.fields.empty()) return in.skip(1, 1);
  for (const msg::Field& f : type.fields) {
    in.push(&f.name);
    if (!skip(in, f.type)) return false;
    in.pop();
  }
  return true;
}

}  // namespace rvc::io
