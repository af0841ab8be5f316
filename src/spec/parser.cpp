// Recursive-descent parser for Rye. Works directly on characters: the grammar
// is small, and a hand-written scanner gives exact columns for every error.
#include "spec/parser.hpp"
#include "spec/exact_time.hpp"

#include <pthread.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <exception>
#include <memory>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace rvc::spec {
namespace {

bool is_ident_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool is_ident_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// Limits that keep hostile specs from exhausting the stack (the parser, the
// compiler and the tree's destructor all recurse over its height). Real specs
// nest a few dozen levels; and/or chains longer than 64 terms are built as
// balanced trees (both operators are associative), so `{a} or {b} or ...`
// with 50,000 terms is 16 levels high, not 50,000.
//
// Two limits: the formula's height (kMaxNesting operators), and the written
// nesting the parser recurses over (parentheses and prefix operators). The
// printed form of a formula wraps each operator in parentheses, so the second
// limit leaves room for twice the first: whatever is accepted prints to text
// that is accepted again (the fuzz_spec oracle).
inline constexpr int kMaxNesting = 1000;
inline constexpr int kMaxWrittenNesting = 2 * kMaxNesting + 8;
// Discrete bounds are step counts kept in a double: integers up to 2^53 are exact.
inline constexpr uint64_t kMaxDiscreteBound = uint64_t{1} << 53;

class Parser {
 public:
  Parser(const std::string& text, const ParseOptions& options) : s_(text), opt_(options) {}

  NodePtr parse_all() {
    skip_ws();
    if (at_end()) fail("the specification is empty", 0);
    NodePtr node = parse_quantified();
    skip_ws();
    check_height(*node);
    if (!at_end()) {
      if (peek() == ')') fail("unmatched ')'", pos_);
      refuse_chain();
      fail("unexpected '" + std::string(1, peek()) + "' after a complete formula (missing operator?)", pos_);
    }
    return node;
  }

 private:
  // Without recursion: the tree may be up to kMaxWrittenNesting high here.
  void check_height(const Node& root) const {
    std::vector<std::pair<const Node*, int>> todo{{&root, 1}};
    while (!todo.empty()) {
      auto [n, h] = todo.back();
      todo.pop_back();
      if (h > kMaxNesting)
        throw SpecError("formula nested deeper than " + std::to_string(kMaxNesting) + " levels (the limit)", s_,
                        n->column > 0 ? n->column : 1);
      if (n->left) todo.push_back({n->left.get(), h + 1});
      if (n->right) todo.push_back({n->right.get(), h + 1});
    }
  }

  const std::string& s_;
  ParseOptions opt_;
  size_t pos_ = 0;

  int nesting_ = 0;
  // Byte offset -> 1-based column in characters (UTF-8 code points), so the
  // caret sits under the right character after non-ASCII text. Cached: the
  // parser asks mostly for increasing offsets.
  mutable size_t col_byte_ = 0;
  mutable int col_chars_ = 0;
  int column(size_t at) const {
    if (at < col_byte_) col_byte_ = 0, col_chars_ = 0;
    for (; col_byte_ < at && col_byte_ < s_.size(); ++col_byte_)
      if ((static_cast<unsigned char>(s_[col_byte_]) & 0xC0) != 0x80) ++col_chars_;
    return col_chars_ + 1;
  }
  std::string column_text(size_t at) const { return std::to_string(column(at)); }

  [[noreturn]] void fail(const std::string& message, size_t at) const { throw SpecError(message, s_, column(at)); }

  // One more level of nesting (a parenthesis, a prefix operator, a
  // quantifier, the right side of an implication) for the scope of a parse
  // function.
  class Nest {
   public:
    Nest(Parser& p, size_t at) : p_(p) {
      if (++p_.nesting_ > kMaxWrittenNesting)
        p_.fail("formula nested deeper than " + std::to_string(kMaxWrittenNesting) +
                    " levels of parentheses and operators (the limit)",
                at);
    }
    ~Nest() { --p_.nesting_; }

   private:
    Parser& p_;
  };

  // A chain of one associative operator. Short chains nest to the left as
  // written (the canonical text users see); long ones are built as balanced
  // trees so their height stays logarithmic.
  // `at` holds the operators' columns (taken while parsing, in order: asking
  // for a column behind the cache would recount from the start).
  NodePtr chain(Op op, std::vector<NodePtr>& operands, const std::vector<int>& at) {
    if (operands.size() > 64) return balanced(op, operands, at, 0, operands.size());
    NodePtr left = std::move(operands[0]);
    for (size_t i = 1; i < operands.size(); ++i) {
      auto node = make_at_column(op, at[i - 1]);
      node->left = std::move(left);
      node->right = std::move(operands[i]);
      left = std::move(node);
    }
    return left;
  }
  NodePtr balanced(Op op, std::vector<NodePtr>& operands, const std::vector<int>& at, size_t lo, size_t hi) {
    if (hi - lo == 1) return std::move(operands[lo]);
    size_t mid = (lo + hi) / 2;
    auto node = make_at_column(op, at[mid - 1]);  // the operator between the halves
    node->left = balanced(op, operands, at, lo, mid);
    node->right = balanced(op, operands, at, mid, hi);
    return node;
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

  NodePtr make(Op op, size_t at) const { return make_at_column(op, column(at)); }
  static NodePtr make_at_column(Op op, int column) {
    auto n = std::make_unique<Node>();
    n->op = op;
    n->column = column;
    return n;
  }

  // quantified := ('exists' | 'forall') '[' vars ']' '.' quantified | implication
  NodePtr parse_quantified() {
    skip_ws();
    size_t at = pos_;
    Nest nest(*this, at);
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
      Nest nest(*this, at);
      auto node = make(Op::Implies, at);
      node->left = std::move(left);
      node->right = parse_implication();  // right-associative
      return node;
    }
    return left;
  }

