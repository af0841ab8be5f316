// A property compiled for evaluation: the AST flattened into an array of
// instructions in post-order (children before parents, root last), each
// naming its operands by index. Evaluating it is one pass over the array with
// a switch: no virtual call per node per event, no pointer chasing.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/atom_table.hpp"
#include "spec/ast.hpp"

namespace rvc::engine {

enum class TimeModel { Discrete, Dense };

enum class Code : uint8_t {
  True, False, Atom, Not, And, Or, Implies, Pre, Once, Historically, Since,
  // Data references (engine/data): {key: *x} and the quantifiers binding x.
  Bind, Exists, Forall,
};

// Quantified variables per property: each free variable multiplies the
// entries of a sub-formula by its distinct values (engine/data).
inline constexpr size_t kMaxVariables = 8;

struct Instr {
  Code code;
  int32_t a = -1, b = -1;  // operand instructions (a: unary/left, b: right)
  int32_t atom = -1;       // Code::Atom, Code::Bind: index into the atom table
  int32_t var = -1;        // Code::Bind, Exists, Forall: the variable, 0.. per property
  spec::Bounds bounds;     // temporal operators
};

struct Program {
  std::vector<Instr> code;
  std::vector<std::string> text;  // per instruction: its sub-formula in Rye (--explain)
  // Data references: each quantified variable, by index (a name bound twice,
  // `exists[x]. ... exists[x]. ...`, is two variables). Empty: none.
  std::vector<std::string> variables;
  bool has_data() const { return !variables.empty(); }
};

// Compiles a parsed property. Throws spec::SpecError (pointing into `source`)
// for constructs the chosen time model cannot evaluate. `texts` false leaves
// Program::text empty strings: a bounded-future rewrite (spec/pastify.hpp),
// which --explain refuses, has up to 65,000 nodes, and printing every
// sub-formula of it costs its size times its depth (seconds, 200 MB).
Program compile(const spec::Node& root, AtomTable& atoms, TimeModel model, const std::string& source,
                bool texts = true);

}  // namespace rvc::engine
