// Recursive-descent parser for Rye. Works directly on characters: the grammar
// is small, and a hand-written scanner gives exact columns for every error.
#include "spec/parser.hpp"

#include <cctype>
#include <charconv>
#include <cmath>

namespace rvc::spec {
namespace {

bool is_ident_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool is_ident_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

class Parser {
 public:
  Parser(const std::string& text, const ParseOptions& options) : s_(text), opt_(options) {}

  NodePtr parse_all() {
    skip_ws();
    if (at_end()) fail("the specification is empty", 0);
    NodePtr node = parse_quantified();
    skip_ws();
    if (!at_end()) {
      if (peek() == ')') fail("unmatched ')'", pos_);
      if (peek_word("since") || peek_word("S"))
        fail("chained 'since' is ambiguous: add parentheses, e.g. (a since b) since c", pos_);
      fail("unexpected '" + std::string(1, peek()) + "' after a complete formula (missing operator?)", pos_);
    }
    return node;
  }

 private:
  const std::string& s_;
  ParseOptions opt_;
  size_t pos_ = 0;

  [[noreturn]] void fail(const std::string& message, size_t at) const {
    throw SpecError(message, s_, static_cast<int>(at) + 1);
  }
  bool at_end() const { return pos_ >= s_.size(); }
  char peek(size_t ahead = 0) const { return pos_ + ahead < s_.size() ? s_[pos_ + ahead] : '\0'; }
  void skip_ws() {
    while (!at_end() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
  }
  bool peek_symbol(const char* sym) const { return s_.compare(pos_, std::char_traits<char>::length(sym), sym) == 0; }
  bool accept_symbol(const char* sym) {
    skip_ws();
    if (!peek_symbol(sym)) return false;
    pos_ += std::char_traits<char>::length(sym);
    return true;
  }
  // A keyword must not run into an identifier character: "once" but not "oncex".
  bool peek_word(const char* word) const {
    size_t n = std::char_traits<char>::length(word);
    if (s_.compare(pos_, n, word) != 0) return false;
    return pos_ + n >= s_.size() || !is_ident_char(s_[pos_ + n]);
  }
  bool accept_word(const char* word) {
    skip_ws();
    if (!peek_word(word)) return false;
    pos_ += std::char_traits<char>::length(word);
    return true;
  }
  void expect(const char* sym, const std::string& what) {
    skip_ws();
    if (!peek_symbol(sym)) fail("expected '" + std::string(sym) + "' " + what, pos_);
    pos_ += std::char_traits<char>::length(sym);
  }

  static NodePtr make(Op op, size_t at) {
    auto n = std::make_unique<Node>();
    n->op = op;
    n->column = static_cast<int>(at) + 1;
    return n;
  }

  // quantified := ('exists' | 'forall') '[' vars ']' '.' quantified | implication
  NodePtr parse_quantified() {
    skip_ws();
    size_t at = pos_;
    Op op;
    if (accept_word("exists")) op = Op::Exists;
    else if (accept_word("forall")) op = Op::Forall;
    else return parse_implication();
    auto node = make(op, at);
    expect("[", "after '" + std::string(op_name(op)) + "' to list its variables, e.g. exists[x]. ...");
    do {
      skip_ws();
      if (!is_ident_start(peek())) fail("expected a variable name", pos_);
      size_t start = pos_;
      while (is_ident_char(peek())) ++pos_;
      node->variables.push_back(s_.substr(start, pos_ - start));
    } while (accept_symbol(","));
    expect("]", "to close the variable list");
    expect(".", "after the variable list, e.g. exists[x]. {id: *x}");
    node->left = parse_quantified();
    return node;
  }

  NodePtr parse_implication() {
    NodePtr left = parse_disjunction();
    skip_ws();
    size_t at = pos_;
    if (accept_symbol("->") || accept_word("implies")) {
      auto node = make(Op::Implies, at);
      node->left = std::move(left);
      node->right = parse_implication();  // right-associative
      return node;
    }
    return left;
  }

  NodePtr parse_disjunction() {
    NodePtr left = parse_conjunction();
    for (;;) {
      skip_ws();
      size_t at = pos_;
      if (!(accept_symbol("||") || accept_word("or"))) return left;
      auto node = make(Op::Or, at);
      node->left = std::move(left);
      node->right = parse_conjunction();
      left = std::move(node);
    }
  }

  NodePtr parse_conjunction() {
    NodePtr left = parse_since();
    for (;;) {
      skip_ws();
      size_t at = pos_;
      if (!(accept_symbol("&&") || accept_word("and"))) return left;
      auto node = make(Op::And, at);
      node->left = std::move(left);
      node->right = parse_since();
      left = std::move(node);
    }
  }

  NodePtr parse_since() {
    NodePtr left = parse_unary();
    skip_ws();
    size_t at = pos_;
    if (!(accept_word("since") || accept_word("S"))) return left;
    auto node = make(Op::Since, at);
    node->bounds = parse_bounds_opt(at);
    node->left = std::move(left);
    node->right = parse_unary();
    return node;
  }

  NodePtr parse_unary() {
    skip_ws();
    size_t at = pos_;
    Op op;
    if (accept_symbol("!") || accept_word("not")) op = Op::Not;
    else if (accept_word("pre") || accept_word("Y")) op = Op::Pre;
    else if (accept_word("once") || accept_word("P")) op = Op::Once;
    else if (accept_word("historically") || accept_word("H")) op = Op::Historically;
    else return parse_primary();
    auto node = make(op, at);
    if (op != Op::Not) node->bounds = parse_bounds_opt(at);
    if (op == Op::Pre && node->bounds.explicit_bounds)
      fail("'pre' takes no time bounds: it always looks exactly one step back", at);
    node->left = parse_unary();
    return node;
  }

  NodePtr parse_primary() {
    skip_ws();
    size_t at = pos_;
    if (at_end()) fail("unexpected end of specification: expected a formula", pos_);
    char c = peek();
    if (c == '(') {
      ++pos_;
      NodePtr inner = parse_quantified();
      skip_ws();
      if (peek() != ')') {
        if (peek_word("since") || peek_word("S"))
          fail("chained 'since' is ambiguous: add parentheses, e.g. (a since b) since c", pos_);
        fail(at_end() ? "missing ')' to close the '(' at column " + std::to_string(at + 1)
                      : "expected ')' to close the '(' at column " + std::to_string(at + 1),
             pos_);
      }
      ++pos_;
      return inner;
    }
    if (c == '{') return parse_braces();
    if (accept_word("true")) return make(Op::True, at);
    if (accept_word("false")) return make(Op::False, at);
    if (c == ')') fail("expected a formula before ')'", pos_);
    if (is_ident_start(c)) {
      size_t end = pos_;
      while (end < s_.size() && is_ident_char(s_[end])) ++end;
      std::string word = s_.substr(pos_, end - pos_);
      if (word == "and" || word == "or" || word == "implies" || word == "since" || word == "S")
        fail("'" + word + "' needs a formula on its left", pos_);
      fail("unknown word '" + word + "': atoms are written in braces, e.g. {" + word + "}", pos_);
    }
    fail("unexpected '" + std::string(1, c) + "': expected a formula", pos_);
  }

  // Optional "[a:b]", "[a:]", "[:b]" after a temporal operator.
  Bounds parse_bounds_opt(size_t op_at) {
    Bounds b;
    skip_ws();
    if (peek() != '[') return b;
    size_t open = pos_++;
    b.explicit_bounds = true;
    skip_ws();
    bool has_lo = peek() != ':';
    if (has_lo) b.lo = parse_bound_number();
    expect(":", "between the lower and upper time bound, e.g. [3:10]");
    skip_ws();
    if (peek() != ']') b.hi = parse_bound_number();
    skip_ws();
    if (peek() != ']') fail("expected ']' to close the time bounds opened at column " + std::to_string(open + 1), pos_);
    ++pos_;
    if (b.hi < b.lo) fail("empty time interval: the lower bound is greater than the upper bound", open);
    return b;
  }

  double parse_bound_number() {
    skip_ws();
    size_t at = pos_;
    if (peek() == '-') fail("time bounds must not be negative", at);
    double v = parse_number_token("a time bound");
    if (!opt_.dense && v != std::floor(v))
      fail("discrete time needs integer bounds (use --dense for real-valued bounds)", at);
    if (std::isinf(v) || std::isnan(v)) fail("time bound out of range", at);
    return v;
  }

  double parse_number_token(const char* what) {
    size_t at = pos_;
    size_t end = pos_;
    if (end < s_.size() && (s_[end] == '-' || s_[end] == '+')) ++end;
    while (end < s_.size() && (std::isdigit(static_cast<unsigned char>(s_[end])) || s_[end] == '.' ||
                               s_[end] == 'e' || s_[end] == 'E' ||
                               ((s_[end] == '-' || s_[end] == '+') && (s_[end - 1] == 'e' || s_[end - 1] == 'E'))))
      ++end;
    double v = 0;
    const char* first = s_.data() + pos_ + (s_[pos_] == '+' ? 1 : 0);
    auto [ptr, ec] = std::from_chars(first, s_.data() + end, v);
    if (ec != std::errc() || ptr != s_.data() + end || end == at)
      fail(std::string("expected a number for ") + what, at);
    pos_ = end;
    return v;
  }

  // braces := '{' test (',' test)* '}'  — a conjunction of field tests
  NodePtr parse_braces() {
    size_t open = pos_++;
    NodePtr result;
    for (;;) {
      auto leaf = make(Op::Test, pos_);
      leaf->test = parse_field_test();
      leaf->column = leaf->test.column;
      if (!result) {
        result = std::move(leaf);
      } else {
        auto conj = make(Op::And, open);
        conj->left = std::move(result);
        conj->right = std::move(leaf);
        result = std::move(conj);
      }
      skip_ws();
      if (peek() == ',') { ++pos_; continue; }
      if (peek() == '}') { ++pos_; return result; }
      if (at_end()) fail("missing '}' to close the atom opened at column " + std::to_string(open + 1), pos_);
      fail("expected ',' or '}' in the atom opened at column " + std::to_string(open + 1), pos_);
    }
  }

  std::string parse_key_segment() {
    skip_ws();
    if (peek() == '"') return parse_quoted();
    if (!is_ident_start(peek())) {
      if (peek() == '}') fail("empty atom: expected a field name, e.g. {speed > 3}", pos_);
      fail("expected a field name", pos_);
    }
    size_t start = pos_;
    while (is_ident_char(peek())) ++pos_;
    return s_.substr(start, pos_ - start);
  }

  std::string parse_quoted() {
    size_t open = pos_++;
    std::string out;
    while (!at_end() && peek() != '"') {
      if (peek() == '\\' && pos_ + 1 < s_.size()) ++pos_;
      out.push_back(s_[pos_++]);
    }
    if (at_end()) fail("unterminated string started at column " + std::to_string(open + 1), open);
    ++pos_;
    return out;
  }

  FieldTest parse_field_test() {
    FieldTest t;
    skip_ws();
    t.column = static_cast<int>(pos_) + 1;
    t.path.push_back(parse_key_segment());
    while (peek() == '.') {  // nested field: {pose.position.x > 1}
      ++pos_;
      t.path.push_back(parse_key_segment());
    }
    skip_ws();
    size_t op_at = pos_;
    using FOp = FieldTest::Op;
    if (peek() == ',' || peek() == '}') { t.op = FOp::Truthy; return t; }
    if (accept_symbol(":")) {
      skip_ws();
      if (peek() == '*') {
        ++pos_;
        skip_ws();
        if (is_ident_start(peek())) {  // {id: *x} binds x
          size_t start = pos_;
          while (is_ident_char(peek())) ++pos_;
          t.op = FOp::Bind;
          t.variable = s_.substr(start, pos_ - start);
        } else {
          t.op = FOp::Present;
        }
        return t;
      }
      t.op = FOp::Eq;
      t.value = parse_literal(/*allow_bare_word=*/true);
      return t;
    }
    if (accept_symbol("==")) t.op = FOp::Eq;
    else if (accept_symbol("!=")) t.op = FOp::Ne;
    else if (accept_symbol("<=")) t.op = FOp::Le;
    else if (accept_symbol(">=")) t.op = FOp::Ge;
    else if (accept_symbol("<")) t.op = FOp::Lt;
    else if (accept_symbol(">")) t.op = FOp::Gt;
    else fail("expected ':', a comparison (< <= > >= == !=), ',' or '}' after field '" + t.key() + "'", op_at);
    skip_ws();
    size_t lit_at = pos_;
    t.value = parse_literal(/*allow_bare_word=*/true);
    bool ordering = t.op == FOp::Lt || t.op == FOp::Le || t.op == FOp::Gt || t.op == FOp::Ge;
    if (ordering && t.value.kind != Literal::Kind::Number)
      fail("'<', '<=', '>', '>=' compare numbers; this is not a number", lit_at);
    return t;
  }

  Literal parse_literal(bool allow_bare_word) {
    skip_ws();
    Literal lit;
    size_t at = pos_;
    char c = peek();
    if (c == '"') {
      lit.kind = Literal::Kind::String;
      lit.text = parse_quoted();
    } else if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.') {
      lit.kind = Literal::Kind::Number;
      lit.number = parse_number_token("the comparison");
    } else if (is_ident_start(c)) {
      size_t start = pos_;
      while (is_ident_char(peek())) ++pos_;
      std::string word = s_.substr(start, pos_ - start);
      if (word == "true" || word == "false") {
        lit.kind = Literal::Kind::Bool;
        lit.b = word == "true";
      } else if (allow_bare_word) {  // Reelay reads {mode: sport} as the string "sport"
        lit.kind = Literal::Kind::String;
        lit.text = word;
      }
    } else {
      fail(at_end() ? "unexpected end of specification: expected a value" : "expected a value (number, true, false or string)", at);
    }
    return lit;
  }
};

}  // namespace

NodePtr parse(const std::string& text, const ParseOptions& options) {
  return Parser(text, options).parse_all();
}

}  // namespace rvc::spec