  NodePtr parse_disjunction() {
    std::vector<NodePtr> operands;
    std::vector<int> ops;
    operands.push_back(parse_conjunction());
    for (;;) {
      skip_ws();
      size_t at = pos_;
      if (!(accept_symbol("||") || accept_word("or"))) break;
      ops.push_back(column(at));
      operands.push_back(parse_conjunction());
    }
    return chain(Op::Or, operands, ops);
  }

  NodePtr parse_conjunction() {
    std::vector<NodePtr> operands;
    std::vector<int> ops;
    operands.push_back(parse_since());
    for (;;) {
      skip_ws();
      size_t at = pos_;
      if (!(accept_symbol("&&") || accept_word("and"))) break;
      ops.push_back(column(at));
      operands.push_back(parse_since());
    }
    return chain(Op::And, operands, ops);
  }

  NodePtr parse_since() {
    NodePtr left = parse_unary();
    skip_ws();
    size_t at = pos_;
    Op op = Op::Since;
    if (accept_word("until")) op = Op::Until;
    else if (!(accept_word("since") || accept_word("S"))) return left;
    auto node = make(op, at);
    node->bounds = parse_bounds_opt(at);
    if (op == Op::Until) check_future_bounds(node->bounds, "until", at);
    node->left = std::move(left);
    node->right = parse_unary();
    return node;
  }

  NodePtr parse_unary() {
    skip_ws();
    size_t at = pos_;
    if (NodePtr edge = parse_edge_opt()) return edge;
    Op op;
    if (accept_symbol("!") || accept_word("not")) op = Op::Not;
    else if (accept_word("pre") || accept_word("Y")) op = Op::Pre;
    else if (accept_word("once") || accept_word("P")) op = Op::Once;
    else if (accept_word("historically") || accept_word("H")) op = Op::Historically;
    else if (accept_word("eventually")) op = Op::Eventually;
    else if (accept_word("always")) op = Op::Always;
    else if (accept_word("next")) op = Op::Next;
    else return parse_primary();
    Nest nest(*this, at);
    auto node = make(op, at);
    if (op != Op::Not) node->bounds = parse_bounds_opt(at);
    if (op == Op::Pre && node->bounds.explicit_bounds)
      fail("'pre' takes no time bounds: it always looks exactly one step back", at);
    if (op == Op::Next && node->bounds.explicit_bounds)
      fail("'next' takes no time bounds: it always looks exactly one step ahead (use eventually[a:b])", at);
    if (op == Op::Next && opt_.dense)
      fail("'next' has no meaning in dense time (there is no next step); use eventually[a:b] or discrete time", at);
    if (op == Op::Eventually || op == Op::Always) check_future_bounds(node->bounds, op_name(op), at);
    node->left = parse_unary();
    return node;
  }

  // ---- rise and fall (issue 29), as RTAMT defines them in discrete time ----
  //   rise φ = φ and not pre φ              (step 0: φ, the step before reads false)
  //   fall φ = not φ and not pre (not φ)    (step 0: not φ, the step before reads true)
  // Written out with `pre`, so every monitor (Boolean, robustness, data
  // references, --explain) has them with nothing of its own; the robustness
  // is RTAMT's min(φ, -previous φ) / min(previous φ, -φ).
  static constexpr size_t kMaxEdgeCopies = 100000;  // nodes copied for rise/fall in one spec
  size_t edge_copies_ = 0;

  NodePtr copy_of(const Node& n) {
    if (++edge_copies_ > kMaxEdgeCopies)
      throw SpecError("rise/fall nested too deeply: each one copies its operand, and this spec would copy more than " +
                          std::to_string(kMaxEdgeCopies) + " operators",
                      s_, n.column > 0 ? n.column : 1);
    auto c = std::make_unique<Node>();
    c->op = n.op;
    c->column = n.column;
    c->bounds = n.bounds;
    c->test = n.test;
    c->variables = n.variables;
    if (n.left) c->left = copy_of(*n.left);
    if (n.right) c->right = copy_of(*n.right);
    return c;
  }
  NodePtr unary(Op op, NodePtr operand, size_t at) {
    auto n = make(op, at);
    n->left = std::move(operand);
    return n;
  }

