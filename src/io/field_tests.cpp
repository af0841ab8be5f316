#include "io/field_tests.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace rvc::io {

using FOp = spec::FieldTest::Op;

const char* value_kind_name(ValueKind kind) {
  switch (kind) {
    case ValueKind::Array: return "an array";
    case ValueKind::Object: return "an object";
    case ValueKind::Number: return "a number";
    case ValueKind::String: return "a string";
    case ValueKind::Bool: return "a Boolean";
    case ValueKind::Null: return "null";
  }
  return "a value";
}

namespace {

const char* expected_for(const spec::FieldTest& t) {
  if (t.op == FOp::Truthy) return "a Boolean or number";
  if (t.op == FOp::Bind) return "a string, number or Boolean to bind";
  if (t.op == FOp::Value) return "a number (or a Boolean, 1 or 0)";
  switch (t.value.kind) {
    case spec::Literal::Kind::Bool: return "a Boolean or number";
    case spec::Literal::Kind::Number: return "a number";
    case spec::Literal::Kind::String: return "a string";
  }
  return "a value";
}

}  // namespace

std::string wrong_type_problem(const spec::FieldTest& t, ValueKind kind) {
  if (t.op == FOp::Value)  // a hidden test: name what reads it
    return "field \"" + t.key() + "\" is " + value_kind_name(kind) + ", but an expression reads it, which needs " +
           expected_for(t);
  return "field \"" + t.key() + "\" is " + value_kind_name(kind) + ", but {" + t.to_string() + "} needs " +
         expected_for(t);
}

namespace {

// Reelay 25 reads a Boolean as the number 1 or 0 wherever a number is tested
// ({flag > 0}, {flag == 1}): the same field then reads the same whether its
// sender wrote it as a JSON Boolean or a ROS 2 bool/uint8.
FieldValue as_number(const FieldValue& v) {
  if (v.kind != ValueKind::Bool) return v;
  FieldValue n;
  n.kind = ValueKind::Number;
  n.d = v.b ? 1 : 0;
  return n;
}

// A Boolean test ({p}, {p: true}, {p: false}) reads its field as Python's
// bool() does, as Reelay 25 does: a number is true unless 0 (NaN is true),
// null is false. So a 0/1 flag in a uint8 field works as one. -1: a string,
// array or object, which no Boolean test can read.
int truth_of(const FieldValue& v) {
  switch (v.kind) {
    case ValueKind::Bool: return v.b;
    case ValueKind::Number: return v.d != 0;
    case ValueKind::Null: return 0;
    default: return -1;
  }
}

}  // namespace

int evaluate_test(const spec::FieldTest& t, const FieldValue& field) {
  const auto lit = t.value.kind;
  // A Boolean counts 1 or 0 against a number literal; a Boolean literal reads the field's truth.
  FieldValue converted;
  const FieldValue& v = lit == spec::Literal::Kind::Number && field.kind == ValueKind::Bool
                            ? (converted = as_number(field))
                            : field;
  const bool number = v.kind == ValueKind::Number;
  switch (t.op) {
    case FOp::Present: return 1;
    case FOp::Value: return number || v.kind == ValueKind::Bool ? 1 : -1;  // null: no value (as missing)
    case FOp::Bind:  // binds scalars; null is no value (as a missing field)
      return v.kind == ValueKind::String || v.kind == ValueKind::Number || v.kind == ValueKind::Bool ? 1 : -1;
    case FOp::Truthy: return truth_of(v);
    case FOp::Eq:
    case FOp::Ne: {
      int eq = -1;
      if (lit == spec::Literal::Kind::Bool) {
        const int truth = truth_of(v);
        if (truth >= 0) eq = truth == static_cast<int>(t.value.b);
      } else if (lit == spec::Literal::Kind::Number && number) eq = compare_test(FOp::Eq, v, t.value);
      else if (lit == spec::Literal::Kind::String && v.kind == ValueKind::String) eq = v.s == t.value.text;
      if (eq < 0) return -1;
      return t.op == FOp::Eq ? eq : !eq;
    }
    case FOp::Lt:
    case FOp::Le:
    case FOp::Gt:
    case FOp::Ge: return number ? compare_test(t.op, v, t.value) : -1;
  }
  return -1;
}

namespace {
// A margin that is NaN (a NaN operand, or inf - inf) takes the sign of the
// Boolean verdict, +inf or -inf: NaN makes every comparison false (but !=),
// so {x > c} with x NaN is -inf and and/or (min/max) never see a NaN, whose
// result would depend on the operands' order (docs/semantics.md, "Robustness").
double signed_margin(double m, const spec::FieldTest& t, const FieldValue& v) {
  if (!std::isnan(m)) return m;
  constexpr double inf = std::numeric_limits<double>::infinity();
  return evaluate_test(t, v) == 1 ? inf : -inf;
}
}  // namespace

