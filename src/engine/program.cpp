#include "engine/program.hpp"

#include "spec/spec_error.hpp"

namespace rvc::engine {
namespace {

struct Compiler {
  AtomTable& atoms;
  TimeModel model;
  const std::string& source;
  Program program;

  [[noreturn]] void fail(const std::string& message, int column) { throw spec::SpecError(message, source, column); }

  int32_t emit(Instr instr, const spec::Node& node) {
    program.code.push_back(instr);
    program.text.push_back(spec::to_string(node));
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
        if (n.test.op == spec::FieldTest::Op::Bind)
          fail("data references ({key: *var}) are not yet supported by rvc's monitors", n.column);
        in.code = Code::Atom;
        in.atom = atoms.intern(n.test);
        return emit(in, n);
      case Op::Exists:
      case Op::Forall:
        fail(std::string("'") + spec::op_name(n.op) + "' (data quantifiers) is not yet supported by rvc's monitors",
             n.column);
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
    }
    in.a = visit(*n.left);
    if (n.right) in.b = visit(*n.right);
    return emit(in, n);
  }
};

}  // namespace

Program compile(const spec::Node& root, AtomTable& atoms, TimeModel model, const std::string& source) {
  Compiler c{atoms, model, source, {}};
  c.visit(root);
  return std::move(c.program);
}

}  // namespace rvc::engine