  NodePtr parse_edge_opt() {
    const size_t at = pos_;
    const bool rise = peek_word("rise");
    if (!rise && !peek_word("fall")) return nullptr;
    if (opt_.dense)
      fail(std::string(rise ? "rise" : "fall") +
               " marks an instant, and in dense time a signal holds values over intervals (RTAMT's dense monitors "
               "have no rise/fall either): check it in discrete time",
           at);
    pos_ += 4;
    Nest nest(*this, at);
    NodePtr operand = parse_unary();
    NodePtr before = copy_of(*operand);
    if (!rise) {
      operand = unary(Op::Not, std::move(operand), at);
      before = unary(Op::Not, std::move(before), at);
    }
    auto edge = make(Op::And, at);
    edge->left = std::move(operand);
    edge->right = unary(Op::Not, unary(Op::Pre, std::move(before), at), at);
    return edge;
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
        refuse_chain();
        fail(at_end() ? "missing ')' to close the '(' at column " + column_text(at)
                      : "expected ')' to close the '(' at column " + column_text(at),
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
      if (word == "and" || word == "or" || word == "implies" || word == "since" || word == "S" || word == "until")
        fail("'" + word + "' needs a formula on its left", pos_);
      fail("unknown word '" + word + "': atoms are written in braces, e.g. {" + word + "}", pos_);
    }
    fail("unexpected '" + std::string(1, c) + "': expected a formula", pos_);
  }

  // After a complete since/until: another one needs parentheses (Reelay
  // silently drops the last part of `a since b since c`).
  void refuse_chain() const {
    if (peek_word("since") || peek_word("S"))
      fail("chained 'since' is ambiguous: add parentheses, e.g. (a since b) since c", pos_);
    if (peek_word("until"))
      fail("chained 'until' is ambiguous: add parentheses, e.g. (a until[0:1] b) until[0:1] c", pos_);
  }

  // A future operator is monitored with a delay equal to its horizon
  // (spec/pastify.hpp): without an upper bound no verdict would ever be known.
  void check_future_bounds(const Bounds& b, const char* name, size_t at) const {
    if (!b.explicit_bounds || b.hi == kInfinity)
      fail("unbounded future: '" + std::string(name) + "' needs an upper time bound to be monitored online, e.g. " +
               name + (std::string(name) == "until" ? "[0:5]" : "[0:5] {p}") +
               " (its verdicts are then known 5 time units late)",
           at);
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
    if (has_lo) b.lo = parse_bound_number(b.lo_ns);
    expect(":", "between the lower and upper time bound, e.g. [3:10]");
    skip_ws();
    if (peek() != ']') b.hi = parse_bound_number(b.hi_ns);
    skip_ws();
    if (peek() != ']') fail("expected ']' to close the time bounds opened at column " + column_text(open), pos_);
    ++pos_;
    if (b.hi < b.lo) fail("empty time interval: the lower bound is greater than the upper bound", open);
    return b;
  }

  double parse_bound_number(double& ns) {
    skip_ws();
    size_t at = pos_;
    if (peek() == '-') fail("time bounds must not be negative", at);
    if (!opt_.dense) {
      // Discrete bounds count steps: read them as integers, never through a
      // double that would round or saturate a huge bound silently.
      size_t end = pos_;
      while (end < s_.size() && std::isdigit(static_cast<unsigned char>(s_[end]))) ++end;
      const bool fraction = end < s_.size() && (s_[end] == '.' || s_[end] == 'e' || s_[end] == 'E');
      if (end > pos_ && !fraction) {
        uint64_t v = 0;
        auto [ptr, ec] = std::from_chars(s_.data() + pos_, s_.data() + end, v);
        if (ec == std::errc::result_out_of_range || (ec == std::errc() && v > kMaxDiscreteBound))
          fail("time bound " + s_.substr(pos_, end - pos_) + " is too large: discrete bounds go up to " +
                   std::to_string(kMaxDiscreteBound) + " steps",
               at);
        pos_ = end;
        return static_cast<double>(v);
      }
    }
    const size_t token_at = pos_;
    double v = parse_number_token("a time bound");
    if (opt_.dense) {
      // Exact nanoseconds from the text (0.025 is 25000000 ns, not the
      // double nearest to 0.025 s), within the span dense time holds exactly.
      int64_t exact = 0;
      const SecondsStatus st = parse_seconds(std::string_view(s_).substr(token_at, pos_ - token_at), exact);
      if (st != SecondsStatus::Ok || exact > kExactSpanNs)
        fail("time bound " + s_.substr(token_at, pos_ - token_at) +
                 " is too large: dense time is exact to the nanosecond up to 9007199.254740992 s (2^53 ns, "
                 "about 104 days), and bounds must lie within it",
             at);
      ns = static_cast<double>(exact);
    }
    if (!opt_.dense && v != std::floor(v))
      fail("discrete time needs integer bounds (use --dense for real-valued bounds)", at);
    if (!opt_.dense && v > static_cast<double>(kMaxDiscreteBound))
      fail("time bound is too large: discrete bounds go up to " + std::to_string(kMaxDiscreteBound) + " steps", at);
    if (std::isinf(v) || std::isnan(v)) fail("time bound out of range (not a finite number)", at);
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
    if (ec == std::errc::result_out_of_range && ptr == s_.data() + end)
      fail(std::string("the number for ") + what + " is out of range (not a finite number)", at);
    if (ec != std::errc() || ptr != s_.data() + end || end == at)
      fail(std::string("expected a number for ") + what, at);
    pos_ = end;
    return v;
  }

