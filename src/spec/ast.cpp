#include "spec/ast.hpp"
#include "spec/exact_time.hpp"

#include <cctype>
#include <charconv>
#include <cmath>

#include "spec/spec_error.hpp"

namespace rvc::spec {
namespace {

std::string number_text(double v) {
  char buf[64];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, ptr);
}

std::string quote_if_needed(const std::string& key) {
  bool plain = !key.empty() && (std::isalpha(static_cast<unsigned char>(key[0])) || key[0] == '_');
  for (char c : key) plain = plain && (std::isalnum(static_cast<unsigned char>(c)) || c == '_');
  if (plain) return key;
  std::string out = "\"";
  for (char c : key) {
    if (c == '"' || c == '\\') out.push_back('\\');
    out.push_back(c);
  }
  return out + "\"";
}

std::string literal_text(const Literal& l) {
  switch (l.kind) {
    case Literal::Kind::Bool: return l.b ? "true" : "false";
    case Literal::Kind::Number: {
      if (l.exact.kind == ExactInt::None) return number_text(l.number);
      std::string out;  // all its digits: {u == 2^63 - 1} and {u == 2^63} are two tests
      append_exact(out, l.exact);
      return out;
    }
    case Literal::Kind::String: {
      std::string out = "\"";
      for (char c : l.text) {
        if (c == '"' || c == '\\') out.push_back('\\');
        out.push_back(c);
      }
      return out + "\"";
    }
  }
  return "";
}

std::string bounds_text(const Bounds& b) {
  if (!b.explicit_bounds) return "";
  std::string out = "[";
  // Rescaled to nanoseconds (engine::Checker): printed as the seconds written.
  const auto text = [&](double v) { return b.in_ns ? seconds_text(static_cast<int64_t>(v)) : number_text(v); };
  if (b.lo != 0) out += text(b.lo);
  out += ":";
  if (b.hi != kInfinity) out += text(b.hi);
  return out + "]";
}

std::string path_text(const std::vector<std::string>& path) {
  std::string out;
  for (size_t i = 0; i < path.size(); ++i) {
    if (is_index_part(path[i]) || is_every_part(path[i])) out += path[i];
    else out.append(i ? "." : "").append(quote_if_needed(path[i]));
  }
  return out;
}

const char* comparison_text(FieldTest::Op op) {
  switch (op) {
    case FieldTest::Op::Eq: return " == ";
    case FieldTest::Op::Ne: return " != ";
    case FieldTest::Op::Lt: return " < ";
    case FieldTest::Op::Le: return " <= ";
    case FieldTest::Op::Gt: return " > ";
    case FieldTest::Op::Ge: return " >= ";
    default: return " ? ";
  }
}

}  // namespace

std::string to_string(const Expr& e) {
  using K = Expr::Kind;
  auto arg = [&](size_t i) { return to_string(*e.args[i]); };
  switch (e.kind) {
    case K::Number: return number_text(e.number);
    case K::Field: return path_text(e.path);
    case K::Neg: return "(-" + arg(0) + ")";
    case K::Add: return "(" + arg(0) + " + " + arg(1) + ")";
    case K::Sub: return "(" + arg(0) + " - " + arg(1) + ")";
    case K::Mul: return "(" + arg(0) + " * " + arg(1) + ")";
    case K::Div: return "(" + arg(0) + " / " + arg(1) + ")";
    case K::Abs: return "abs(" + arg(0) + ")";
    case K::Min: return "min(" + arg(0) + ", " + arg(1) + ")";
    case K::Max: return "max(" + arg(0) + ", " + arg(1) + ")";
  }
  return "?";
}

void expr_fields(const Expr& e, std::vector<const Expr*>& out) {
  if (e.kind == Expr::Kind::Field) {
    for (const Expr* f : out)
      if (f->path == e.path) return;
    out.push_back(&e);
    return;
  }
  for (const auto& a : e.args) expr_fields(*a, out);
}

