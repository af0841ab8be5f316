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
  // Dense time: the bounds in integer nanoseconds, read exactly from their
  // text (spec/exact_time.hpp; at most kExactSpanNs, so a double holds them
  // exactly). The engine's dense monitors run on these (engine::Checker
  // rescales its copy of the formula); lo/hi stay the written seconds.
  double lo_ns = 0;
  double hi_ns = kInfinity;
  bool in_ns = false;  // lo/hi hold the nanoseconds (the checker's copy): printed as seconds
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
// "[*]": every element of the array, in an array quantifier (ArrayQuant).
inline constexpr const char* kEveryElement = "[*]";
inline bool is_every_part(const std::string& part) { return part == kEveryElement; }

// An array quantifier (issue 29): the test's path has one "[*]" part, and
// the test (op, value) is asked of each element; the atom is
//   all(ranges[*] > 0.2)                    every element passes (true for none)
//   any(objects[*].distance < 2)            some element passes (false for none)
//   count(objects[*].distance < 2) >= 3     how many pass, compared with a number
struct ArrayQuant {
  enum class Kind : uint8_t { None, All, Any, Count };
  Kind kind = Kind::None;
  uint8_t count_op = 0;  // Count: a FieldTest::Op (Eq .. Ge) comparing the count
  double count_value = 0;
};
const char* quant_name(ArrayQuant::Kind kind);  // "all"

// A timing atom or a window aggregate (issue 26): not a field of the message
// but what the runtime knows about an input's messages over time.
//   {steer.@arrived}                 a message of input steer is in this step
//   {steer.@age <= 0.1}              time since its last message
//   {steer.@latency < 0.05}          arrival - stamp of its last message
//   {count[0:1](steer.@arrived) >= 20}, {avg[0:2](steer.speed) > 3}
// The input name is left out with one unnamed input ({@age <= 0.2}).
struct Timed {
  // Expr: an arithmetic comparison ({abs(a.x - b.x) < 0.05}; FieldTest::lhs, rhs),
  // valued by the runtime like the others from its fields' committed values.
  enum class Kind : uint8_t { None, Arrived, Age, Latency, Aggregate, Expr };
  enum class Func : uint8_t { Count, Sum, Avg, Min, Max };
  Kind kind = Kind::None;
  Func func = Func::Count;  // Aggregate
  Bounds window;            // Aggregate: the past window (steps, or seconds in dense time)
  bool of_arrivals = false; // Aggregate over x.@arrived (each message counts 1), else over the field `path`
};
const char* timed_name(Timed::Kind kind);  // "@age"
const char* func_name(Timed::Func func);   // "count"

// An arithmetic expression over fields and numbers (issue 29): one side of
// {abs(steer.angle - cmd.angle) < 0.05}, {a.x + 2 * b.x >= c}, {min(x, y) > 0}.
// Evaluated in double (engine/timed/expr_atoms.hpp); the tree is shared
// between copies of its test, never changed after parsing.
struct Expr {
  enum class Kind : uint8_t { Number, Field, Neg, Add, Sub, Mul, Div, Abs, Min, Max };
  Kind kind = Kind::Number;
  double number = 0;               // Number (a double: expressions compute in double)
  std::vector<std::string> path;   // Field: as FieldTest::path
  std::vector<std::shared_ptr<const Expr>> args;  // operands (Neg, Abs: one; the rest: two)
  int column = 0;                  // where it starts in the spec text
};
using ExprPtr = std::shared_ptr<const Expr>;
std::string to_string(const Expr& e);  // canonical text, round-trips through the parser
// The fields an expression reads, each once, in the order written.
void expr_fields(const Expr& e, std::vector<const Expr*>& out);

// One test on one field: {p}, {p: false}, {x > 3}, {mode: "a"}, {m: *}, {id: *x}.
// Timing atoms and aggregates are tests too (see Timed): `path` names the
// input then the atom ({"steer", "@age"}), or an aggregate's field.
struct FieldTest {
  // Value: the field's number, for an expression (a hidden test the runtime
  // adds for each field an Expr reads; a Boolean counts 1 or 0).
  enum class Op { Truthy, Eq, Ne, Lt, Le, Gt, Ge, Present, Bind, Value };
  // "a.b" -> {"a", "b"}; quoted keys stay whole; an array element is its own
  // part: "ranges[0].x" -> {"ranges", "[0]", "x"} (see is_index_part).
  std::vector<std::string> path;
  Op op = Op::Truthy;
  Literal value;                  // for Eq .. Ge
  std::string variable;           // for Bind ({id: *x})
  int column = 0;
  Timed timed;                    // kind None: an ordinary field test
  ExprPtr lhs, rhs;               // Timed::Kind::Expr: `lhs op rhs` (path is empty)
  ArrayQuant quant;               // kind None: not an array quantifier

  bool is_timed() const { return timed.kind != Timed::Kind::None; }
  bool is_expr() const { return timed.kind == Timed::Kind::Expr; }
  bool is_quantified() const { return quant.kind != ArrayQuant::Kind::None; }
  // The input a timing atom or aggregate is about ("" with one unnamed input).
  std::string timed_input() const;
  std::string key() const;        // path joined with '.'
  std::string to_string() const;  // canonical text, used to share atoms between properties
};

enum class Op {
  True, False, Test,             // leaves
  Not, Pre, Once, Historically,  // unary
  And, Or, Implies, Since,       // binary
  Exists, Forall,                // data quantifiers (parsed; not yet evaluated)
  // Bounded future (issue 29): rewritten into past operators with a delay
  // (spec/pastify.hpp) before compiling; never reach an engine directly.
  Eventually, Always, Until, Next,
};

struct Node {
  Op op;
  int column = 0;  // 1-based column of the operator in the spec text
  Bounds bounds;   // Pre, Once, Historically, Since, Eventually, Always, Until
  FieldTest test;  // Test
  std::vector<std::string> variables;  // Exists, Forall
  std::unique_ptr<Node> left, right;   // unary operators use left only

  bool is_temporal() const { return op == Op::Pre || op == Op::Once || op == Op::Historically || op == Op::Since; }
  bool is_future() const { return op == Op::Eventually || op == Op::Always || op == Op::Until || op == Op::Next; }
};

using NodePtr = std::unique_ptr<Node>;

// Fully parenthesized canonical text; round-trips through the parser.
std::string to_string(const Node& node);
const char* op_name(Op op);

}  // namespace rvc::spec