  // braces := '{' test (',' test)* '}'  — a conjunction of field tests
  NodePtr parse_braces() {
    size_t open = pos_++;
    std::vector<NodePtr> tests;
    std::vector<int> ands;  // every conjunction of a braces group sits at its '{'
    const int open_column = column(open);
    for (;;) {
      auto leaf = make(Op::Test, pos_);
      leaf->test = parse_field_test();
      leaf->column = leaf->test.column;
      if (!tests.empty()) ands.push_back(open_column);
      tests.push_back(std::move(leaf));
      skip_ws();
      if (peek() == ',') { ++pos_; continue; }
      if (peek() == '}') { ++pos_; return chain(Op::And, tests, ands); }
      if (at_end()) fail("missing '}' to close the atom opened at column " + column_text(open), pos_);
      fail("expected ',' or '}' in the atom opened at column " + column_text(open), pos_);
    }
  }

  std::string parse_key_segment() {
    skip_ws();
    if (peek() == '"') {
      const size_t at = pos_;
      std::string key = parse_quoted();
      if (is_index_part(key) || is_every_part(key))
        fail("a key written like an array element (\"" + key + "\") is ambiguous", at);
      return key;
    }
    if (!is_ident_start(peek())) {
      if (peek() == '}') fail("empty atom: expected a field name, e.g. {speed > 3}", pos_);
      fail("expected a field name", pos_);
    }
    size_t start = pos_;
    while (is_ident_char(peek())) ++pos_;
    return s_.substr(start, pos_ - start);
  }

  // Array elements after a field name: {ranges[0] < 0.5}, {grid[2][3]}.
  void parse_indexes(std::vector<std::string>& path) {
    while (peek() == '[') {
      const size_t open = pos_++;
      if (peek() == '*') {  // every element: only inside an array quantifier
        if (!in_quantifier_)
          fail("'[*]' (every element) is written inside all(..), any(..) or count(..), e.g. {all(ranges[*] > 0.2)}",
               open);
        if (every_parts_++ > 0) fail("one '[*]' per quantifier: nested quantifiers are not supported", open);
        ++pos_;
        if (peek() != ']') fail("expected ']' after '[*'", pos_);
        ++pos_;
        path.push_back(kEveryElement);
        continue;
      }
      const size_t start = pos_;
      while (std::isdigit(static_cast<unsigned char>(peek()))) ++pos_;
      if (pos_ == start) fail("expected an array index (0, 1, ...) after '['", pos_);
      if (pos_ - start > 9) fail("array index too large", start);
      if (peek() != ']') fail("expected ']' to close the index opened at column " + column_text(open), pos_);
      ++pos_;
      path.push_back("[" + std::to_string(std::stoul(s_.substr(start, pos_ - 1 - start))) + "]");
    }
  }

  std::string parse_quoted() {
    size_t open = pos_++;
    std::string out;
    while (!at_end() && peek() != '"') {
      if (peek() == '\\' && pos_ + 1 < s_.size()) ++pos_;
      out.push_back(s_[pos_++]);
    }
    if (at_end()) fail("unterminated string started at column " + column_text(open), open);
    ++pos_;
    return out;
  }

  // An aggregate's name followed by its window or its '(': count[0:1](..),
  // sum(..). A field may be named "count": {count > 3}, {count[2] > 3} (an
  // array element: no ':' inside the brackets) stay field tests.
  bool peek_aggregate(Timed::Func& func, size_t& length) const {
    static constexpr std::pair<const char*, Timed::Func> kFuncs[] = {
        {"count", Timed::Func::Count}, {"sum", Timed::Func::Sum}, {"avg", Timed::Func::Avg},
        {"min", Timed::Func::Min},     {"max", Timed::Func::Max}};
    for (const auto& [word, f] : kFuncs) {
      const size_t n = std::char_traits<char>::length(word);
      if (s_.compare(pos_, n, word) != 0 || pos_ + n >= s_.size()) continue;
      const char next = s_[pos_ + n];
      bool window = false;
      if (next == '[') {
        // Scans only to the first ':' or ']', which the parse then consumes either way.
        const size_t first = s_.find_first_of(":]", pos_ + n);
        window = first != std::string::npos && s_[first] == ':';
      }
      if (next == '(' || window) {
        func = f;
        length = n;
        return true;
      }
    }
    return false;
  }

  // ---- Array quantifiers (issue 29): all(a[*] > 0), any(..), count(..) >= 3 ----
  // all( and any( always start one; count( only with a '[*]' inside its
  // parentheses (else it is count(x), the aggregate over the whole past).
  bool peek_array_quantifier(ArrayQuant::Kind& kind, size_t& length) const {
    static constexpr std::pair<const char*, ArrayQuant::Kind> kWords[] = {
        {"all", ArrayQuant::Kind::All}, {"any", ArrayQuant::Kind::Any}, {"count", ArrayQuant::Kind::Count}};
    for (const auto& [word, k] : kWords) {
      const size_t n = std::char_traits<char>::length(word);
      if (s_.compare(pos_, n, word) != 0 || pos_ + n >= s_.size() || s_[pos_ + n] != '(') continue;
      if (k == ArrayQuant::Kind::Count) {
        int depth = 0;
        bool every = false;
        for (size_t i = pos_ + n; i < s_.size() && !every; ++i) {
          const char c = s_[i];
          if (c == '"') {  // a quoted key or string: skip it
            for (++i; i < s_.size() && s_[i] != '"'; ++i)
              if (s_[i] == '\\') ++i;
          } else if (c == '(') {
            ++depth;
          } else if (c == ')') {
            if (--depth == 0) break;
          } else if (c == '}' || c == '{') {
            break;
          } else if (c == '[' && s_.compare(i, 3, kEveryElement) == 0) {
            every = true;
          }
        }
        if (!every) continue;
      }
      kind = k;
      length = n;
      return true;
    }
    return false;
  }

