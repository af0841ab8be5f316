#include "engine/discrete/monitor.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>

namespace rvc::engine::discrete {
namespace {
Step to_step(double v) { return v >= static_cast<double>(kForever) ? kForever : static_cast<Step>(v); }
}  // namespace

Monitor::Monitor(const Program& program) : program_(program) {
  // Local slots for the atoms this property reads (the shared table may hold
  // many more, from other properties).
  std::vector<int32_t> local(program.code.size(), -1);
  for (size_t i = 0; i < program.code.size(); ++i) {
    const Instr& in = program.code[i];
    if (in.code != Code::Atom) continue;
    auto found = std::find(atoms_.begin(), atoms_.end(), static_cast<uint32_t>(in.atom));
    local[i] = static_cast<int32_t>(found - atoms_.begin());
    if (found == atoms_.end()) atoms_.push_back(static_cast<uint32_t>(in.atom));
  }
  const size_t zero = atoms_.size(), one = atoms_.size() + 1;
  size_t slots = atoms_.size() + 2;
  if (slots + program.code.size() > 65535) throw std::length_error("property too large (more than 65000 nodes)");
  std::vector<Operand> operand(program.code.size());
  for (size_t i = 0; i < program.code.size(); ++i) {
    const Instr& in = program.code[i];
    switch (in.code) {
      case Code::True: operand[i] = {static_cast<uint16_t>(one), 0}; continue;
      case Code::False: operand[i] = {static_cast<uint16_t>(zero), 0}; continue;
      case Code::Atom: operand[i] = {static_cast<uint16_t>(local[i]), 0}; continue;
      case Code::Not: operand[i] = {operand[in.a].slot, static_cast<uint8_t>(!operand[in.a].negate)}; continue;
      default: break;
    }
    Op op{in.code};
    op.a = operand[in.a].slot;
    op.negate_a = operand[in.a].negate;
    if (in.b >= 0) {
      op.b = operand[in.b].slot;
      op.negate_b = operand[in.b].negate;
    }
    op.out = static_cast<uint16_t>(slots++);
    Step lo = to_step(in.bounds.lo), hi = to_step(in.bounds.hi);
    switch (in.code) {
      case Code::Pre: op.slot = static_cast<uint16_t>(pre_.size()); pre_.emplace_back(); break;
      case Code::Once: op.slot = static_cast<uint16_t>(once_.size()); once_.push_back(Once{lo, hi, {}}); break;
      case Code::Historically:
        op.slot = static_cast<uint16_t>(historically_.size());
        historically_.push_back(Historically{Once{lo, hi, {}}});
        break;
      case Code::Since: op.slot = static_cast<uint16_t>(since_.size()); since_.push_back(Since{lo, hi, {}}); break;
      default: break;
    }
    ops_.push_back(op);
    operand[i] = {op.out, 0};
  }
  root_ = operand.back();
  operand_ = std::move(operand);
  value_.assign(slots, 0);
  value_[one] = 1;
}

bool Monitor::step(const uint8_t* atoms) {
  uint8_t* v = value_.data();
  const uint32_t* ids = atoms_.data();
  for (size_t k = 0, n = atoms_.size(); k < n; ++k) v[k] = atoms[ids[k]];
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
    uint8_t r;
    switch (op->code) {
      case Code::And: r = a & b; break;
      case Code::Or: r = a | b; break;
      case Code::Implies: r = (a ^ 1) | b; break;
      case Code::Pre: r = pre[op->slot].update(a); break;
      case Code::Once: r = once[op->slot].update(now, a); break;
      case Code::Historically: r = historically[op->slot].update(now, a); break;
      case Code::Since: r = since[op->slot].update(now, a, b); break;
      default: r = 0; break;  // leaves and negations never become operators
    }
    v[op->out] = r;
  }
  now_ = now + 1;
  return v[root_.slot] ^ root_.negate;
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
void Monitor::why(size_t i, Step at, std::vector<std::string>& out) const {
  if (out.size() >= 16) return;  // a wide formula: the first reasons are enough
  const Instr& in = program_.code[i];
  const std::string& text = program_.text[i];
  const bool v = value_of(i);
  const size_t a = static_cast<size_t>(in.a), b = static_cast<size_t>(in.b);
  switch (in.code) {
    case Code::Atom: out.push_back(text + " is " + word(v) + " at step " + std::to_string(at)); return;
    case Code::True:
    case Code::False: return;
    case Code::Not: why(a, at, out); return;
    case Code::And:
      if (v) {
        why(a, at, out);
        why(b, at, out);
      } else {
        why(!value_of(a) ? a : b, at, out);
      }
      return;
    case Code::Or:
      if (v) {
        why(value_of(a) ? a : b, at, out);
      } else {
        why(a, at, out);
        why(b, at, out);
      }
      return;
    case Code::Implies:
      if (v) {
        why(!value_of(a) ? a : b, at, out);
      } else {
        why(a, at, out);
        why(b, at, out);
      }
      return;
    case Code::Pre:
      out.push_back(text + " is " + word(v) + (at == 0 ? ": there is no previous step"
                                                      : ": " + program_.text[a] + " was " + word(v) + " at step " +
                                                            std::to_string(at - 1)));
      return;
    case Code::Once:
      out.push_back(text + " is " + word(v) + ": " + program_.text[a] + (v ? " held at least once " : " never held ") +
                    range_text(at, in.bounds));
      if (!v && in.bounds.lo == 0) why(a, at, out);
      return;
    case Code::Historically:
      out.push_back(text + " is " + word(v) + ": " + program_.text[a] +
                    (v ? " held every time " : " failed at least once ") + range_text(at, in.bounds));
      if (!v && in.bounds.lo == 0 && !value_of(a)) why(a, at, out);  // failing now: the step that broke it
      return;
    case Code::Since:
      out.push_back(text + " is " + word(v) + ": " + program_.text[b] +
                    (v ? " held " + range_text(at, in.bounds) + " and " + program_.text[a] + " at every step after"
                       : " never held " + range_text(at, in.bounds) + " with " + program_.text[a] +
                             " holding at every step after"));
      if (!v && !value_of(a)) why(a, at, out);  // the left side failing now ended it
      return;
  }
}

std::vector<std::string> Monitor::explain() const {
  std::vector<std::string> out;
  if (!program_.code.empty()) why(program_.code.size() - 1, now_ - 1, out);
  return out;
}

}  // namespace rvc::engine::discrete
