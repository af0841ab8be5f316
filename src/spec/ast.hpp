// The abstract syntax of Rye specifications (Reelay's expression format).
// The parser builds it once; each time model compiles it into its own flat
// evaluator, so nothing here knows about time.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "spec/exact_number.hpp"

namespace rvc::spec {

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

// A time interval [lo:hi] of a temporal operator; hi = infinity when open.
struct Bounds {
  double lo = 0;
  double hi = kInfinity;
  bool explicit_bounds = false;  // written as [..] in the spec
  bool unbounded() const { return lo == 0 && hi == kInfinity; }
};

// The right-hand side of one field test inside braces.
struct Literal {
  enum class Kind { Bool, Number, String } kind = Kind::Bool;
  bool b = false;
  double number = 0;
  ExactInt exact;  // an integer beyond 2^53, exactly (number is its rounded double)
  std::string text;
  bool bare_word = false;  // a String written without quotes ({gear: REVERSE}): may name a message constant
};

// Path parts naming an array element are written "[N]": no field name can
// be one, since the parser refuses a quoted key of that form.
bool is_index_part(const std::string& part);
uint32_t index_of_part(const std::string& part);  // "[12]" -> 12

// One test on one field: {p}, {p: false}, {x > 3}, {mode: "a"}, {m: *}, {id: *x}.
struct FieldTest {
  enum class Op { Truthy, Eq, Ne, Lt, Le, Gt, Ge, Present, Bind };
  // "a.b" -> {"a", "b"}; quoted keys stay whole; an array element is its own
  // part: "ranges[0].x" -> {"ranges", "[0]", "x"} (see is_index_part).
  std::vector<std::string> path;
  Op op = Op::Truthy;
  Literal value;                  // for Eq .. Ge
  std::string variable;           // for Bind ({id: *x})
  int column = 0;

  std::string key() const;        // path joined with '.'
  std::string to_string() const;  // canonical text, used to share atoms between properties
};

enum class Op {
  True, False, Test,             // leaves
  Not, Pre, Once, Historically,  // unary
  And, Or, Implies, Since,       // binary
  Exists, Forall,                // data quantifiers (parsed; not yet evaluated)
};

struct Node {
  Op op;
  int column = 0;  // 1-based column of the operator in the spec text
  Bounds bounds;   // Pre, Once, Historically, Since
  FieldTest test;  // Test
  std::vector<std::string> variables;  // Exists, Forall
  std::unique_ptr<Node> left, right;   // unary operators use left only

  bool is_temporal() const { return op == Op::Pre || op == Op::Once || op == Op::Historically || op == Op::Since; }
};

using NodePtr = std::unique_ptr<Node>;

// Fully parenthesized canonical text; round-trips through the parser.
std::string to_string(const Node& node);
const char* op_name(Op op);

}  // namespace rvc::spec