bool is_index_part(const std::string& part) {
  if (part.size() < 3 || part.front() != '[' || part.back() != ']') return false;
  for (size_t i = 1; i + 1 < part.size(); ++i)
    if (!std::isdigit(static_cast<unsigned char>(part[i]))) return false;
  return true;
}

uint32_t index_of_part(const std::string& part) {
  return static_cast<uint32_t>(std::stoul(part.substr(1, part.size() - 2)));
}

const char* timed_name(Timed::Kind kind) {
  switch (kind) {
    case Timed::Kind::Arrived: return "@arrived";
    case Timed::Kind::Age: return "@age";
    case Timed::Kind::Latency: return "@latency";
    default: return "";
  }
}

const char* quant_name(ArrayQuant::Kind kind) {
  switch (kind) {
    case ArrayQuant::Kind::All: return "all";
    case ArrayQuant::Kind::Any: return "any";
    case ArrayQuant::Kind::Count: return "count";
    default: return "";
  }
}

const char* func_name(Timed::Func func) {
  switch (func) {
    case Timed::Func::Count: return "count";
    case Timed::Func::Sum: return "sum";
    case Timed::Func::Avg: return "avg";
    case Timed::Func::Min: return "min";
    case Timed::Func::Max: return "max";
  }
  return "?";
}

std::string FieldTest::timed_input() const {
  if (!is_timed() || path.size() < 2) return "";
  return path[0];
}

std::string FieldTest::key() const {
  // The last part is a timing atom's name (bare), unless this is an
  // aggregate of a field, whose key may be "@x" like any other (quoted).
  const bool names_atom = is_timed() && (timed.kind != Timed::Kind::Aggregate || timed.of_arrivals);
  std::string out;
  for (size_t i = 0; i < path.size(); ++i) {
    if (is_index_part(path[i]) || is_every_part(path[i])) out += path[i];
    // A timing atom's name is written bare; a field named "@age" is quoted.
    else if (i + 1 == path.size() && names_atom) out.append(i ? "." : "").append(path[i]);
    else out.append(i ? "." : "").append(quote_if_needed(path[i]));
  }
  return out;
}

std::string FieldTest::to_string() const {
  if (is_expr()) {
    // {a == (b)}: a bare word after == is a string (or a message constant), so
    // a field there is written in parentheses.
    std::string right = spec::to_string(*rhs);
    // A quoted key there would read as a string too: {a < ("k y")}.
    if (rhs->kind == Expr::Kind::Field && (op == Op::Eq || op == Op::Ne || right[0] == '"')) right = "(" + right + ")";
    return spec::to_string(*lhs) + comparison_text(op) + right;
  }
  if (is_quantified()) {  // all(ranges[*] > 0.2), count(a[*].x < 2) >= 3
    FieldTest element = *this;
    element.quant = {};
    std::string out = std::string(quant_name(quant.kind)) + "(" + element.to_string() + ")";
    if (quant.kind == ArrayQuant::Kind::Count)
      out += std::string(comparison_text(static_cast<Op>(quant.count_op))) + number_text(quant.count_value);
    return out;
  }
  std::string k = key();
  if (timed.kind == Timed::Kind::Aggregate) k = std::string(func_name(timed.func)) + bounds_text(timed.window) + "(" + k + ")";
  switch (op) {
    case Op::Truthy: return k;
    case Op::Present: return k + ": *";
    case Op::Bind: return k + ": *" + variable;
    case Op::Value: return k + " as a number";  // hidden (no syntax): an expression's field
    case Op::Eq: return k + " == " + literal_text(value);
    case Op::Ne: return k + " != " + literal_text(value);
    case Op::Lt: return k + " < " + literal_text(value);
    case Op::Le: return k + " <= " + literal_text(value);
    case Op::Gt: return k + " > " + literal_text(value);
    case Op::Ge: return k + " >= " + literal_text(value);
  }
  return k;
}

