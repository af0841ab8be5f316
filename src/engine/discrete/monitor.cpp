#include "engine/discrete/monitor.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

namespace rvc::engine::discrete {
namespace {
Step to_step(double v) { return v >= static_cast<double>(kForever) ? kForever : static_cast<Step>(v); }
constexpr size_t kMaxSlots = 65535;
}  // namespace

Monitor::Kind Monitor::kind_of(const Instr& in) {
  const bool all = to_step(in.bounds.lo) == 0 && to_step(in.bounds.hi) >= kForever;  // [0, inf): the whole past
  switch (in.code) {
    case Code::And: return Kind::And;
    case Code::Or: return Kind::Or;
    case Code::Implies: return Kind::Implies;
    case Code::Pre: return Kind::Pre;
    case Code::Once: return all ? Kind::OnceAll : Kind::Once;
    case Code::Historically: return all ? Kind::HistoricallyAll : Kind::Historically;
    case Code::Since: return all ? Kind::SinceAll : Kind::Since;
    default: throw std::logic_error("discrete::Monitor: not an operator");  // leaves, negations, references
  }
}

Monitor::Monitor() : value_{0, 1} {}  // slot 0: false, slot 1: true

bool Monitor::add(const Program& program) {
  if (now_ > 0) throw std::logic_error("discrete::Monitor::add after the first step");
  // At most one new slot per instruction.
  if (value_.size() + program.code.size() > kMaxSlots) {
    if (properties_.empty()) throw std::length_error("property too large (more than 65000 nodes)");
    return false;
  }
  Property p;
  p.program = program;
  p.operand.resize(program.code.size());
  for (size_t i = 0; i < program.code.size(); ++i) {
    const Instr& in = program.code[i];
    switch (in.code) {
      case Code::True: p.operand[i] = {1, 0}; continue;
      case Code::False: p.operand[i] = {0, 0}; continue;
      case Code::Atom: {
        auto [it, added] = atom_slot_of_.try_emplace(static_cast<uint32_t>(in.atom), static_cast<uint16_t>(value_.size()));
        if (added) {
          value_.push_back(0);
          atom_ids_.push_back(static_cast<uint32_t>(in.atom));
          atom_slots_.push_back(it->second);
        }
        p.operand[i] = {it->second, 0};
        continue;
      }
      case Code::Not: p.operand[i] = {p.operand[in.a].slot, static_cast<uint8_t>(!p.operand[in.a].negate)}; continue;
      default: break;
    }
    const Operand a = p.operand[in.a];
    const Operand b = in.b >= 0 ? p.operand[in.b] : Operand{};
    const Key key{in.code, a.slot, a.negate, b.slot, b.negate, in.bounds.lo, in.bounds.hi};
    if (auto found = shared_.find(key); found != shared_.end()) {  // the same sub-formula: one operator
      p.operand[i] = {found->second, 0};
      continue;
    }
    Op op{kind_of(in)};
    op.a = a.slot;
    op.negate_a = a.negate;
    op.b = b.slot;
    op.negate_b = b.negate;
    op.out = static_cast<uint16_t>(value_.size());
    // A latch reads its own slot before writing it: historically starts true
    // (nothing has failed yet), the others false. No other operator reads the
    // slot before this one writes it in the same step.
    value_.push_back(op.kind == Kind::HistoricallyAll ? 1 : 0);
    const Step lo = to_step(in.bounds.lo), hi = to_step(in.bounds.hi);
    switch (op.kind) {
      case Kind::Pre: op.slot = static_cast<uint16_t>(pre_.size()); pre_.emplace_back(); break;
      case Kind::Once: op.slot = static_cast<uint16_t>(once_.size()); once_.push_back(Once{lo, hi, {}}); break;
      case Kind::Historically:
        op.slot = static_cast<uint16_t>(historically_.size());
        historically_.push_back(Historically{Once{lo, hi, {}}});
        break;
      case Kind::Since: op.slot = static_cast<uint16_t>(since_.size()); since_.push_back(Since{lo, hi, {}}); break;
      default: break;  // the Boolean connectives and the latches keep no state but their slot
    }
    ops_.push_back(op);
    shared_.emplace(key, op.out);
    p.operand[i] = {op.out, 0};
  }
  p.root = p.operand.back();
  properties_.push_back(std::move(p));
  return true;
}

void Monitor::step(const uint8_t* atoms) {
  uint8_t* v = value_.data();
  for (size_t k = 0, n = atom_ids_.size(); k < n; ++k) v[atom_slots_[k]] = atoms[atom_ids_[k]];
  const Step now = now_;
  // Locals, not members: stores through uint8_t* may alias anything, which
  // would make the compiler reload every member pointer after each node.
  Pre* pre = pre_.data();
  Once* once = once_.data();
  Historically* historically = historically_.data();
  Since* since = since_.data();
  for (const Op *op = ops_.data(), *end = op + ops_.size(); op != end; ++op) {
    const uint8_t a = v[op->a] ^ op->negate_a;
    const uint8_t b = v[op->b] ^ op->negate_b;
    const uint8_t last = v[op->out];  // this operator's output at the previous step
    uint8_t r = 0;  // every Kind sets it; the compiler cannot tell the switch is exhaustive
    switch (op->kind) {
      case Kind::And: r = a & b; break;
      case Kind::Or: r = a | b; break;
      case Kind::Implies: r = (a ^ 1) | b; break;
      case Kind::Pre: r = pre[op->slot].update(a); break;
      case Kind::Once: r = once[op->slot].update(now, a); break;
      case Kind::OnceAll: r = last | a; break;
      case Kind::Historically: r = historically[op->slot].update(now, a); break;
      case Kind::HistoricallyAll: r = last & a; break;
      case Kind::Since: r = since[op->slot].update(now, a, b); break;
      case Kind::SinceAll: r = b | (a & last); break;
    }
    v[op->out] = r;
  }
  now_ = now + 1;
}

namespace {

// "at step 4", "at steps 0..4": the steps an operator's bounds look at now.
std::string range_text(Step now, const spec::Bounds& b) {
  const Step from = b.hi >= static_cast<double>(kForever) ? 0 : std::max<Step>(0, now - static_cast<Step>(b.hi));
  const Step to = now - static_cast<Step>(b.lo);
  if (to < from) return "at no step yet";
  return from == to ? "at step " + std::to_string(from) : "at steps " + std::to_string(from) + ".." + std::to_string(to);
}

const char* word(bool v) { return v ? "true" : "false"; }

}  // namespace

// One sentence per sub-formula on the way from the root to the atoms (or to
// a temporal operator, whose reason lies in earlier steps): only the
// operands that decide the value are followed.
void Monitor::why(const Property& p, size_t i, Step at, std::vector<std::string>& out) const {
  if (out.size() >= 16) return;  // a wide formula: the first reasons are enough
  const Instr& in = p.program.code[i];
  const std::string& text = p.program.text[i];
  const bool v = read(p.operand[i]);
  const size_t a = static_cast<size_t>(in.a), b = static_cast<size_t>(in.b);
  switch (in.code) {
    case Code::Atom: out.push_back(text + " is " + word(v) + " at step " + std::to_string(at)); return;
    case Code::True:
    case Code::False:
    case Code::Bind:  // data references run in data::DiscreteMonitor, never here
    case Code::Exists:
    case Code::Forall: return;
    case Code::Not: why(p, a, at, out); return;
    case Code::And:
      if (v) {
        why(p, a, at, out);
        why(p, b, at, out);
      } else {
        why(p, !read(p.operand[a]) ? a : b, at, out);
      }
      return;
    case Code::Or:
      if (v) {
        why(p, read(p.operand[a]) ? a : b, at, out);
      } else {
        why(p, a, at, out);
        why(p, b, at, out);
      }
      return;
    case Code::Implies:
      if (v) {
        why(p, !read(p.operand[a]) ? a : b, at, out);
      } else {
        why(p, a, at, out);
        why(p, b, at, out);
      }
      return;
    case Code::Pre:
      out.push_back(text + " is " + word(v) + (at == 0 ? ": there is no previous step"
                                                      : ": " + p.program.text[a] + " was " + word(v) + " at step " +
                                                            std::to_string(at - 1)));
      return;
    case Code::Once:
      out.push_back(text + " is " + word(v) + ": " + p.program.text[a] + (v ? " held at least once " : " never held ") +
                    range_text(at, in.bounds));
      if (!v && in.bounds.lo == 0) why(p, a, at, out);
      return;
    case Code::Historically:
      out.push_back(text + " is " + word(v) + ": " + p.program.text[a] +
                    (v ? " held every time " : " failed at least once ") + range_text(at, in.bounds));
      if (!v && in.bounds.lo == 0 && !read(p.operand[a])) why(p, a, at, out);  // failing now: the step that broke it
      return;
    case Code::Since:
      out.push_back(text + " is " + word(v) + ": " + p.program.text[b] +
                    (v ? " held " + range_text(at, in.bounds) + " and " + p.program.text[a] + " at every step after"
                       : " never held " + range_text(at, in.bounds) + " with " + p.program.text[a] +
                             " holding at every step after"));
      if (!v && !read(p.operand[a])) why(p, a, at, out);  // the left side failing now ended it
      return;
  }
}

std::vector<std::string> Monitor::explain(size_t k) const {
  std::vector<std::string> out;
  const Property& p = properties_[k];
  if (!p.program.code.empty()) why(p, p.program.code.size() - 1, now_ - 1, out);
  return out;
}

}  // namespace rvc::engine::discrete
