#include "engine/timed/timed_atoms.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "spec/exact_time.hpp"

namespace rvc::engine::timed {
namespace {

using Kind = spec::Timed::Kind;
using FOp = spec::FieldTest::Op;
constexpr double kInf = std::numeric_limits<double>::infinity();

bool compare(FOp op, double v, double c) {
  if (std::isnan(v)) return false;  // unknown (empty window, no latency): every comparison is false
  switch (op) {
    case FOp::Lt: return v < c;
    case FOp::Le: return v <= c;
    case FOp::Gt: return v > c;
    case FOp::Ge: return v >= c;
    case FOp::Eq: return v == c;
    case FOp::Ne: return v != c;
    default: return v != 0;
  }
}

// Reelay's margins for a numeric test (io::test_margin's rule).
double margin(FOp op, double v, double c) {
  if (std::isnan(v)) return -kInf;
  switch (op) {
    case FOp::Lt:
    case FOp::Le: return c - v;
    case FOp::Gt:
    case FOp::Ge: return v - c;
    case FOp::Eq: return -std::fabs(v - c);
    case FOp::Ne: return std::fabs(v - c);
    default: return v;
  }
}

}  // namespace

TimedAtoms::TimedAtoms(AtomTable& atoms, const std::vector<std::string>& inputs, TimeModel model)
    : dense_(model == TimeModel::Dense), inputs_(inputs.size()) {
  const size_t n = atoms.size();  // hidden tests are added behind: not scanned again
  for (size_t id = 0; id < n; ++id) {
    const spec::FieldTest test = atoms.tests()[id];  // a copy: intern() below may grow the table
    if (!test.is_timed()) continue;
    if (test.is_expr()) {  // whatever inputs its fields come from: they carry the input's name
      auto leaf_of = [&](const std::vector<std::string>& path) {
        spec::FieldTest field;
        field.path = path;
        field.op = FOp::Value;
        const int hidden = atoms.intern(field);
        for (size_t k = 0; k < leaves_.size(); ++k)
          if (leaves_[k].id == hidden) return static_cast<int>(k);
        leaves_.push_back({hidden, field.key()});
        return static_cast<int>(leaves_.size() - 1);
      };
      ExprAtom e{static_cast<int>(id), test.op, CompiledExpr(*test.lhs, leaf_of), CompiledExpr(*test.rhs, leaf_of), {}};
      std::vector<const spec::Expr*> fields;
      spec::expr_fields(*test.lhs, fields);
      spec::expr_fields(*test.rhs, fields);
      for (const spec::Expr* f : fields) e.leaves.push_back(leaf_of(f->path));
      exprs_.push_back(std::move(e));
      field_values_ = true;
      continue;
    }
    // {steer.@age ..}, count(steer.@arrived), avg(steer.speed): the input
    // comes first; with one unnamed input there is none ({@age ..}, avg(speed)).
    const bool named = !inputs.empty() && !inputs[0].empty();
    const std::string input =
        test.timed.kind == Kind::Aggregate ? (named ? test.path[0] : std::string())
                                           : (test.path.size() > 1 ? test.path[0] : std::string());
    uint32_t k = 0;
    bool found = false;
    for (uint32_t i = 0; i < inputs.size(); ++i)
      if (inputs[i] == input) k = i, found = true;
    if (!found) throw std::invalid_argument("'" + test.to_string() + "' names no input");
    Atom a{static_cast<int>(id), k, test.timed.kind, test.op, test.value.number};
    // Dense time runs in nanoseconds (spec/exact_time.hpp): an age or latency
    // bound of 0.025 s is 25000000 ns exactly, read from the literal's
    // shortest text, so a gap of exactly the bound is never a violation.
    if (dense_ && (a.kind == Kind::Age || a.kind == Kind::Latency)) a.bound = spec::seconds_to_ns(a.bound);
    if (test.timed.kind == Kind::Latency) latency_ = true;
    if (test.timed.kind == Kind::Aggregate) {
      Source src{k, test.timed.of_arrivals};
      if (!src.of_arrivals) {
        spec::FieldTest field;
        field.path = test.path;
        field.op = FOp::Present;
        src.present = atoms.intern(field);
        field.op = FOp::Truthy;
        src.value = atoms.intern(field);
        field_values_ = true;
      }
      a.window = static_cast<int>(windows_.size());
      spec::Bounds window = test.timed.window;
      if (dense_) window.lo = window.lo_ns, window.hi = window.hi_ns;  // the exact nanoseconds of its text
      windows_.emplace_back(test.timed.func, window, dense_);
      sources_.push_back(src);
    }
    atoms_.push_back(a);
  }
}

void TimedAtoms::advance(double t) {
  if (!(t >= now_)) return;
  now_ = t;
  for (auto& w : windows_) w.advance(t);
}

void TimedAtoms::arrive(uint32_t input, double latency, const uint8_t* values, const double* margins) {
  InputState& in = inputs_[input];
  in.any = true;
  in.last = now_;
  in.latency = latency;
  in.arrived_at = now_;
  for (size_t k = 0; k < windows_.size(); ++k) {
    const Source& s = sources_[k];
    if (s.input != input) continue;
    if (s.of_arrivals) {
      windows_[k].add(now_, 1);
      continue;
    }
    // A message without the field (or with a value that is not a number)
    // gives no sample: the window holds the messages that carried one.
    if (!values[s.present] || !margins) continue;
    const double v = margins[s.value];
    if (std::isfinite(v)) windows_[k].add(now_, v);
  }
  if (exprs_.empty()) return;
  for (Leaf& l : leaves_) {
    if (!values[l.id] || !margins) continue;
    l.number = margins[l.id];
    l.seen = true;
  }
  evaluate_exprs();
}

// Each field an expression reads keeps its last number (a message without
// it, or with a value of another type, changes nothing: Reelay's rule for
// every test); before its first number the expression has no value, and
// every comparison with it is false (margin -inf, as a field never seen).
void TimedAtoms::evaluate_exprs() {
  // (Called after every message; the leaves are re-read from the committed
  // values: in a synchronized run this message's input wrote its own.)
  leaf_numbers_.resize(leaves_.size());
  for (size_t k = 0; k < leaves_.size(); ++k) leaf_numbers_[k] = leaves_[k].number;
  for (ExprAtom& e : exprs_) {
    bool ready = true;
    for (int k : e.leaves) ready = ready && leaves_[static_cast<size_t>(k)].seen;
    if (!ready) {
      e.holds = false;
      e.margin = -kInf;
      continue;
    }
    const double l = e.lhs.eval(leaf_numbers_.data(), stack_), r = e.rhs.eval(leaf_numbers_.data(), stack_);
    e.holds = !std::isnan(l) && !std::isnan(r) && compare(e.op, l, r);
    double m;
    switch (e.op) {
      case FOp::Lt:
      case FOp::Le: m = r - l; break;
      case FOp::Gt:
      case FOp::Ge: m = l - r; break;
      case FOp::Eq: m = -std::fabs(l - r); break;
      default: m = std::fabs(l - r); break;  // !=
    }
    // An undefined value (NaN: 0/0, inf - inf) holds nothing; a margin that is
    // NaN while both sides are numbers (inf <= inf) is +inf or -inf with the verdict.
    if (std::isnan(l) || std::isnan(r)) m = -kInf;
    else if (std::isnan(m)) m = e.holds ? kInf : -kInf;
    e.margin = m;
  }
}

double TimedAtoms::next_change() const {
  if (!dense_) return kInf;
  double next = kInf;
  for (const Atom& a : atoms_) {
    if (a.kind != Kind::Age || !inputs_[a.input].any) continue;
    // Computed as holds() compares, so stepping to it changes the value.
    const double at = inputs_[a.input].last + a.bound;
    if (at > now_ && at < next) next = at;
  }
  for (const auto& w : windows_) next = std::min(next, w.next_change(now_));
  return next;
}

double TimedAtoms::measure(const Atom& a) const {
  const InputState& in = inputs_[a.input];
  switch (a.kind) {
    case Kind::Age: return in.any ? now_ - in.last : kInf;
    case Kind::Latency: return in.any ? in.latency : std::numeric_limits<double>::quiet_NaN();
    case Kind::Aggregate: return windows_[static_cast<size_t>(a.window)].value();
    default: return 0;
  }
}

bool TimedAtoms::holds(const Atom& a) const {
  const InputState& in = inputs_[a.input];
  if (a.kind == Kind::Arrived) return in.any && in.arrived_at == now_;
  if (a.kind == Kind::Age && dense_) {
    // Right-continuous: the value just after now, which holds over [now, next
    // change). The age passes its bound at last + bound: compare with that
    // instant, as next_change() gives it, not with now - last (rounding).
    if (!in.any) return compare(a.op, kInf, a.bound);
    const double at = in.last + a.bound;
    switch (a.op) {
      case FOp::Lt:
      case FOp::Le: return now_ < at;
      case FOp::Gt:
      case FOp::Ge: return now_ >= at;
      case FOp::Eq: return false;  // one instant, never a stretch of time
      default: return true;        // !=
    }
  }
  return compare(a.op, measure(a), a.bound);
}

std::string TimedAtoms::describe(int atom_id) const {
  std::string out;
  for (const ExprAtom& e : exprs_) {
    if (e.id != atom_id) continue;
    for (int k : e.leaves) {
      const Leaf& l = leaves_[static_cast<size_t>(k)];
      out += (out.empty() ? "" : ", ") + l.key;
      if (!l.seen) {
        out += ": no number yet";
        continue;
      }
      char buf[32];
      const auto r = std::to_chars(buf, buf + sizeof buf, l.number);
      out += " = " + std::string(buf, r.ptr);
    }
  }
  return out;
}

void TimedAtoms::write(uint8_t* values) const {
  for (const Atom& a : atoms_) values[a.id] = holds(a) ? 1 : 0;
  for (const ExprAtom& e : exprs_) values[e.id] = e.holds ? 1 : 0;
}

void TimedAtoms::write_margins(double* margins) const {
  for (const Atom& a : atoms_) {
    if (a.kind == Kind::Arrived) margins[a.id] = holds(a) ? 1 : 0;  // a Boolean field's margin
    else if (dense_ && (a.kind == Kind::Age || a.kind == Kind::Latency))
      margins[a.id] = margin(a.op, measure(a), a.bound) / 1e9;  // margins in seconds, as the spec wrote them
    else margins[a.id] = margin(a.op, measure(a), a.bound);
  }
  for (const ExprAtom& e : exprs_) margins[e.id] = e.margin;
}

}  // namespace rvc::engine::timed
