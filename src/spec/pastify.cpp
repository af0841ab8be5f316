#include "spec/pastify.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <utility>

#include "spec/spec_error.hpp"

namespace rvc::spec {

double horizon(const Node& n) {
  const double l = n.left ? horizon(*n.left) : 0;
  const double r = n.right ? horizon(*n.right) : 0;
  switch (n.op) {
    case Op::Eventually:
    case Op::Always: return n.bounds.hi + l;
    case Op::Until: return n.bounds.hi + std::max(l, r);
    case Op::Next: return 1 + l;
    default: return std::max(l, r);
  }
}

bool has_future(const Node& n) {
  return n.is_future() || (n.left && has_future(*n.left)) || (n.right && has_future(*n.right));
}

namespace {

void check_until(const Node& n, bool dense, const std::string& source) {
  if (dense)
    throw SpecError("'until' is not supported in dense time yet (RTAMT's dense monitors lack it too); "
                    "use discrete time, or eventually/always",
                    source, n.column);
  if (n.bounds.hi - n.bounds.lo >= kMaxUntilWindow)
    throw SpecError("until[a:b] with b - a >= " + std::to_string(static_cast<int>(kMaxUntilWindow)) +
                        " is not supported: it is checked as b - a + 1 terms",
                    source, n.column);
}

// A delay computed by subtracting dense bounds may miss the operand's
// horizon by a rounding error: snap to it (delays are never below it).
double snap(double d, double h) {
  if (std::abs(d - h) <= 1e-9 * std::max(1.0, std::abs(d))) return h;
  return d;
}
double delay_of(const Node& n, double d) {
  d = snap(d, horizon(n));
  return d < 1e-12 ? 0 : d;
}

// Node counts saturate here (far above any limit), so that nesting cannot overflow them.
constexpr uint64_t kSaturated = uint64_t{1} << 62;
uint64_t add(uint64_t a, uint64_t b) { return std::min(kSaturated, a + b); }  // both <= kSaturated: no overflow

SpecError too_large(uint64_t nodes, uint64_t limit, const std::string& source, int column) {
  const std::string n = nodes >= kSaturated ? "more than " + std::to_string(kSaturated) : std::to_string(nodes);
  return SpecError("property too large: its rewrite into past operators would need " + n +
                       " operators, the limit is " + std::to_string(limit) +
                       " (until[a:b] is checked as b - a + 1 terms, each with a copy of its operands: "
                       "nesting multiplies them); narrow the bounds or split the property",
                   source, column);
}

// The number of nodes Pastifier::visit(n, d) makes, computed without making
// them (Pastifier's rules, node for node: tests/unit/future_test.cpp checks
// that they agree). until[a:b] copies its operands into each of its b − a + 1
// terms, so nesting multiplies: this is linear in the formula, the rewrite is
// not. Throws SpecError at the column of an until whose rewrite alone is past
// `limit`, and the checks of until (dense time, width) first.
struct Sizer {
  bool dense;
  const std::string& source;
  uint64_t limit;

  static uint64_t delayed(double d) { return d > 0 ? 1 : 0; }                 // the once[d:d] over it
  static uint64_t ended(double e) { return 1 + delayed(e); }                  // the end marker, delayed
  static uint64_t started(double d) { return d > 0 ? 3 : 0; }                 // and + once[d:] + true
  static uint64_t not_started(double d) { return d > 0 ? 4 : 0; }             // or + not + once[d:] + true