  FieldTest parse_array_quantifier(FieldTest t, ArrayQuant::Kind kind, size_t length) {
    const std::string name = s_.substr(pos_, length);
    if (in_quantifier_) fail("quantifiers do not nest: " + name + "(..) inside another", pos_);
    pos_ += length + 1;  // the name and its '('
    skip_ws();
    const size_t inner_at = pos_;
    in_quantifier_ = true;
    every_parts_ = 0;
    FieldTest element = parse_field_test();
    in_quantifier_ = false;
    using FOp = FieldTest::Op;
    if (element.is_timed() || element.op == FOp::Present || element.op == FOp::Bind)
      fail(name + "(..) tests each element of an array against a value, e.g. " + name +
               "(ranges[*] > 0.2); this test is not one",
           inner_at);
    if (every_parts_ == 0)
      fail(name + "(..) needs an array path with '[*]' (every element), e.g. " + name + "(ranges[*] > 0.2)", inner_at);
    skip_ws();
    if (peek() != ')') fail("expected ')' to close " + name + "(", pos_);
    ++pos_;
    element.column = t.column;
    element.quant.kind = kind;
    if (kind == ArrayQuant::Kind::Count) {
      FieldTest cmp;
      parse_number_comparison(cmp, "count(..)", "{count(objects[*].distance < 2) >= 3}");
      element.quant.count_op = static_cast<uint8_t>(cmp.op);
      element.quant.count_value = cmp.value.number;
    }
    return element;
  }
  bool in_quantifier_ = false;
  int every_parts_ = 0;

  // A field path, or an input's timing atom as its last part: {@age ..},
  // {steer.@age ..}. Returns where the timing atom was written (npos: none).
  size_t parse_path(FieldTest& t) {
    for (;;) {
      skip_ws();
      if (peek() == '@') {
        const size_t at = pos_++;
        while (is_ident_char(peek())) ++pos_;
        const std::string name = s_.substr(at, pos_ - at);
        if (name == "@arrived") t.timed.kind = Timed::Kind::Arrived;
        else if (name == "@age") t.timed.kind = Timed::Kind::Age;
        else if (name == "@latency") t.timed.kind = Timed::Kind::Latency;
        else fail("unknown timing atom '" + name + "': there are @arrived, @age and @latency", at);
        if (t.path.size() > 1 || (t.path.size() == 1 && is_index_part(t.path[0])))
          fail("'" + name + "' follows an input's name ({steer." + name.substr(1) + "}), not a field", at);
        t.path.push_back(name);
        if (peek() == '.' || peek() == '[') fail("'" + name + "' ends the path: nothing can follow it", pos_);
        return at;
      }
      t.path.push_back(parse_key_segment());
      parse_indexes(t.path);
      if (peek() != '.') return std::string::npos;  // nested field: {pose.position.x > 1}
      ++pos_;
    }
  }

  // The comparison a timing atom or an aggregate needs: {x.@age <= 0.1}.
  void parse_number_comparison(FieldTest& t, const std::string& what, const std::string& example) {
    skip_ws();
    const size_t op_at = pos_;
    using FOp = FieldTest::Op;
    if (accept_symbol("==")) t.op = FOp::Eq;
    else if (accept_symbol("!=")) t.op = FOp::Ne;
    else if (accept_symbol("<=")) t.op = FOp::Le;
    else if (accept_symbol(">=")) t.op = FOp::Ge;
    else if (accept_symbol("<")) t.op = FOp::Lt;
    else if (accept_symbol(">")) t.op = FOp::Gt;
    else fail(what + " is a number: compare it (< <= > >= == !=) with one, e.g. " + example, op_at);
    skip_ws();
    const size_t lit_at = pos_;
    t.value = parse_literal(/*allow_bare_word=*/false);
    if (t.value.kind != Literal::Kind::Number) fail(what + " is compared with a number; this is not a number", lit_at);
  }

  // {count[0:1](steer.@arrived) >= 20}, {avg[0:2](steer.speed) > 3}
  FieldTest parse_aggregate(FieldTest t, Timed::Func func, size_t length) {
    const size_t at = pos_;
    const std::string name = s_.substr(pos_, length);
    pos_ += length;
    t.timed.func = func;
    t.timed.window = parse_bounds_opt(at);
    expect("(", "after '" + name + "[a:b]' to name what it aggregates, e.g. count[0:1](x.@arrived), avg[0:2](x.speed)");
    skip_ws();
    const size_t inner_at = pos_;
    const size_t atom_at = parse_path(t);
    if (t.timed.kind == Timed::Kind::Age || t.timed.kind == Timed::Kind::Latency)
      fail(name + " aggregates a field or arrivals (x.@arrived), not " + std::string(timed_name(t.timed.kind)), atom_at);
    t.timed.of_arrivals = t.timed.kind == Timed::Kind::Arrived;
    if (t.timed.of_arrivals && func != Timed::Func::Count)
      fail("arrivals are counted: count[a:b](x.@arrived); " + name + " takes a numeric field", inner_at);
    skip_ws();
    if (peek() != ')') fail("expected ')' to close " + name + "(", pos_);
    ++pos_;
    t.timed.kind = Timed::Kind::Aggregate;
    parse_number_comparison(t, "an aggregate", "{" + name + "[0:1](x.speed) > 3}");
    return t;
  }