const char* op_name(Op op) {
  switch (op) {
    case Op::True: return "true";
    case Op::False: return "false";
    case Op::Test: return "atom";
    case Op::Not: return "not";
    case Op::Pre: return "pre";
    case Op::Once: return "once";
    case Op::Historically: return "historically";
    case Op::And: return "and";
    case Op::Or: return "or";
    case Op::Implies: return "implies";
    case Op::Since: return "since";
    case Op::Exists: return "exists";
    case Op::Forall: return "forall";
    case Op::Eventually: return "eventually";
    case Op::Always: return "always";
    case Op::Until: return "until";
    case Op::Next: return "next";
  }
  return "?";
}

std::string to_string(const Node& n) {
  switch (n.op) {
    case Op::True: return "true";
    case Op::False: return "false";
    case Op::Test: return "{" + n.test.to_string() + "}";
    case Op::Not: return "(not " + to_string(*n.left) + ")";
    case Op::Pre:
    case Op::Once:
    case Op::Historically:
    case Op::Next:
    case Op::Eventually:
    case Op::Always:
      return "(" + std::string(op_name(n.op)) + bounds_text(n.bounds) + " " + to_string(*n.left) + ")";
    case Op::And:
    case Op::Or:
    case Op::Implies:
      return "(" + to_string(*n.left) + " " + op_name(n.op) + " " + to_string(*n.right) + ")";
    case Op::Since:
    case Op::Until:
      return "(" + to_string(*n.left) + " " + op_name(n.op) + bounds_text(n.bounds) + " " + to_string(*n.right) + ")";
    case Op::Exists:
    case Op::Forall: {
      std::string vars;
      for (size_t i = 0; i < n.variables.size(); ++i) vars += (i ? ", " : "") + n.variables[i];
      return "(" + std::string(op_name(n.op)) + "[" + vars + "]. " + to_string(*n.left) + ")";
    }
  }
  return "?";
}

std::string SpecError::render(const std::string& message, const std::string& source, int column) {
  // `column` counts characters (UTF-8 code points) from the start of the
  // spec; find the byte where that character starts.
  size_t at = 0;
  for (int chars = 1; at < source.size() && chars < column; ++chars) {
    ++at;
    while (at < source.size() && (static_cast<unsigned char>(source[at]) & 0xC0) == 0x80) ++at;
  }
  // Show the line holding the column (specs from files may span lines).
  size_t line_start = at == 0 ? 0 : source.rfind('\n', at - 1);
  line_start = (line_start == std::string::npos || at == 0) ? 0 : line_start + 1;
  size_t line_end = source.find('\n', at);
  if (line_end == std::string::npos) line_end = source.size();
  // A long line is shown as a window around the column, cut at character
  // boundaries, with "..." where it was cut.
  auto char_start = [&](size_t i) {
    while (i > 0 && i < source.size() && (static_cast<unsigned char>(source[i]) & 0xC0) == 0x80) --i;
    return i;
  };
  std::string before, after;
  if (at - line_start > 60) {
    line_start = char_start(at - 60);
    before = "...";
  }
  if (line_end - at > 60) {
    line_end = char_start(at + 60);
    after = "...";
  }
  std::string line = before + source.substr(line_start, line_end - line_start) + after;
  // The caret line: one space per character before the column, tabs kept so
  // it lines up under a tabbed line.
  std::string caret(before.size(), ' ');
  for (size_t i = line_start; i < at; ++i) {
    unsigned char c = static_cast<unsigned char>(source[i]);
    if ((c & 0xC0) == 0x80) continue;  // a continuation byte: same character
    caret.push_back(c == '\t' ? '\t' : ' ');
  }
  return "spec error at column " + std::to_string(column) + ": " + message + "\n  " + line + "\n  " + caret + "^";
}

}  // namespace rvc::spec
