// Parser for Rye, Reelay's specification syntax.
//
// Precedence, tightest first (matches Reelay 25, checked by differential tests):
//   atoms {..}, true, false, ( )
//   unary:  not ! pre Y once P historically H          (prefix, stackable)
//           eventually[a:b] always[a:b] next            (bounded future, issue 29: spec/pastify.hpp)
//   since S [a:b], until[a:b]                          (non-associative: chains need parentheses)
//   and &&                                             (left-associative)
//   or ||                                              (left-associative)
//   implies ->                                         (right-associative)
//   exists[x]. / forall[x].                            (body extends as far right as possible)
#pragma once

#include <string>

#include "spec/ast.hpp"
#include "spec/spec_error.hpp"

namespace rvc::spec {

struct ParseOptions {
  bool dense = false;  // dense time accepts real-valued bounds; discrete needs integers
  bool robustness = false;  // --robustness: refuses what has no piecewise-constant margin (dense @age)
};

// Throws SpecError (with the column) on any problem; never returns null.
NodePtr parse(const std::string& text, const ParseOptions& options = {});

}  // namespace rvc::spec