  FieldTest parse_field_test() {
    FieldTest t;
    skip_ws();
    t.column = column(pos_);
    expr_nodes_ = 0;
    Timed::Func func;
    size_t length = 0;
    ArrayQuant::Kind quant;
    if (peek_array_quantifier(quant, length)) return parse_array_quantifier(std::move(t), quant, length);
    if (peek_aggregate(func, length) && !peek_function(pos_)) return parse_aggregate(std::move(t), func, length);
    if (starts_expression()) return finish_expression_test(std::move(t), parse_expr());
    const size_t path_at = pos_;
    const size_t atom_at = parse_path(t);
    if (t.is_timed()) return finish_timing_atom(std::move(t), atom_at);
    skip_ws();
    if (is_arithmetic(peek())) {
      // The expression is read before t is moved: function arguments are evaluated in no fixed
      // order (clang moved t first and the field's path was lost; fuzz_spec found it).
      ExprPtr lhs = parse_expr(field_expr(t.path, path_at));
      return finish_expression_test(std::move(t), std::move(lhs));
    }
    size_t op_at = pos_;
    using FOp = FieldTest::Op;
    if (peek() == ',' || peek() == '}' || (in_quantifier_ && peek() == ')')) { t.op = FOp::Truthy; return t; }
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
    if (rhs_is_expression(t.op)) {  // {a.x < b.x}, {x > 2 * y}
      ExprPtr lhs = field_expr(t.path, path_at);
      t.path.clear();
      return make_expression_test(std::move(t), std::move(lhs), parse_expr());
    }
    size_t lit_at = pos_;
    t.value = parse_literal(/*allow_bare_word=*/true);
    bool ordering = t.op == FOp::Lt || t.op == FOp::Le || t.op == FOp::Gt || t.op == FOp::Ge;
    if (ordering && t.value.kind != Literal::Kind::Number)
      fail("'<', '<=', '>', '>=' compare numbers; this is not a number", lit_at);
    return t;
  }

  // ---- Arithmetic in atoms (issue 29) ----
  //   expr    := term (('+' | '-') term)*
  //   term    := unary (('*' | '/') unary)*
  //   unary   := '-' unary | primary
  //   primary := number | path | '(' expr ')' | abs(expr) | min(expr, expr) | max(expr, expr)
  // min/max with one argument stay the aggregates over the whole past.
  static bool is_arithmetic(char c) { return c == '+' || c == '-' || c == '*' || c == '/'; }

  // At `at`: "abs(", or "min(" / "max(" with two arguments (a ',' at the top
  // level of its parentheses).
  bool peek_function(size_t at) const {
    for (const char* name : {"abs", "min", "max"}) {
      const size_t n = std::char_traits<char>::length(name);
      if (s_.compare(at, n, name) != 0 || at + n >= s_.size() || s_[at + n] != '(') continue;
      if (name[0] == 'a') return true;
      int depth = 0;
      for (size_t i = at + n; i < s_.size(); ++i) {
        const char c = s_[i];
        if (c == '"') {  // a quoted key: skip it
          for (++i; i < s_.size() && s_[i] != '"'; ++i)
            if (s_[i] == '\\') ++i;
        } else if (c == '(' || c == '[') {
          ++depth;
        } else if (c == ')' || c == ']') {
          if (--depth == 0) return false;
        } else if (c == ',' && depth == 1) {
          return true;
        } else if (c == '}' || c == '{') {
          return false;
        }
      }
      return false;
    }
    return false;
  }

  // A test that starts with something no field path starts with: {-x > 1},
  // {(a + b) > 1}, {3 < x}, {abs(x - y) < 0.1}.
  bool starts_expression() const {
    const char c = peek();
    return c == '(' || c == '-' || c == '+' || c == '.' || std::isdigit(static_cast<unsigned char>(c)) ||
           peek_function(pos_);
  }

