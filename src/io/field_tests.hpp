// What a field test ({speed > 3}, {gear == REVERSE}, {door: *}) makes of one
// field value, whatever the payload format: the JSON decoder and the CDR
// decoder both evaluate tests here, so a property gives the same verdicts on
// a message sent as JSON or as a typed sample.
#pragma once

#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

#include "spec/ast.hpp"

namespace rvc::io {

enum class ValueKind : unsigned char { Null, Bool, Number, String, Array, Object };

struct FieldValue {
  ValueKind kind = ValueKind::Null;
  bool b = false;
  double d = 0;          // a number's value (rounded, for an integer beyond 2^53)
  std::string_view s;
  spec::ExactInt exact;  // such an integer exactly: comparisons use it (spec/exact_number.hpp)
};

// A number's test against the test's literal, exactly: 1 or 0 (NaN: every
// comparison false but !=, as IEEE 754 has it).
inline int compare_test(spec::FieldTest::Op op, const FieldValue& v, const spec::Literal& lit) {
  const spec::Order o = spec::order_numbers(v.d, v.exact, lit.number, lit.exact);
  using Op = spec::FieldTest::Op;
  switch (op) {
    case Op::Eq: return o == spec::Equal;
    case Op::Ne: return o != spec::Equal;
    case Op::Lt: return o == spec::Less;
    case Op::Le: return o == spec::Less || o == spec::Equal;
    case Op::Gt: return o == spec::Greater;
    case Op::Ge: return o == spec::Greater || o == spec::Equal;
    default: return 1;  // Present
  }
}

// A JSON number token already read as the double d (simdjson validated it):
// an integer literal beyond 2^53 keeps its exact value, as Python's json
// reads integers. (Beyond the 64-bit range it stays the double.)
inline void set_json_number(FieldValue& v, std::string_view token, double d) {
  v.kind = ValueKind::Number;
  v.d = d;
  v.exact = {};
  while (!token.empty() && (token.back() == ' ' || token.back() == '\t' || token.back() == '\r' || token.back() == '\n'))
    token.remove_suffix(1);
  double exact_d;
  spec::ExactInt exact;
  if (std::fabs(d) >= spec::kTwo53 && spec::integer_literal(token, exact_d, exact)) v.d = exact_d, v.exact = exact;
}

// 1 or 0: the test's value; -1: the value has a type the test cannot use
// (the test then keeps its previous value, or the message is refused in
// strict mode). Null reads as false for a truthiness test, as Reelay does.
int evaluate_test(const spec::FieldTest& test, const FieldValue& value);

// The test's robustness (Reelay's quantitative semantics): {x > c} and
// {x >= c}: x - c; {x < c}, {x <= c}: c - x; {x == c}: -|x - c|; {x != c}:
// |x - c|; a Boolean field {p}: 1 or 0; a number {x}: x; string and Boolean
// equality, presence: +inf or -inf; Value (an expression's field): the
// number, a Boolean 1 or 0. A comparison never gives NaN: where the
// difference is NaN (a NaN field, inf - inf) the margin is +inf if the test
// holds, else -inf (NaN fails every comparison but !=). NaN is returned only
// for a type the test cannot use (as evaluate_test's -1) and for Value.
double test_margin(const spec::FieldTest& test, const FieldValue& value);

// An array quantifier's fold over the elements of one array (issue 29,
// spec::ArrayQuant): each element's test, then the atom's value and margin.
// An element without a value the test can use (its field missing, null, or
// of the wrong type) makes the whole atom unusable for this message: it
// keeps its previous value (with a warning), or strict mode rejects it.
struct QuantFold {
  uint32_t evaluated = 0;       // elements whose test had a value
  uint32_t hits = 0;            // ... that passed
  double margin = 0;            // all: min of the element margins; any: max
  uint32_t seen = 0;            // elements that had the field at all
  int64_t bad_element = -1;     // the first element without a usable value
  ValueKind bad_kind = ValueKind::Null;
  bool bad_missing = false;     // ... because its field is missing
};
// After element `index` was decoded: did it have the field?
inline void quant_element_done(QuantFold& fold, uint32_t index) {
  if (fold.seen > index) return;
  if (fold.bad_element < 0) fold.bad_element = index, fold.bad_missing = true;
  fold.seen = index + 1;
}
void quant_start(const spec::FieldTest& test, QuantFold& fold);
// One element's value (`index`: its position, for the error).
void quant_element(const spec::FieldTest& test, const FieldValue& value, uint32_t index, QuantFold& fold);
// The array had `elements` elements: the atom's value (1 or 0; -1 with
// `problem` set when some element had no usable value) and its margin.
int quant_finish(const spec::FieldTest& test, QuantFold& fold, uint32_t elements, double& margin,
                 std::string& problem);
// "field "ranges" is a string, but {all(ranges[*] > 0.2)} needs an array"
std::string not_an_array_problem(const spec::FieldTest& test, ValueKind kind);

// "field "speed" is a string, but {speed > 3} needs a number"
std::string wrong_type_problem(const spec::FieldTest& test, ValueKind kind);

const char* value_kind_name(ValueKind kind);  // "a number", "an array", "null"

}  // namespace rvc::io