  uint64_t visit(const Node& n, double d) {
    d = delay_of(n, d);
    switch (n.op) {
      case Op::True:
      case Op::False: return 1;
      case Op::Test: return 1 + delayed(d);
      case Op::Not:
      case Op::Exists:
      case Op::Forall: return add(1, visit(*n.left, d));
      case Op::And:
      case Op::Or:
      case Op::Implies: return add(1, add(visit(*n.left, d), visit(*n.right, d)));
      // guard_pre: or + (and + once[d:] + true) + (and + not + once[d:] + true + once + false)
      case Op::Pre: return add(1 + (d > 0 ? 10 : 0), visit(*n.left, d));
      case Op::Once: return add(1 + started(d), visit(*n.left, d));
      case Op::Historically: return add(1 + not_started(d), visit(*n.left, d));
      case Op::Since: return add(1 + started(d), add(visit(*n.left, d), visit(*n.right, d)));
      case Op::Eventually: {
        const double e = d - n.bounds.hi;
        return add(2 + ended(e) + window(n), visit(*n.left, e));
      }
      case Op::Always: {
        const double e = d - n.bounds.hi;
        return add(1 + ended(e) + window(n), visit(*n.left, e));
      }
      case Op::Next: return add(2 + ended(d - 1), visit(*n.left, d - 1));
      case Op::Until: return until(n, d);
    }
    return 1;
  }
  static uint64_t window(const Node& n) { return n.bounds.hi - n.bounds.lo > 0 ? 1 : 0; }

  uint64_t until(const Node& n, double d) {
    check_until(n, dense, source);
    const double a = n.bounds.lo, b = n.bounds.hi, w = b - a, e = d - b;
    const uint64_t witness = add(2 + ended(e), visit(*n.right, e));  // and, not, end marker; ψ
    const uint64_t held = add(2, visit(*n.left, e));                 // and, historically; φ
    uint64_t total = 0, terms = 0;
    for (double k = 0; k <= w; ++k, ++terms) {
      total = add(total, add(witness, delayed(w - k)));
      if (a + k > 0) total = add(total, held);
    }
    total = add(total, terms - 1);  // the ors between the terms
    if (total > limit) throw too_large(total, limit, source, n.column);
    return total;
  }
};

struct Pastifier {
  const FieldTest& end;
  bool dense;
  const std::string& source;

  static NodePtr node(Op op, int column, NodePtr left = nullptr, NodePtr right = nullptr) {
    auto n = std::make_unique<Node>();
    n->op = op;
    n->column = column;
    n->left = std::move(left);
    n->right = std::move(right);
    return n;
  }
  static NodePtr bounded(Op op, double lo, double hi, int column, NodePtr left, NodePtr right = nullptr) {
    auto n = node(op, column, std::move(left), std::move(right));
    n->bounds.lo = lo;
    n->bounds.hi = hi;
    n->bounds.explicit_bounds = true;
    return n;
  }
  // once[d:d] φ: φ's value d time units ago (φ itself when d = 0).
  static NodePtr delayed(NodePtr f, double d, int column) {
    if (d <= 0) return f;
    return bounded(Op::Once, d, d, column, std::move(f));
  }
  // S(d): the time referred to (t − d) is not before the start.
  static NodePtr started(double d, int column) { return bounded(Op::Once, d, kInfinity, column, node(Op::True, column)); }
  // E(e): t − e is past the end of the stream.
  NodePtr ended(double e, int column) const {
    auto atom = node(Op::Test, column);
    atom->test = end;
    return delayed(std::move(atom), e, column);
  }
  static NodePtr both(NodePtr a, NodePtr b, int column) { return node(Op::And, column, std::move(a), std::move(b)); }
  static NodePtr either(NodePtr a, NodePtr b, int column) { return node(Op::Or, column, std::move(a), std::move(b)); }
  static NodePtr negate(NodePtr a, int column) { return node(Op::Not, column, std::move(a)); }