  // After a comparison: is its right side an expression rather than a
  // literal? A bare word after '==' / '!=' stays a string or a message
  // constant ({gear == REVERSE}); after '<' .. '>=' it is a field.
  bool rhs_is_expression(FieldTest::Op op) const {
    const bool ordering = op != FieldTest::Op::Eq && op != FieldTest::Op::Ne;
    size_t i = pos_;
    const char c = peek();
    auto next_is_arithmetic = [&](size_t j) {
      while (j < s_.size() && std::isspace(static_cast<unsigned char>(s_[j]))) ++j;
      return j < s_.size() && is_arithmetic(s_[j]);
    };
    if (c == '(' || peek_function(i)) return true;
    if (c == '-' || c == '+') {
      size_t j = i + 1;
      while (j < s_.size() && std::isspace(static_cast<unsigned char>(s_[j]))) ++j;
      if (j < s_.size() && (is_ident_start(s_[j]) || s_[j] == '(' || s_[j] == '-')) return true;
    }
    if (c == '-' || c == '+' || c == '.' || std::isdigit(static_cast<unsigned char>(c))) {
      size_t j = i + 1;
      while (j < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[j])) || s_[j] == '.' ||
                               ((s_[j] == '-' || s_[j] == '+') && (s_[j - 1] == 'e' || s_[j - 1] == 'E'))))
        ++j;
      return next_is_arithmetic(j);
    }
    if (!is_ident_start(c)) return false;
    size_t j = i;
    while (j < s_.size() && is_ident_char(s_[j])) ++j;
    const std::string word = s_.substr(i, j - i);
    if (word == "true" || word == "false") return false;
    if (j < s_.size() && (s_[j] == '.' || s_[j] == '[')) return true;
    return ordering || next_is_arithmetic(j);
  }

  // Expressions are trees of shared nodes freed recursively: their size is bounded.
  static constexpr int kMaxExprNodes = 1000;
  int expr_nodes_ = 0;
  std::shared_ptr<Expr> new_expr(Expr::Kind kind, size_t at) {
    if (++expr_nodes_ > kMaxExprNodes)
      fail("expression too long: at most " + std::to_string(kMaxExprNodes) + " numbers, fields and operators in one atom",
           at);
    auto e = std::make_shared<Expr>();
    e->kind = kind;
    e->column = column(at);
    return e;
  }
  ExprPtr field_expr(std::vector<std::string> path, size_t at) {
    auto e = new_expr(Expr::Kind::Field, at);
    e->path = std::move(path);
    return e;
  }
  ExprPtr binary(Expr::Kind kind, ExprPtr a, ExprPtr b, size_t at) {
    auto e = new_expr(kind, at);
    e->args = {std::move(a), std::move(b)};
    return e;
  }

  // `first`: a field already read as the first operand ({a.x - b.x < 1}).
  ExprPtr parse_expr(ExprPtr first = nullptr) {
    ExprPtr left = parse_term(std::move(first));
    for (;;) {
      skip_ws();
      const size_t at = pos_;
      if (peek() != '+' && peek() != '-') return left;
      const Expr::Kind kind = peek() == '+' ? Expr::Kind::Add : Expr::Kind::Sub;
      ++pos_;
      left = binary(kind, std::move(left), parse_term(nullptr), at);
    }
  }
  ExprPtr parse_term(ExprPtr first) {
    ExprPtr left = first ? std::move(first) : parse_expr_unary();
    for (;;) {
      skip_ws();
      const size_t at = pos_;
      if (peek() != '*' && peek() != '/') return left;
      const Expr::Kind kind = peek() == '*' ? Expr::Kind::Mul : Expr::Kind::Div;
      ++pos_;
      left = binary(kind, std::move(left), parse_expr_unary(), at);
    }
  }
  ExprPtr parse_expr_unary() {
    skip_ws();
    const size_t at = pos_;
    if (peek() != '-') return parse_expr_primary();
    Nest nest(*this, at);
    ++pos_;
    ExprPtr operand = parse_expr_unary();
    auto e = new_expr(Expr::Kind::Neg, at);
    if (operand->kind == Expr::Kind::Number) {  // -3 is a number
      e->kind = Expr::Kind::Number;
      e->number = -operand->number;
    } else {
      e->args = {std::move(operand)};
    }
    return e;
  }
  ExprPtr parse_expr_primary() {
    skip_ws();
    const size_t at = pos_;
    const char c = peek();
    if (c == '(') {
      Nest nest(*this, at);
      ++pos_;
      ExprPtr inner = parse_expr();
      skip_ws();
      if (peek() != ')') fail("expected ')' to close the '(' at column " + column_text(at), pos_);
      ++pos_;
      return inner;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      auto e = new_expr(Expr::Kind::Number, at);
      e->number = parse_number_token("the expression");
      if (is_ident_char(peek()))  // {1x}: a key that starts with a digit
        fail("expected a field name: names start with a letter or '_' (quote other keys: {\"1x\"})", at);
      return e;
    }
    if (peek_function(at)) {
      Nest nest(*this, at);
      const Expr::Kind kind = c == 'a' ? Expr::Kind::Abs : s_[at + 1] == 'i' ? Expr::Kind::Min : Expr::Kind::Max;
      pos_ += 4;  // "abs(", "min(", "max("
      auto e = new_expr(kind, at);
      e->args.push_back(parse_expr());
      if (kind != Expr::Kind::Abs) {
        expect(",", "between the two arguments of " + s_.substr(at, 3));
        e->args.push_back(parse_expr());
      }
      skip_ws();
      if (peek() == ',') fail(s_.substr(at, 3) + " takes " + (kind == Expr::Kind::Abs ? "one argument" : "two arguments"), pos_);
      if (peek() != ')') fail("expected ')' to close " + s_.substr(at, 4), pos_);
      ++pos_;
      return e;
    }
    if (is_ident_start(c) || c == '"' || c == '@') {
      Timed::Func func;
      size_t length = 0;
      if (peek_aggregate(func, length))
        fail("an aggregate is compared with a number ({avg[0:2](x) > 3}); it cannot be part of an expression", at);
      FieldTest t;
      const size_t atom_at = parse_path(t);
      if (t.is_timed()) fail("a timing atom is compared with a number ({x.@age <= 0.1}); it cannot be part of an expression", atom_at);
      return field_expr(std::move(t.path), at);
    }
    if (c == '}' || c == ',' || at_end()) fail("expected a number, a field or '(' to complete the expression", at);
    fail("unexpected '" + std::string(1, c) + "' in an expression: expected a number, a field, '(', abs, min or max", at);
  }

  // The comparison after an expression, and its right side.
  FieldTest finish_expression_test(FieldTest t, ExprPtr lhs) {
    skip_ws();
    const size_t op_at = pos_;
    using FOp = FieldTest::Op;
    if (accept_symbol("==")) t.op = FOp::Eq;
    else if (accept_symbol("!=")) t.op = FOp::Ne;
    else if (accept_symbol("<=")) t.op = FOp::Le;
    else if (accept_symbol(">=")) t.op = FOp::Ge;
    else if (accept_symbol("<")) t.op = FOp::Lt;
    else if (accept_symbol(">")) t.op = FOp::Gt;
    else fail("an expression is a number: compare it (< <= > >= == !=) with another, e.g. {abs(a - b) < 0.1}", op_at);
    t.path.clear();
    return make_expression_test(std::move(t), std::move(lhs), parse_expr());
  }

  static FieldTest make_expression_test(FieldTest t, ExprPtr lhs, ExprPtr rhs) {
    if (lhs->kind == Expr::Kind::Field && rhs->kind == Expr::Kind::Number) {  // {(x) < 3} is {x < 3}
      t.path = lhs->path;
      t.value.kind = Literal::Kind::Number;
      t.value.number = rhs->number;
      return t;
    }
    t.timed.kind = Timed::Kind::Expr;
    t.lhs = std::move(lhs);
    t.rhs = std::move(rhs);
    return t;
  }

  // {x.@arrived} alone; {x.@age <= d} and {x.@latency < d} compare.
  FieldTest finish_timing_atom(FieldTest t, size_t atom_at) {
    skip_ws();
    if (t.timed.kind == Timed::Kind::Arrived) {
      if (opt_.dense)
        fail("in dense time an arrival is an instant and holds no value over time: write {x.@age <= d} for "
             "silence or count[a:b](x.@arrived) for a rate",
             atom_at);
      if (peek() != ',' && peek() != '}')
        fail("@arrived is true or false: write {x.@arrived} or not {x.@arrived}", pos_);
      return t;
    }
    if (t.timed.kind == Timed::Kind::Latency && !opt_.dense)
      fail("@latency compares a message's arrival with its stamp: it needs dense time (--dense)", atom_at);
    if (t.timed.kind == Timed::Kind::Age && opt_.dense && opt_.robustness)
      fail("@age grows continuously in dense time, so its margin is no step function: check it without "
           "--robustness (or in discrete time, where it counts steps)",
           atom_at);
    const std::string name = timed_name(t.timed.kind);
    parse_number_comparison(t, name, "{x." + name.substr(0) + " <= 0.1}");
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
      const size_t from = pos_;
      lit.number = parse_number_token("the comparison");
      // An integer literal is exact: beyond 2^53 it is kept as an integer.
      double d;
      ExactInt exact;
      if (integer_literal(std::string_view(s_).substr(from, pos_ - from), d, exact)) lit.number = d, lit.exact = exact;
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
        lit.bare_word = true;
      }
    } else {
      fail(at_end() ? "unexpected end of specification: expected a value" : "expected a value (number, true, false or string)", at);
    }
    return lit;
  }
};

