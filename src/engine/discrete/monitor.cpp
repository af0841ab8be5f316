#include "engine/discrete/monitor.hpp"

namespace rvc::engine::discrete {
namespace {
Step to_step(double v) { return v >= static_cast<double>(kForever) ? kForever : static_cast<Step>(v); }
}  // namespace

Monitor::Monitor(const Program& program) : code_(program.code), value_(program.code.size()), state_(program.code.size(), -1) {
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    Step lo = to_step(in.bounds.lo), hi = to_step(in.bounds.hi);
    switch (in.code) {
      case Code::Pre: state_[i] = static_cast<int32_t>(pre_.size()); pre_.emplace_back(); break;
      case Code::Once: state_[i] = static_cast<int32_t>(once_.size()); once_.push_back(Once{lo, hi, {}}); break;
      case Code::Historically:
        state_[i] = static_cast<int32_t>(historically_.size());
        historically_.push_back(Historically{Once{lo, hi, {}}});
        break;
      case Code::Since: state_[i] = static_cast<int32_t>(since_.size()); since_.push_back(Since{lo, hi, {}}); break;
      default: break;
    }
  }
}

bool Monitor::step(const uint8_t* atoms) {
  const size_t n = code_.size();
  uint8_t* v = value_.data();
  for (size_t i = 0; i < n; ++i) {
    const Instr& in = code_[i];
    switch (in.code) {
      case Code::True: v[i] = 1; break;
      case Code::False: v[i] = 0; break;
      case Code::Atom: v[i] = atoms[in.atom]; break;
      case Code::Not: v[i] = !v[in.a]; break;
      case Code::And: v[i] = v[in.a] & v[in.b]; break;
      case Code::Or: v[i] = v[in.a] | v[in.b]; break;
      case Code::Implies: v[i] = (!v[in.a]) | v[in.b]; break;
      case Code::Pre: v[i] = pre_[state_[i]].update(v[in.a]); break;
      case Code::Once: v[i] = once_[state_[i]].update(now_, v[in.a]); break;
      case Code::Historically: v[i] = historically_[state_[i]].update(now_, v[in.a]); break;
      case Code::Since: v[i] = since_[state_[i]].update(now_, v[in.a], v[in.b]); break;
    }
  }
  ++now_;
  return v[n - 1];
}

}  // namespace rvc::engine::discrete