  NodePtr visit(const Node& n, double d) {
    d = delay_of(n, d);
    const int c = n.column;
    switch (n.op) {
      case Op::True:
      case Op::False: return node(n.op, c);
      case Op::Test: {
        auto atom = node(Op::Test, c);
        atom->test = n.test;
        return delayed(std::move(atom), d, c);
      }
      case Op::Not: return negate(visit(*n.left, d), c);
      case Op::And:
      case Op::Or:
      case Op::Implies: return node(n.op, c, visit(*n.left, d), visit(*n.right, d));
      case Op::Exists:
      case Op::Forall: {
        auto q = node(n.op, c, visit(*n.left, d));
        q->variables = n.variables;
        return q;
      }
      case Op::Pre: return node(Op::Pre, c, guard_pre(visit(*n.left, d), d, c));
      // The bounds as written: an unbounded once/historically keeps its robustness start at the
      // lowest/highest finite double (docs/semantics.md's table), where once[0:] starts at -inf.
      case Op::Once: {
        auto o = node(Op::Once, c, guard_true(visit(*n.left, d), d, c));
        o->bounds = n.bounds;
        return o;
      }
      case Op::Historically: {
        auto h = node(Op::Historically, c, guard_false(visit(*n.left, d), d, c));
        h->bounds = n.bounds;
        return h;
      }
      case Op::Since: {
        auto s = node(Op::Since, c, visit(*n.left, d), guard_true(visit(*n.right, d), d, c));
        s->bounds = n.bounds;
        return s;
      }
      case Op::Eventually: {
        const double e = d - n.bounds.hi;
        auto operand = both(visit(*n.left, e), negate(ended(e, c), c), c);
        return window(Op::Once, n.bounds.hi - n.bounds.lo, std::move(operand), c);
      }
      case Op::Always: {
        const double e = d - n.bounds.hi;
        auto operand = either(visit(*n.left, e), ended(e, c), c);
        return window(Op::Historically, n.bounds.hi - n.bounds.lo, std::move(operand), c);
      }
      case Op::Next: return both(visit(*n.left, d - 1), negate(ended(d - 1, c), c), c);
      case Op::Until: return until(n, d);
    }
    return node(Op::False, c);
  }

  static NodePtr window(Op op, double width, NodePtr operand, int c) {
    if (width <= 0) return operand;  // once[0:0] φ is φ
    return bounded(op, 0, width, c, std::move(operand));
  }
  // Operands of past operators: false (once, since) or true (historically)
  // where the time they refer to is before the start.
  static NodePtr guard_true(NodePtr f, double d, int c) { return d > 0 ? both(std::move(f), started(d, c), c) : std::move(f); }
  static NodePtr guard_false(NodePtr f, double d, int c) {
    return d > 0 ? either(std::move(f), negate(started(d, c), c), c) : std::move(f);
  }
  // pre's operand: where its time is before the start, what pre gives at the first step (false;
  // robustness: the lowest finite double, which `once false` is), not -inf:
  // (f and S(d)) or (not S(d) and once false).
  static NodePtr guard_pre(NodePtr f, double d, int c) {
    if (d <= 0) return f;
    auto first = both(negate(started(d, c), c), node(Op::Once, c, node(Op::False, c)), c);
    return either(both(std::move(f), started(d, c), c), std::move(first), c);
  }

  // φ until[a:b] ψ at t − d: some J in [t−d+a, t−d+b] with ψ(J) and φ on
  // [t−d, J). With both operands at delay e = d − b, J = t − (w − k) for k
  // in 0..w and [t−d, J) is [t−b, t−(w−k)−1] in monitor time.
  NodePtr until(const Node& n, double d) {
    const int c = n.column;
    check_until(n, dense, source);
    const double a = n.bounds.lo, b = n.bounds.hi, w = b - a;
    const double e = d - b;
    NodePtr result;
    for (double k = 0; k <= w; ++k) {
      auto witness = delayed(both(visit(*n.right, e), negate(ended(e, c), c), c), w - k, c);
      NodePtr term;
      if (a + k > 0) {
        // φ on the a + k steps before the witness.
        auto held = bounded(Op::Historically, w - k + 1, b, c, visit(*n.left, e));
        term = both(std::move(witness), std::move(held), c);
      } else {
        term = std::move(witness);
      }
      result = result ? either(std::move(result), std::move(term), c) : std::move(term);
    }
    return result;
  }
};

}  // namespace

uint64_t pastified_size(const Node& root, double h, bool dense, const std::string& source) {
  return Sizer{dense, source, kSaturated}.visit(root, h);
}

NodePtr pastify(const Node& root, double h, const FieldTest& end_marker, bool dense, const std::string& source) {
  // The size first: a rewrite past the limit is refused before it is made
  // (nested until[0:255] would otherwise take minutes and gigabytes to build).
  if (const uint64_t n = Sizer{dense, source, kMaxPastifiedNodes}.visit(root, h); n > kMaxPastifiedNodes)
    throw too_large(n, kMaxPastifiedNodes, source, root.column);
  Pastifier p{end_marker, dense, source};
  return p.visit(root, h);
}

}  // namespace rvc::spec
