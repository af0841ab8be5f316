#include "runtime/typed_specs.hpp"

#include <functional>
#include <optional>
#include <map>

#include "spec/parser.hpp"
#include "spec/spec_error.hpp"

namespace rvc::runtime {
namespace {

using msg::ArrayKind;
using msg::MessageType;
using msg::Prim;

std::string list_fields(const MessageType& t) {
  std::string s;
  for (const auto& f : t.fields) s += (s.empty() ? "" : ", ") + f.name;
  return s.empty() ? "none" : s;
}

std::string list_constants(const MessageType& t) {
  std::string s;
  for (const auto& c : t.constants) s += (s.empty() ? "" : ", ") + c.name;
  return s.empty() ? "none" : s;
}

// The value a test compares with, or nullopt when it stays as written.
std::optional<spec::Literal> check_test(const spec::FieldTest& test, const MessageType& root, bool dense,
                                        const std::string& time_field, const std::string& text) {
  if (dense && test.path.size() == 1 && test.path[0] == time_field) return std::nullopt;

  // Walk the path: `holder` is the message whose field was named last (its
  // constants are the ones a bare word may name), `value` the type of what
  // the path has reached so far (a field, or an element of an array field).
  const MessageType* holder = &root;
  msg::FieldType value;
  std::string reached;  // the path so far, for errors
  for (size_t i = 0; i < test.path.size(); ++i) {
    const std::string& part = test.path[i];
    if (spec::is_every_part(part)) {  // every element, in an array quantifier
      if (value.array == ArrayKind::None)
        throw spec::SpecError("field '" + test.key() + "': '" + reached + "' is " + value.to_string() +
                                  ", not an array",
                              text, test.column);
      value.array = ArrayKind::None;
      value.array_size = 0;
      reached += part;
      continue;
    }
    if (spec::is_index_part(part)) {
      if (value.array == ArrayKind::None)
        throw spec::SpecError("field '" + test.key() + "': '" + reached + "' is " + value.to_string() +
                                  ", not an array",
                              text, test.column);
      const uint32_t index = spec::index_of_part(part);
      if (value.array != ArrayKind::Unbounded && index >= value.array_size)
        throw spec::SpecError("field '" + test.key() + "': index " + std::to_string(index) + " is past the end of '" +
                                  reached + "' (" + value.to_string() + ")",
                              text, test.column);
      value.array = ArrayKind::None;  // an element
      value.array_size = 0;
      reached += part;
      continue;
    }
    if (i > 0) {
      if (value.prim != Prim::Message || value.array != ArrayKind::None)
        throw spec::SpecError("field '" + test.key() + "': '" + reached + "' is " + value.to_string() +
                                  ", not a message",
                              text, test.column);
      holder = value.message;
    }
    const msg::Field* field = nullptr;
    for (const auto& f : holder->fields)
      if (f.name == part) field = &f;
    if (!field) {
      std::string where = i ? "'" + reached + "' (" + holder->full_name() + ")" : holder->full_name();
      throw spec::SpecError("no field '" + part + "' in " + where + "; its fields: " + list_fields(*holder), text,
                            test.column);
    }
    value = field->type;
    reached += (reached.empty() ? "" : ".") + part;
  }
  const bool numeric = value.array == ArrayKind::None && value.prim != Prim::Message && value.prim != Prim::String &&
                       value.prim != Prim::WString;
  if (test.op == spec::FieldTest::Op::Value && !numeric)  // a field of an expression (issue 29)
    throw spec::SpecError("field '" + test.key() + "' is " + value.to_string() +
                              ": an expression computes with numbers (and Booleans, as 1 or 0)",
                          text, test.column);
  if (test.op == spec::FieldTest::Op::Bind && (value.array != ArrayKind::None || value.prim == Prim::Message))
    throw spec::SpecError("field '" + test.key() + "' is " + value.to_string() +
                              ": a reference binds a string, number or Boolean field",
                          text, test.column);
  if (!numeric || test.value.kind != spec::Literal::Kind::String || !test.value.bare_word) return std::nullopt;
  const msg::Constant* c = holder->constant(test.value.text);
  if (!c) {
    throw spec::SpecError("'" + test.value.text + "' is not a constant of " + holder->full_name() +
                              " (its constants: " + list_constants(*holder) + ")",
                          text, test.column);
  }
  spec::Literal lit;
  if (c->prim == Prim::Bool) {
    lit.kind = spec::Literal::Kind::Bool;
    lit.b = c->number != 0;
  } else {
    lit.kind = spec::Literal::Kind::Number;
    lit.number = c->number;
    spec::integer_literal(c->text, lit.number, lit.exact);  // a 64-bit constant, exactly (its text is decimal)
  }
  return lit;
}

}  // namespace

void bind_message_type(engine::AtomTable& atoms, const std::vector<engine::PropertySpec>& properties,
                       const MessageType& type, bool dense, const std::string& time_field,
                       const std::string& input) {
  std::map<std::string, spec::Literal> resolved;  // canonical test text -> its value
  spec::ParseOptions options;
  options.dense = dense;
  for (const auto& p : properties) {
    try {
      spec::NodePtr ast = spec::parse(p.spec, options);
      std::function<void(const spec::Node&)> walk = [&](const spec::Node& n) {
        if (n.op == spec::Op::Test) {
          spec::FieldTest test = n.test;
          if (test.is_expr()) {  // each field it reads, as a number, at the field's column
            std::vector<const spec::Expr*> fields;
            spec::expr_fields(*test.lhs, fields);
            spec::expr_fields(*test.rhs, fields);
            for (const spec::Expr* f : fields) {
              spec::FieldTest leaf;
              leaf.path = f->path;
              leaf.op = spec::FieldTest::Op::Value;
              leaf.column = f->column;
              if (!input.empty() && (leaf.path.size() < 2 || leaf.path[0] != input)) continue;
              if (!input.empty()) leaf.path.erase(leaf.path.begin());
              check_test(leaf, type, dense && input.empty(), time_field, p.spec);
            }
            return;
          }
          if (test.is_timed()) {
            // A timing atom reads no field; an aggregate's field must exist.
            if (test.timed.kind != spec::Timed::Kind::Aggregate || test.timed.of_arrivals) test.path.clear();
            test.timed = {};
            test.op = spec::FieldTest::Op::Truthy;
          }
          if (test.path.empty()) {
            if (n.left) walk(*n.left);
            return;
          }
          // One input of several: its tests, seen as the input sees them.
          const bool mine = input.empty() || (test.path.size() > 1 && test.path[0] == input);
          if (!input.empty() && mine) test.path.erase(test.path.begin());
          if (mine) {
            if (auto lit = check_test(test, type, dense && input.empty(), time_field, p.spec))
              resolved[test.to_string()] = *lit;
          }
        }
        if (n.left) walk(*n.left);
        if (n.right) walk(*n.right);
      };
      walk(*ast);
    } catch (const spec::SpecError& e) {
      throw spec::SpecError("in property '" + p.name + "': " + e.message(), e.source(), e.column());
    }
  }
  for (size_t id = 0; id < atoms.size(); ++id) {
    auto it = resolved.find(atoms.tests()[id].to_string());
    if (it != resolved.end()) atoms.set_value(static_cast<int>(id), it->second);
  }
}

void bind_message_type(engine::Checker& checker, const std::vector<engine::PropertySpec>& properties,
                       const MessageType& type, bool dense, const std::string& time_field) {
  bind_message_type(checker.atoms(), properties, type, dense, time_field, {});
}

}  // namespace rvc::runtime
