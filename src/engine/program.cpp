#include "engine/program.hpp"

#include "spec/spec_error.hpp"

namespace rvc::engine {
namespace {

struct Compiler {
  AtomTable& atoms;
  TimeModel model;
  const std::string& source;
  bool texts;
  Program program;
  std::vector<std::pair<std::string, int32_t>> scope;  // quantified variables in scope, innermost last

  [[noreturn]] void fail(const std::string& message, int column) { throw spec::SpecError(message, source, column); }

  int32_t emit(Instr instr, const spec::Node& node) {
    program.code.push_back(instr);
    program.text.push_back(texts ? spec::to_string(node) : std::string());
    return static_cast<int32_t>(program.code.size() - 1);
  }

  int32_t visit(const spec::Node& n) {
    using spec::Op;
    Instr in{};
    in.bounds = n.bounds;
    switch (n.op) {
      case Op::True: in.code = Code::True; return emit(in, n);
      case Op::False: in.code = Code::False; return emit(in, n);
      case Op::Test:
        in.code = Code::Atom;
        if (n.test.op == spec::FieldTest::Op::Bind) {
          in.code = Code::Bind;
          in.var = lookup(n.test.variable, n.column);
        }
        in.atom = atoms.intern(n.test);
        return emit(in, n);
      case Op::Exists:
      case Op::Forall: return quantify(n, 0);
      case Op::Pre:
        if (model == TimeModel::Dense)
          fail("'pre' has no meaning in dense time (there is no previous step); use once[a:b] or discrete time",
               n.column);
        in.code = Code::Pre;
        break;
      case Op::Not: in.code = Code::Not; break;
      case Op::Once: in.code = Code::Once; break;
      case Op::Historically: in.code = Code::Historically; break;
      case Op::And: in.code = Code::And; break;
      case Op::Or: in.code = Code::Or; break;
      case Op::Implies: in.code = Code::Implies; break;
      case Op::Since: in.code = Code::Since; break;
      case Op::Eventually:
      case Op::Always:
      case Op::Until:
      case Op::Next:  // spec/pastify.hpp rewrites them first (engine::Checker)
        fail(std::string("'") + spec::op_name(n.op) + "' reached the compiler without its rewrite into past operators",
             n.column);
    }
    in.a = visit(*n.left);
    if (n.right) in.b = visit(*n.right);
    return emit(in, n);
  }

  // The innermost variable of that name in scope.
  int32_t lookup(const std::string& name, int column) {
    for (auto it = scope.rbegin(); it != scope.rend(); ++it)
      if (it->first == name) return it->second;
    fail("variable '" + name + "' is not bound: put the test inside exists[" + name + "]. ... or forall[" + name +
             "]. ...",
         column);
  }

  // exists[x, y]. φ is exists[x]. exists[y]. φ: one instruction per variable.
  int32_t quantify(const spec::Node& n, size_t first) {
    if (program.variables.size() >= kMaxVariables)
      fail("more than " + std::to_string(kMaxVariables) + " quantified variables in one property (the limit)",
           n.column);
    const auto var = static_cast<int32_t>(program.variables.size());
    program.variables.push_back(n.variables[first]);
    scope.emplace_back(n.variables[first], var);
    Instr in{};
    in.code = n.op == spec::Op::Exists ? Code::Exists : Code::Forall;
    in.var = var;
    in.a = first + 1 < n.variables.size() ? quantify(n, first + 1) : visit(*n.left);
    scope.pop_back();
    return emit(in, n);
  }
};

}  // namespace

Program compile(const spec::Node& root, AtomTable& atoms, TimeModel model, const std::string& source, bool texts) {
  Compiler c{atoms, model, source, texts, {}, {}};
  c.visit(root);
  return std::move(c.program);
}

}  // namespace rvc::engine
