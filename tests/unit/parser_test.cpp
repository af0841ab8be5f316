// Rye parser: one group per grammar rule, precedence through the canonical
// text of spec::to_string, error messages with exact columns and carets, and
// a fuzz pass that must only ever produce SpecError.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "engine/checker.hpp"
#include "spec/ast.hpp"
#include "spec/parser.hpp"
#include "spec/spec_error.hpp"

namespace rvc::spec {
namespace {

using FOp = FieldTest::Op;

std::string canon(const std::string& text, bool dense = false) {
  ParseOptions o;
  o.dense = dense;
  return to_string(*parse(text, o));
}

// The single field test of an atom-only spec.
FieldTest atom(const std::string& text) {
  NodePtr n = parse(text);
  EXPECT_EQ(n->op, Op::Test) << text;
  return n->test;
}

// ---------------------------------------------------------------- atoms {..}

TEST(ParserAtom, BareFieldIsTruthyTest) {
  FieldTest t = atom("{p}");
  EXPECT_EQ(t.op, FOp::Truthy);
  ASSERT_EQ(t.path.size(), 1u);
  EXPECT_EQ(t.path[0], "p");
  EXPECT_EQ(t.column, 2);  // the key starts right after '{'
  EXPECT_EQ(canon("{p}"), "{p}");
  EXPECT_EQ(canon("{  p  }"), "{p}");  // whitespace inside braces is insignificant
  EXPECT_EQ(canon("{_under_score9}"), "{_under_score9}");
}

TEST(ParserAtom, ColonBooleanIsEquality) {
  FieldTest t = atom("{p: false}");
  EXPECT_EQ(t.op, FOp::Eq);
  EXPECT_EQ(t.value.kind, Literal::Kind::Bool);
  EXPECT_FALSE(t.value.b);
  EXPECT_EQ(canon("{p: false}"), "{p == false}");
  EXPECT_EQ(canon("{p:true}"), "{p == true}");
}

TEST(ParserAtom, AllSixComparisons) {
  struct Case {
    const char* text;
    FOp op;
    const char* canonical;
  };
  const Case cases[] = {
      {"{speed < 20.5}", FOp::Lt, "{speed < 20.5}"},   {"{speed <= 20.5}", FOp::Le, "{speed <= 20.5}"},
      {"{speed > 20.5}", FOp::Gt, "{speed > 20.5}"},   {"{speed >= 20.5}", FOp::Ge, "{speed >= 20.5}"},
      {"{speed == 20.5}", FOp::Eq, "{speed == 20.5}"}, {"{speed != 20.5}", FOp::Ne, "{speed != 20.5}"},
      {"{speed>20.5}", FOp::Gt, "{speed > 20.5}"},  // no spaces needed
  };
  for (const Case& c : cases) {
    FieldTest t = atom(c.text);
    EXPECT_EQ(t.op, c.op) << c.text;
    EXPECT_EQ(t.value.kind, Literal::Kind::Number) << c.text;
    EXPECT_DOUBLE_EQ(t.value.number, 20.5) << c.text;
    EXPECT_EQ(canon(c.text), c.canonical);
  }
}

TEST(ParserAtom, NumberForms) {
  EXPECT_DOUBLE_EQ(atom("{x > -2.5}").value.number, -2.5);
  EXPECT_DOUBLE_EQ(atom("{x > +3}").value.number, 3.0);
  EXPECT_DOUBLE_EQ(atom("{x > 1e3}").value.number, 1000.0);
  EXPECT_DOUBLE_EQ(atom("{x > 2.5E-1}").value.number, 0.25);
  EXPECT_DOUBLE_EQ(atom("{x > .5}").value.number, 0.5);
  EXPECT_EQ(canon("{x >= +3}"), "{x >= 3}");  // shortest form, no sign
  EXPECT_EQ(canon("{x < 1e3}"), "{x < 1000}");
  EXPECT_EQ(canon("{x == -0.125}"), "{x == -0.125}");
}

TEST(ParserAtom, QuotedAndBareStringValuesAreTheSame) {
  FieldTest quoted = atom("{mode: \"sport\"}");
  FieldTest bare = atom("{mode: sport}");
  EXPECT_EQ(quoted.op, FOp::Eq);
  EXPECT_EQ(bare.op, FOp::Eq);
  EXPECT_EQ(quoted.value.kind, Literal::Kind::String);
  EXPECT_EQ(bare.value.kind, Literal::Kind::String);  // Reelay reads a bare word as a string
  EXPECT_EQ(quoted.value.text, "sport");
  EXPECT_EQ(bare.value.text, "sport");
  EXPECT_EQ(canon("{mode: sport}"), "{mode == \"sport\"}");
  EXPECT_EQ(canon("{mode: \"sport\"}"), "{mode == \"sport\"}");
  EXPECT_EQ(canon("{mode != \"a b\"}"), "{mode != \"a b\"}");
  EXPECT_EQ(atom("{s: \"say \\\"hi\\\"\"}").value.text, "say \"hi\"");  // \" escapes a quote
  EXPECT_EQ(canon("{s: \"a\\\\b\"}"), "{s == \"a\\\\b\"}");          // a backslash stays escaped
}

TEST(ParserAtom, PresenceTest) {
  FieldTest t = atom("{mode: *}");
  EXPECT_EQ(t.op, FOp::Present);
  EXPECT_EQ(canon("{mode: *}"), "{mode: *}");
  EXPECT_EQ(canon("{ mode :* }"), "{mode: *}");
}

TEST(ParserAtom, CommaIsConjunctionOfTests) {
  NodePtr n = parse("{k1: true, k2 < 3}");
  ASSERT_EQ(n->op, Op::And);
  EXPECT_EQ(n->column, 1);  // the conjunction points at its '{'
  ASSERT_EQ(n->left->op, Op::Test);
  ASSERT_EQ(n->right->op, Op::Test);
  EXPECT_EQ(n->left->test.key(), "k1");
  EXPECT_EQ(n->left->column, 2);
  EXPECT_EQ(n->right->test.key(), "k2");
  EXPECT_EQ(n->right->column, 12);  // "{k1: true, " is 11 characters
  EXPECT_EQ(to_string(*n), "({k1 == true} and {k2 < 3})");
  // Three tests associate to the left like 'and'.
  EXPECT_EQ(canon("{a, b, c: *}"), "(({a} and {b}) and {c: *})");
}

TEST(ParserAtom, NestedPath) {
  FieldTest t = atom("{a.b > 1}");
  ASSERT_EQ(t.path.size(), 2u);
  EXPECT_EQ(t.path[0], "a");
  EXPECT_EQ(t.path[1], "b");
  EXPECT_EQ(t.key(), "a.b");
  EXPECT_EQ(canon("{pose.position.x >= 0}"), "{pose.position.x >= 0}");
  EXPECT_EQ(atom("{pose.position.x >= 0}").path.size(), 3u);
}

TEST(ParserAtom, QuotedKeys) {
  FieldTest spaced = atom("{\"my key\" > 1}");
  ASSERT_EQ(spaced.path.size(), 1u);
  EXPECT_EQ(spaced.path[0], "my key");
  EXPECT_EQ(canon("{\"my key\" > 1}"), "{\"my key\" > 1}");
  // A quoted key with a dot is one key, not a path: it must not share an atom with {a.b}.
  FieldTest dotted = atom("{\"a.b\"}");
  ASSERT_EQ(dotted.path.size(), 1u);
  EXPECT_EQ(dotted.path[0], "a.b");
  EXPECT_EQ(canon("{\"a.b\"}"), "{\"a.b\"}");
  EXPECT_NE(canon("{\"a.b\"}"), canon("{a.b}"));
  // A plain identifier in quotes needs no quotes in the canonical form.
  EXPECT_EQ(canon("{\"p\"}"), "{p}");
  // Quoted segments mix with plain ones.
  FieldTest mixed = atom("{a.\"b c\".d: *}");
  ASSERT_EQ(mixed.path.size(), 3u);
  EXPECT_EQ(mixed.path[1], "b c");
  EXPECT_EQ(canon("{a.\"b c\".d: *}"), "{a.\"b c\".d: *}");
  EXPECT_EQ(canon("{\"9lives\"}"), "{\"9lives\"}");  // cannot start an identifier
  EXPECT_EQ(atom("{\"q\\\"uote\"}").path[0], "q\"uote");
  EXPECT_EQ(canon("{\"q\\\"uote\"}"), "{\"q\\\"uote\"}");
}

TEST(ParserAtom, KeywordsAreOrdinaryKeysInsideBraces) {
  EXPECT_EQ(canon("{once}"), "{once}");
  EXPECT_EQ(canon("{since > 1}"), "{since > 1}");
  EXPECT_EQ(canon("{S} S {Y}"), "({S} since {Y})");
}

TEST(ParserAtom, DataReferenceParses) {
  FieldTest t = atom("{id: *x}");
  EXPECT_EQ(t.op, FOp::Bind);
  EXPECT_EQ(t.variable, "x");
  EXPECT_EQ(canon("{id: *x}"), "{id: *x}");
  EXPECT_EQ(canon("{id: * x}"), "{id: *x}");
}

TEST(ParserQuantifier, ExistsAndForallParse) {
  NodePtr n = parse("exists[x]. {id: *x}");
  EXPECT_EQ(n->op, Op::Exists);
  EXPECT_EQ(n->column, 1);
  ASSERT_EQ(n->variables.size(), 1u);
  EXPECT_EQ(n->variables[0], "x");
  EXPECT_EQ(to_string(*n), "(exists[x]. {id: *x})");
  EXPECT_EQ(canon("forall[x, y]. {a: *x, b: *y}"), "(forall[x, y]. ({a: *x} and {b: *y}))");
  EXPECT_EQ(canon("exists[x]. forall[y]. {a: *x} -> {b: *y}"),
            "(exists[x]. (forall[y]. ({a: *x} implies {b: *y})))");  // the body extends to the right
  EXPECT_EQ(canon("{p} and (exists[x]. {id: *x})"), "({p} and (exists[x]. {id: *x}))");
}

// Compile rejects references to variables no quantifier binds, pointing at them.
void expect_compile_error(const std::string& spec, engine::TimeModel model, const std::string& fragment, int column) {
  engine::Checker checker(model, false, nullptr);
  try {
    checker.add_property({"p", spec});
    ADD_FAILURE() << "compiled: " << spec;
  } catch (const SpecError& e) {
    EXPECT_NE(e.message().find(fragment), std::string::npos) << spec << " -> " << e.message();
    EXPECT_EQ(e.column(), column) << spec << " -> " << e.what();
  }
}

TEST(ParserQuantifier, CompileRejectsUnboundVariablesWithColumn) {
  using engine::TimeModel;
  expect_compile_error("{id: *x}", TimeModel::Discrete, "variable 'x' is not bound", 2);
  // "{p} -> " is 7 characters; the key 'id' starts at column 9.
  expect_compile_error("{p} -> {id: *x}", TimeModel::Dense, "variable 'x' is not bound", 9);
  // Bound on the left only: the right side's x is free.
  expect_compile_error("(exists[x]. {id: *x}) and {o: *x}", TimeModel::Discrete, "variable 'x' is not bound", 28);
  expect_compile_error("exists[x]. {id: *y}", TimeModel::Discrete, "variable 'y' is not bound", 13);
  expect_compile_error("exists[a,b,c,d,e,f,g,h,i]. {id: *a}", TimeModel::Discrete, "more than 8 quantified variables", 1);
  engine::Checker robust(TimeModel::Discrete, false, nullptr);
  robust.enable_robustness();
  EXPECT_THROW(robust.add_property({"p", "exists[x]. {id: *x}"}), SpecError);
}

// ---------------------------------------------------------------- Boolean

TEST(ParserBoolean, Constants) {
  EXPECT_EQ(parse("true")->op, Op::True);
  EXPECT_EQ(parse("false")->op, Op::False);
  EXPECT_EQ(canon("true and false"), "(true and false)");
}

TEST(ParserBoolean, NotAndBang) {
  EXPECT_EQ(canon("not {p}"), "(not {p})");
  EXPECT_EQ(canon("!{p}"), "(not {p})");
  EXPECT_EQ(canon("! ! {p}"), "(not (not {p}))");
  EXPECT_EQ(canon("not not {p}"), "(not (not {p}))");
  EXPECT_EQ(canon("not{p}"), "(not {p})");  // a brace ends the keyword
}

TEST(ParserBoolean, AndSpellings) {
  EXPECT_EQ(canon("{a} and {b}"), "({a} and {b})");
  EXPECT_EQ(canon("{a} && {b}"), "({a} and {b})");
  EXPECT_EQ(canon("{a}&&{b}"), "({a} and {b})");
  NodePtr n = parse("{a} and {b}");
  EXPECT_EQ(n->op, Op::And);
  EXPECT_EQ(n->column, 5);
}

TEST(ParserBoolean, OrSpellings) {
  EXPECT_EQ(canon("{a} or {b}"), "({a} or {b})");
  EXPECT_EQ(canon("{a} || {b}"), "({a} or {b})");
}

TEST(ParserBoolean, ImpliesSpellings) {
  EXPECT_EQ(canon("{a} implies {b}"), "({a} implies {b})");
  EXPECT_EQ(canon("{a} -> {b}"), "({a} implies {b})");
  EXPECT_EQ(canon("{a}->{b}"), "({a} implies {b})");
}

TEST(ParserBoolean, Parentheses) {
  EXPECT_EQ(canon("(({p}))"), "{p}");
  EXPECT_EQ(canon("({a} or {b}) and {c}"), "(({a} or {b}) and {c})");
  EXPECT_EQ(canon("{a} and ({b} or {c})"), "({a} and ({b} or {c}))");
  EXPECT_EQ(canon("({a} -> {b}) -> {c}"), "(({a} implies {b}) implies {c})");
}

// ---------------------------------------------------------------- temporal

TEST(ParserTemporal, KeywordsAndAliases) {
  EXPECT_EQ(canon("pre {p}"), "(pre {p})");
  EXPECT_EQ(canon("Y {p}"), "(pre {p})");
  EXPECT_EQ(canon("once {p}"), "(once {p})");
  EXPECT_EQ(canon("P {p}"), "(once {p})");
  EXPECT_EQ(canon("historically {p}"), "(historically {p})");
  EXPECT_EQ(canon("H {p}"), "(historically {p})");
  EXPECT_EQ(canon("{a} since {b}"), "({a} since {b})");
  EXPECT_EQ(canon("{a} S {b}"), "({a} since {b})");
  EXPECT_EQ(canon("once{p}"), "(once {p})");
  EXPECT_EQ(canon("not once pre {p}"), "(not (once (pre {p})))");
}

TEST(ParserTemporal, Bounds) {
  NodePtr full = parse("once[2:5] {p}");
  EXPECT_TRUE(full->bounds.explicit_bounds);
  EXPECT_EQ(full->bounds.lo, 2);
  EXPECT_EQ(full->bounds.hi, 5);
  NodePtr from = parse("historically[3:] {p}");
  EXPECT_EQ(from->bounds.lo, 3);
  EXPECT_EQ(from->bounds.hi, kInfinity);
  NodePtr upto = parse("{a} since[:7] {b}");
  EXPECT_EQ(upto->op, Op::Since);
  EXPECT_EQ(upto->bounds.lo, 0);
  EXPECT_EQ(upto->bounds.hi, 7);
  NodePtr none = parse("once {p}");
  EXPECT_FALSE(none->bounds.explicit_bounds);
  EXPECT_TRUE(none->bounds.unbounded());

  EXPECT_EQ(canon("once[2:5] {p}"), "(once[2:5] {p})");
  EXPECT_EQ(canon("once[0:5] {p}"), "(once[:5] {p})");  // a zero lower bound is left out
  EXPECT_EQ(canon("once[3:] {p}"), "(once[3:] {p})");
  EXPECT_EQ(canon("once[:7] {p}"), "(once[:7] {p})");
  EXPECT_EQ(canon("once[0:0] {p}"), "(once[:0] {p})");
  EXPECT_EQ(canon("once[ 2 : 5 ]{p}"), "(once[2:5] {p})");
  EXPECT_EQ(canon("{a} since[2:5] {b}"), "({a} since[2:5] {b})");
  EXPECT_EQ(canon("{a} S[1:] {b}"), "({a} since[1:] {b})");
  EXPECT_EQ(canon("historically[4:4] {p}"), "(historically[4:4] {p})");
}

TEST(ParserTemporal, DiscreteRejectsRealBoundsDenseAccepts) {
  EXPECT_EQ(canon("once[0.5:1.25] {p}", /*dense=*/true), "(once[0.5:1.25] {p})");
  EXPECT_EQ(canon("{a} since[:2.5] {b}", true), "({a} since[:2.5] {b})");
  EXPECT_EQ(canon("historically[1.5:] {p}", true), "(historically[1.5:] {p})");
  try {
    parse("once[0.5:1.25] {p}");
    ADD_FAILURE() << "discrete accepted a real bound";
  } catch (const SpecError& e) {
    EXPECT_NE(e.message().find("discrete time needs integer bounds"), std::string::npos);
    EXPECT_EQ(e.column(), 6);  // the '0.5'
  }
  try {
    parse("once[1:2.5] {p}");
    ADD_FAILURE();
  } catch (const SpecError& e) {
    EXPECT_EQ(e.column(), 8);  // the '2.5'
  }
  // Integers written as reals are still integers.
  EXPECT_EQ(canon("once[2.0:1e1] {p}"), "(once[2:10] {p})");
}

TEST(ParserTemporal, PreTakesNoBounds) {
  try {
    parse("{q} and pre[1:2] {p}");
    ADD_FAILURE();
  } catch (const SpecError& e) {
    EXPECT_NE(e.message().find("'pre' takes no time bounds"), std::string::npos);
    EXPECT_EQ(e.column(), 9);  // the 'pre'
  }
}

TEST(ParserTemporal, DenseRejectsPreAtCompile) {
  // Parses in dense mode (the parser does not know time models)...
  EXPECT_EQ(canon("{q} and pre {p}", true), "({q} and (pre {p}))");
  // ...but the dense compiler rejects it at the 'pre'.
  expect_compile_error("{q} and pre {p}", engine::TimeModel::Dense, "'pre' has no meaning in dense time", 9);
  expect_compile_error("Y{p}", engine::TimeModel::Dense, "'pre' has no meaning in dense time", 1);
  // Discrete compiles it.
  engine::Checker discrete(engine::TimeModel::Discrete, false, nullptr);
  EXPECT_NO_THROW(discrete.add_property({"p", "{q} and pre {p}"}));
}

TEST(ParserTemporal, ChainedSinceNeedsParentheses) {
  for (const char* spec : {"{a} since {b} since {c}", "({a} since {b} since {c})", "{a} S {b} S[1:2] {c}"}) {
    try {
      parse(spec);
      ADD_FAILURE() << spec;
    } catch (const SpecError& e) {
      EXPECT_NE(e.message().find("chained 'since' is ambiguous: add parentheses"), std::string::npos) << spec;
      EXPECT_NE(e.message().find("(a since b) since c"), std::string::npos) << spec;
    }
  }
  EXPECT_EQ(canon("({a} since {b}) since {c}"), "(({a} since {b}) since {c})");
  EXPECT_EQ(canon("{a} since ({b} since {c})"), "({a} since ({b} since {c}))");
}

// ---------------------------------------------------------------- precedence

TEST(ParserPrecedence, UnaryBindsTighterThanSince) {
  EXPECT_EQ(canon("not {a} since {b}"), "((not {a}) since {b})");
  EXPECT_EQ(canon("once {a} since historically {b}"), "((once {a}) since (historically {b}))");
  EXPECT_EQ(canon("once[2:5] {a} since[1:] {b}"), "((once[2:5] {a}) since[1:] {b})");
  EXPECT_EQ(canon("{a} since not {b}"), "({a} since (not {b}))");
}

TEST(ParserPrecedence, SinceBindsTighterThanAnd) {
  EXPECT_EQ(canon("{a} and {b} since {c}"), "({a} and ({b} since {c}))");
  EXPECT_EQ(canon("{a} since {b} and {c}"), "(({a} since {b}) and {c})");
  EXPECT_EQ(canon("{a} since {b} and {c} since {d}"), "(({a} since {b}) and ({c} since {d}))");
}

TEST(ParserPrecedence, AndBindsTighterThanOr) {
  EXPECT_EQ(canon("{a} or {b} and {c}"), "({a} or ({b} and {c}))");
  EXPECT_EQ(canon("{a} and {b} or {c}"), "(({a} and {b}) or {c})");
  EXPECT_EQ(canon("{a} and {b} and {c}"), "(({a} and {b}) and {c})");  // left-associative
  EXPECT_EQ(canon("{a} or {b} or {c}"), "(({a} or {b}) or {c})");      // left-associative
}

TEST(ParserPrecedence, OrBindsTighterThanImplies) {
  EXPECT_EQ(canon("{a} -> {b} or {c}"), "({a} implies ({b} or {c}))");
  EXPECT_EQ(canon("{a} or {b} -> {c}"), "(({a} or {b}) implies {c})");
  EXPECT_EQ(canon("{a} and {b} -> {c} and {d}"), "(({a} and {b}) implies ({c} and {d}))");
}

TEST(ParserPrecedence, ImpliesIsRightAssociative) {
  EXPECT_EQ(canon("{a} -> {b} -> {c}"), "({a} implies ({b} implies {c}))");
  EXPECT_EQ(canon("{a} implies {b} -> {c} implies {d}"), "({a} implies ({b} implies ({c} implies {d})))");
}

TEST(ParserPrecedence, AllLevelsTogether) {
  EXPECT_EQ(canon("not {a} and once {b} since {c} or {d} -> {e}"),
            "((((not {a}) and ((once {b}) since {c})) or {d}) implies {e})");
  // The published AbsentBQR formula: historically binds to the left of '->' only.
  EXPECT_EQ(canon("historically({r} && !{q} && once{q}) -> ((not{p}) since[3:10] {q})"),
            "((historically (({r} and (not {q})) and (once {q}))) implies ((not {p}) since[3:10] {q}))");
}

TEST(ParserPrecedence, CanonicalTextRoundTrips) {
  const char* specs[] = {
      "not {a} and once[2:5] {b} since {c} or {d} -> {e}",
      "{k1: true, k2 < 3} -> historically[:4] ({mode: sport} || {x != -1.5})",
      "({a} since[1:] {b}) since {c}",
      "{\"my key\".x >= 1e22}",
      "exists[x, y]. {a: *x} and pre {b: *y}",
      "true -> not false",
  };
  for (const char* s : specs) {
    std::string once = canon(s);
    EXPECT_EQ(canon(once), once) << s;
  }
}

// ---------------------------------------------------------------- errors

// `what()` is "spec error at column N: MESSAGE\n  SOURCE\n  <N-1 blanks>^".
void expect_error(const std::string& spec, const std::string& fragment, int column, bool dense = false) {
  ParseOptions o;
  o.dense = dense;
  try {
    parse(spec, o);
    ADD_FAILURE() << "parsed: " << spec;
  } catch (const SpecError& e) {
    EXPECT_NE(e.message().find(fragment), std::string::npos) << "spec: " << spec << "\nmessage: " << e.message();
    EXPECT_EQ(e.column(), column) << "spec: " << spec << "\n" << e.what();
    EXPECT_EQ(e.source(), spec);
    std::string expected = "spec error at column " + std::to_string(column) + ": " + e.message() + "\n  " + spec +
                           "\n  " + std::string(static_cast<size_t>(column - 1), ' ') + "^";
    EXPECT_EQ(std::string(e.what()), expected);
  }
}

TEST(ParserErrors, EmptySpec) {
  expect_error("", "the specification is empty", 1);
  expect_error("   ", "the specification is empty", 1);
}

TEST(ParserErrors, Truncated) {
  expect_error("{p} and", "unexpected end of specification: expected a formula", 8);
  expect_error("{p} ->  ", "unexpected end of specification: expected a formula", 9);
  expect_error("{p: ", "unexpected end of specification: expected a value", 5);
}

TEST(ParserErrors, Bounds) {
  // "once[:2 " is 8 characters: the '{' where ']' belongs is column 9.
  expect_error("once[:2 {p}", "expected ']' to close the time bounds opened at column 5", 9);
  expect_error("once[5:2] {p}", "empty time interval: the lower bound is greater than the upper bound", 5);
  expect_error("once[-1:2] {p}", "time bounds must not be negative", 6);
  expect_error("once[:-1] {p}", "time bounds must not be negative", 7);
  expect_error("once[1.5:2] {p}", "discrete time needs integer bounds", 6);
  expect_error("once[1 {p}", "expected ':' between the lower and upper time bound", 8);
  expect_error("once[a:2] {p}", "expected a number for a time bound", 6);
  expect_error("pre[1:2] {p}", "'pre' takes no time bounds", 1);
  expect_error("{a} since[2:1] {b}", "empty time interval", 10);
}

TEST(ParserErrors, KeysThatReadAsElements) {
  // A quoted key spelt like an element would print back as one: {"[*]" == "a"}
  // printed as {[*] == "a"} (found by fuzz_spec in CI).
  expect_error("{\"[0]\" == 1}", "a key written like an array element", 2);
  expect_error("{\"[*]\" == \"a\"}", "a key written like an array element", 2);
  expect_error("{a.\"[*]\"}", "a key written like an array element", 4);
}

TEST(ParserErrors, ChainedSince) {
  // "{a} since {b} " is 14 characters.
  expect_error("{a} since {b} since {c}", "chained 'since' is ambiguous", 15);
  expect_error("({a} since {b} since {c})", "chained 'since' is ambiguous", 16);
}

TEST(ParserErrors, Parentheses) {
  expect_error("{p})", "unmatched ')'", 4);
  expect_error("   {p} )", "unmatched ')'", 8);
  expect_error("({p}", "missing ')' to close the '(' at column 1", 5);
  expect_error("{q} or ({p} {r})", "expected ')' to close the '(' at column 8", 13);
  expect_error("()", "expected a formula before ')'", 2);
}

TEST(ParserErrors, MissingOperator) {
  expect_error("{p} {q}", "unexpected '{' after a complete formula (missing operator?)", 5);
  expect_error("{p} & {q}", "unexpected '&' after a complete formula", 5);
  expect_error("{p} andx {q}", "unexpected 'a' after a complete formula", 5);
}

TEST(ParserErrors, Words) {
  expect_error("oncex {p}", "unknown word 'oncex': atoms are written in braces, e.g. {oncex}", 1);
  expect_error("{p} and speed", "unknown word 'speed'", 9);
  expect_error("trueish", "unknown word 'trueish'", 1);
  expect_error("and {p}", "'and' needs a formula on its left", 1);
  expect_error("{p} and or {q}", "'or' needs a formula on its left", 9);
  expect_error("{p} since since {q}", "'since' needs a formula on its left", 11);
  expect_error("#", "unexpected '#': expected a formula", 1);
}

TEST(ParserErrors, Atoms) {
  expect_error("{}", "empty atom: expected a field name", 2);
  expect_error("{speed > 3", "missing '}' to close the atom opened at column 1", 11);
  expect_error("{a > 1 b}", "expected ',' or '}' in the atom opened at column 1", 8);
  expect_error("{q} and {a, b c}", "after field 'b'", 15);  // 'c' where ':' or an operator belongs
  expect_error("{p: }", "expected a value (number, true, false or string)", 5);
  expect_error("{speed > \"fast\"}", "'<', '<=', '>', '>=' compare numbers; this is not a number", 10);
  expect_error("{speed <= \"3\"}", "compare numbers", 11);
  expect_error("{speed >= true}", "compare numbers", 11);
  expect_error("{speed ~ 3}", "expected ':', a comparison (< <= > >= == !=), ',' or '}' after field 'speed'", 8);
  expect_error("{\"abc}", "unterminated string started at column 2", 2);
  expect_error("{a..b}", "expected a field name", 4);
  expect_error("{1x}", "expected a field name", 2);
  expect_error("{x > 1e}", "expected a number for the comparison", 6);
  expect_error("{x > -}", "expected a number for the comparison", 6);
}

TEST(ParserErrors, Quantifiers) {
  expect_error("exists x. {id: *x}", "expected '[' after 'exists'", 8);
  expect_error("exists[]. {p}", "expected a variable name", 8);
  expect_error("forall[x {p}", "expected ']' to close the variable list", 10);
  expect_error("exists[x] {p}", "expected '.' after the variable list", 11);
}

TEST(ParserErrors, CaretOnTheErrorLineOfAMultiLineSpec) {
  // Offsets: "{p} and" 0-6, '\n' 7, two blanks 8-9, "{q}" 10-12, blank 13, '{' 14.
  const std::string spec = "{p} and\n  {q} {r}";
  try {
    parse(spec);
    ADD_FAILURE();
  } catch (const SpecError& e) {
    EXPECT_EQ(e.column(), 15);
    EXPECT_EQ(std::string(e.what()), "spec error at column 15: " + e.message() + "\n    {q} {r}\n        ^");
  }
}

TEST(ParserErrors, CaretKeepsTabsAligned) {
  // A tab before the error is copied into the caret line so the caret lines up.
  const std::string spec = "\t{p} )";
  try {
    parse(spec);
    ADD_FAILURE();
  } catch (const SpecError& e) {
    EXPECT_EQ(e.column(), 6);
    EXPECT_EQ(std::string(e.what()), "spec error at column 6: unmatched ')'\n  \t{p} )\n  \t    ^");
  }
}

// ---------------------------------------------------------------- fuzz

// Parse must either succeed (and then round-trip) or throw SpecError with a
// column inside the text (or one past its end). Nothing else, no crash.
void parse_or_spec_error(const std::string& text) {
  for (bool dense : {false, true}) {
    ParseOptions o;
    o.dense = dense;
    try {
      NodePtr n = parse(text, o);
      ASSERT_NE(n, nullptr);
      std::string c = to_string(*n);
      EXPECT_EQ(to_string(*parse(c, o)), c) << "round trip of " << text;
      engine::Checker checker(dense ? engine::TimeModel::Dense : engine::TimeModel::Discrete, false, nullptr);
      try {
        checker.add_property({"p", text});
      } catch (const SpecError& e) {  // data references, quantifiers, dense pre
        EXPECT_GE(e.column(), 1);
        EXPECT_LE(e.column(), static_cast<int>(text.size()) + 1);
      }
    } catch (const SpecError& e) {
      EXPECT_GE(e.column(), 1) << text;
      EXPECT_LE(e.column(), static_cast<int>(text.size()) + 1) << text;
      EXPECT_FALSE(e.message().empty());
      EXPECT_EQ(std::string(e.what()).rfind("spec error at column ", 0), 0u);
    }
  }
}

TEST(ParserFuzz, RandomBytes) {
  std::mt19937 rng(12345);
  for (int i = 0; i < 400; ++i) {
    std::string s(rng() % 40, '\0');
    for (char& c : s) c = static_cast<char>(rng() % 256);
    parse_or_spec_error(s);
  }
}

TEST(ParserFuzz, RandomGrammarCharacters) {
  const std::string alphabet = "{}[]():,.*!<>=-+ \t\n\"\\0123456789.eEpqSYPH_";
  std::mt19937 rng(777);
  for (int i = 0; i < 600; ++i) {
    std::string s(rng() % 30, ' ');
    for (char& c : s) c = alphabet[rng() % alphabet.size()];
    parse_or_spec_error(s);
  }
}

TEST(ParserFuzz, RandomTokenSoup) {
  const char* tokens[] = {"{p}", "{x > 2.5}", "{m: *}", "{id: *v}", "{a.b}", "and", "&&", "or", "||", "->",
                          "implies", "not", "!", "pre", "once", "historically", "since", "S", "[1:2]", "[:3]",
                          "[0.5:]", "[", "]", "(", ")", "true", "false", "exists[v].", ","};
  std::mt19937 rng(4242);
  int parsed = 0;
  for (int i = 0; i < 1500; ++i) {
    std::string s;
    for (int k = 1 + static_cast<int>(rng() % 8); k > 0; --k) {
      s += tokens[rng() % (sizeof tokens / sizeof *tokens)];
      s += ' ';
    }
    try {
      parse(s, ParseOptions{true});
      ++parsed;
    } catch (const SpecError&) {
    }
    parse_or_spec_error(s);
  }
  EXPECT_GT(parsed, 20);  // the soup does reach valid formulas, so round trips are exercised
}

TEST(ParserFuzz, EveryTruncationOfValidSpecs) {
  const char* specs[] = {
      "historically(({r} && !{q} && once{q}) -> ( (({s} -> once[3:10]{p}) and not((not {s}) since[10:] {p})) since {q}))",
      "{k1: true, \"k 2\".x <= -3.5e2, mode: sport, m: *} || exists[x]. {id: *x}",
      "not pre Y P[2:] H[:4] ({a} S[1:2] {b}) implies true -> false",
  };
  for (const char* spec : specs) {
    std::string full(spec);
    for (size_t n = 0; n <= full.size(); ++n) parse_or_spec_error(full.substr(0, n));
  }
}

TEST(ParserFuzz, DeepNestingParses) {
  std::string s = std::string(300, '(') + "{p}" + std::string(300, ')');
  EXPECT_EQ(canon(s), "{p}");
  std::string nots;
  for (int i = 0; i < 300; ++i) nots += "not ";
  EXPECT_EQ(parse(nots + "{p}")->op, Op::Not);
}

}  // namespace
}  // namespace rvc::spec