// The parser recurses about seven frames per written level, so the
// kMaxWrittenNesting levels it accepts need more stack than a thread's default
// 8 MiB under ASan (the sanitizer tier overflowed at ~2000 levels). Long specs
// are parsed on a thread of their own with a stack that leaves a wide margin
// in every build; it is reserved, not touched, so it costs only what is used.
// Short specs cannot nest deeply and stay on the caller's thread.
constexpr size_t kParserStack = size_t{256} << 20;
constexpr size_t kShortSpec = 256;

struct ParseJob {
  const std::string* text;
  const ParseOptions* options;
  NodePtr result;
  std::exception_ptr error;
};

void* run_parse_job(void* arg) {
  auto* job = static_cast<ParseJob*>(arg);
  try {
    job->result = Parser(*job->text, *job->options).parse_all();
  } catch (...) {
    job->error = std::current_exception();
  }
  return nullptr;
}

}  // namespace

NodePtr parse(const std::string& text, const ParseOptions& options) {
  if (text.size() <= kShortSpec) return Parser(text, options).parse_all();
  ParseJob job{&text, &options, nullptr, nullptr};
  pthread_attr_t attr;
  pthread_attr_init(&attr);
  pthread_attr_setstacksize(&attr, kParserStack);
  pthread_t thread;
  const int rc = pthread_create(&thread, &attr, run_parse_job, &job);
  pthread_attr_destroy(&attr);
  if (rc != 0) throw std::system_error(rc, std::generic_category(), "cannot start the spec parser's thread");
  pthread_join(thread, nullptr);
  if (job.error) std::rethrow_exception(job.error);
  return std::move(job.result);
}

}  // namespace rvc::spec
