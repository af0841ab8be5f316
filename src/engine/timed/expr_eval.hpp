// An atom's arithmetic expression (spec::Expr, issue 29) compiled to postfix
// code over the numbers of its fields, evaluated in double with IEEE 754
// rules: x / 0 is ±inf, 0 / 0 and inf - inf are NaN (the comparison is then
// false, docs/semantics.md "Arithmetic in atoms").
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "spec/ast.hpp"

namespace rvc::engine::timed {

class CompiledExpr {
 public:
  // `leaf_of` gives a field's index in the array eval() reads.
  CompiledExpr(const spec::Expr& e, const std::function<int(const std::vector<std::string>&)>& leaf_of) {
    compile(e, leaf_of);
  }

  double eval(const double* leaves, std::vector<double>& stack) const {
    stack.clear();
    using K = spec::Expr::Kind;
    for (const Code& c : code_) {
      switch (c.kind) {
        case K::Number: stack.push_back(c.number); continue;
        case K::Field: stack.push_back(leaves[c.leaf]); continue;
        case K::Neg: stack.back() = -stack.back(); continue;
        case K::Abs: stack.back() = std::fabs(stack.back()); continue;
        default: break;
      }
      const double b = stack.back();
      stack.pop_back();
      double& a = stack.back();
      switch (c.kind) {
        case K::Add: a = a + b; break;
        case K::Sub: a = a - b; break;
        case K::Mul: a = a * b; break;
        case K::Div: a = a / b; break;
        // NaN in, NaN out (std::min/max would pick a side depending on the order).
        case K::Min: a = std::isnan(a) || std::isnan(b) ? NAN : std::min(a, b); break;
        case K::Max: a = std::isnan(a) || std::isnan(b) ? NAN : std::max(a, b); break;
        default: break;
      }
    }
    return stack.back();
  }

 private:
  struct Code {
    spec::Expr::Kind kind;
    double number = 0;
    int leaf = -1;
  };
  void compile(const spec::Expr& e, const std::function<int(const std::vector<std::string>&)>& leaf_of) {
    for (const auto& a : e.args) compile(*a, leaf_of);
    Code c{e.kind, e.number, -1};
    if (e.kind == spec::Expr::Kind::Field) c.leaf = leaf_of(e.path);
    code_.push_back(c);
  }
  std::vector<Code> code_;
};

}  // namespace rvc::engine::timed
