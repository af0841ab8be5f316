#include "engine/discrete/monitor.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace rvc::engine::discrete {
namespace {
Step to_step(double v) { return v >= static_cast<double>(kForever) ? kForever : static_cast<Step>(v); }
}  // namespace

Monitor::Monitor(const Program& program) {
  for (const Instr& in : program.code)
    if (in.code == Code::Atom) atom_count_ = std::max<size_t>(atom_count_, static_cast<size_t>(in.atom) + 1);
  const size_t zero = atom_count_, one = atom_count_ + 1;
  size_t slots = atom_count_ + 2;
  if (slots + program.code.size() > 65535) throw std::length_error("property too large (more than 65000 nodes)");
  std::vector<Operand> operand(program.code.size());
  for (size_t i = 0; i < program.code.size(); ++i) {
    const Instr& in = program.code[i];
    switch (in.code) {
      case Code::True: operand[i] = {static_cast<uint16_t>(one), 0}; continue;
      case Code::False: operand[i] = {static_cast<uint16_t>(zero), 0}; continue;
      case Code::Atom: operand[i] = {static_cast<uint16_t>(in.atom), 0}; continue;
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
  value_.assign(slots, 0);
  value_[one] = 1;
}

bool Monitor::step(const uint8_t* atoms) {
  uint8_t* v = value_.data();
  std::memcpy(v, atoms, atom_count_);
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

}  // namespace rvc::engine::discrete
