// What a field test ({speed > 3}, {gear == REVERSE}, {door: *}) makes of one
// field value, whatever the payload format: the JSON decoder and the CDR
// decoder both evaluate tests here, so a property gives the same verdicts on
// a message sent as JSON or as a typed sample.
#pragma once

#include <string>
#include <string_view>

#include "spec/ast.hpp"

namespace rvc::io {

enum class ValueKind : unsigned char { Null, Bool, Number, String, Array, Object };

struct FieldValue {
  ValueKind kind = ValueKind::Null;
  bool b = false;
  double d = 0;
  std::string_view s;
};

// 1 or 0: the test's value; -1: the value has a type the test cannot use
// (the test then keeps its previous value, or the message is refused in
// strict mode). Null reads as false for a truthiness test, as Reelay does.
int evaluate_test(const spec::FieldTest& test, const FieldValue& value);

// The test's robustness (Reelay's quantitative semantics): {x > c} and
// {x >= c}: x - c; {x < c}, {x <= c}: c - x; {x == c}: -|x - c|; {x != c}:
// |x - c|; a Boolean field {p}: 1 or 0; a number {x}: x; string and Boolean
// equality, presence: +inf or -inf. NaN: a type the test cannot use (as
// evaluate_test's -1).
double test_margin(const spec::FieldTest& test, const FieldValue& value);

// "field "speed" is a string, but {speed > 3} needs a number"
std::string wrong_type_problem(const spec::FieldTest& test, ValueKind kind);

const char* value_kind_name(ValueKind kind);  // "a number", "an array", "null"

}  // namespace rvc::io