double test_margin(const spec::FieldTest& t, const FieldValue& field) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  FieldValue converted;  // as evaluate_test: a Boolean against a number literal counts 1 or 0
  const FieldValue& v = t.value.kind == spec::Literal::Kind::Number && field.kind == ValueKind::Bool
                            ? (converted = as_number(field))
                            : field;
  const bool number = v.kind == ValueKind::Number && t.value.kind == spec::Literal::Kind::Number;
  switch (t.op) {
    case FOp::Truthy:
      if (v.kind == ValueKind::Bool) return v.b ? 1 : 0;
      if (v.kind == ValueKind::Number) return signed_margin(v.d, t, v);  // NaN is non-zero: true, +inf
      if (v.kind == ValueKind::Null) return 0;
      break;
    case FOp::Value:  // the number itself, what an expression computes with
      if (v.kind == ValueKind::Bool) return v.b ? 1 : 0;
      if (v.kind == ValueKind::Number) return v.d;
      return std::numeric_limits<double>::quiet_NaN();
    case FOp::Lt:
    case FOp::Le:
      if (number) return signed_margin(t.value.number - v.d, t, v);
      break;
    case FOp::Gt:
    case FOp::Ge:
      if (number) return signed_margin(v.d - t.value.number, t, v);
      break;
    case FOp::Eq:
    case FOp::Ne: {
      if (!number) break;
      const double gap = std::fabs(v.d - t.value.number);
      return signed_margin(t.op == FOp::Eq ? -gap : gap, t, v);
    }
    default: break;
  }
  const int b = evaluate_test(t, v);  // the rest is all or nothing
  if (b < 0) return std::numeric_limits<double>::quiet_NaN();
  return b ? inf : -inf;
}

// ---- Array quantifiers ----

void quant_start(const spec::FieldTest& t, QuantFold& fold) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  fold = QuantFold{};
  // The empty array: all is true (+inf, the min of nothing), any false (-inf).
  fold.margin = t.quant.kind == spec::ArrayQuant::Kind::All ? inf : -inf;
}

void quant_element(const spec::FieldTest& t, const FieldValue& v, uint32_t index, QuantFold& fold) {
  fold.seen = index + 1;
  const int r = evaluate_test(t, v);
  // null is no value here, as a missing field (there is no previous value of an element to keep)
  if (r < 0 || v.kind == ValueKind::Null) {
    if (fold.bad_element < 0) fold.bad_element = index, fold.bad_kind = v.kind;
    return;
  }
  ++fold.evaluated;
  fold.hits += static_cast<uint32_t>(r);
  const double m = test_margin(t, v);
  if (t.quant.kind == spec::ArrayQuant::Kind::All) fold.margin = std::min(fold.margin, m);
  else if (t.quant.kind == spec::ArrayQuant::Kind::Any) fold.margin = std::max(fold.margin, m);
}

namespace {

// The array part and the element part of a quantified path: "objects", ".distance".
void split_every(const spec::FieldTest& t, std::string& array, std::string& rest) {
  spec::FieldTest a;
  a.path = t.path;
  size_t i = 0;
  while (i < a.path.size() && !spec::is_every_part(a.path[i])) ++i;
  spec::FieldTest r;
  r.path.assign(a.path.begin() + static_cast<long>(std::min(i + 1, a.path.size())), a.path.end());
  a.path.resize(i);
  array = a.key();
  rest = r.key();
}

}  // namespace

int quant_finish(const spec::FieldTest& t, QuantFold& fold, uint32_t elements, double& margin, std::string& problem) {
  using K = spec::ArrayQuant::Kind;
  if (fold.bad_element >= 0) {
    std::string array, rest;
    split_every(t, array, rest);
    const std::string element = "element " + std::to_string(fold.bad_element) + " of \"" + array + "\"";
    const std::string what = fold.bad_missing ? "missing" : value_kind_name(fold.bad_kind);
    problem = rest.empty() ? element + " is " + what
                           : "field \"" + rest.substr(rest[0] == '.' ? 1 : 0) + "\" of " + element + " is " + what;
    problem += ", but {" + t.to_string() + "} needs a usable value in every element";
    return -1;
  }
  const double hits = fold.hits;
  switch (t.quant.kind) {
    case K::All: margin = fold.margin; return fold.hits == elements;
    case K::Any: margin = fold.margin; return fold.hits > 0;
    case K::Count: {  // as a number field compared with the count's literal
      const double k = t.quant.count_value;
      switch (static_cast<FOp>(t.quant.count_op)) {
        case FOp::Eq: margin = -std::fabs(hits - k); return hits == k;
        case FOp::Ne: margin = std::fabs(hits - k); return hits != k;
        case FOp::Lt: margin = k - hits; return hits < k;
        case FOp::Le: margin = k - hits; return hits <= k;
        case FOp::Gt: margin = hits - k; return hits > k;
        case FOp::Ge: margin = hits - k; return hits >= k;
        default: break;
      }
      break;
    }
    default: break;
  }
  return -1;
}

std::string not_an_array_problem(const spec::FieldTest& t, ValueKind kind) {
  std::string array, rest;
  split_every(t, array, rest);
  return "field \"" + array + "\" is " + value_kind_name(kind) + ", but {" + t.to_string() + "} needs an array";
}

}  // namespace rvc::io
