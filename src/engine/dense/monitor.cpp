#include "engine/dense/monitor.hpp"

namespace rvc::engine::dense {

Monitor::Monitor(const Program& program) : code_(program.code), signal_(program.code.size()), state_(program.code.size(), -1) {
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    double lo = in.bounds.lo, hi = in.bounds.hi;
    switch (in.code) {
      case Code::Once: state_[i] = static_cast<int32_t>(once_.size()); once_.push_back(Once{lo, hi, {}}); break;
      case Code::Historically: {
        state_[i] = static_cast<int32_t>(historically_.size());
        Historically h;
        h.violations.lo = lo;
        h.violations.hi = hi;
        historically_.push_back(std::move(h));
        break;
      }
      case Code::Since: {
        state_[i] = static_cast<int32_t>(since_.size());
        Since s;
        s.lo = lo;
        s.hi = hi;
        since_.push_back(std::move(s));
        break;
      }
      default: break;
    }
  }
}

const Signal& Monitor::step(double begin, double end, const uint8_t* atoms) {
  const size_t n = code_.size();
  for (size_t i = 0; i < n; ++i) {
    const Instr& in = code_[i];
    Signal& out = signal_[i];
    switch (in.code) {
      case Code::True: out.constant(begin, true); break;
      case Code::False: out.constant(begin, false); break;
      case Code::Atom: out.constant(begin, atoms[in.atom] != 0); break;
      case Code::Not:
        out.clear();
        for (const Piece& p : signal_[in.a].pieces) out.set(p.t, !p.v);
        break;
      case Code::And:
        out.clear();
        zip(signal_[in.a], signal_[in.b], [&](double t, bool l, bool r) { out.set(t, l && r); });
        break;
      case Code::Or:
        out.clear();
        zip(signal_[in.a], signal_[in.b], [&](double t, bool l, bool r) { out.set(t, l || r); });
        break;
      case Code::Implies:
        out.clear();
        zip(signal_[in.a], signal_[in.b], [&](double t, bool l, bool r) { out.set(t, !l || r); });
        break;
      case Code::Pre: out.constant(begin, false); break;  // rejected by the compiler for dense time
      case Code::Once: once_[state_[i]].update(signal_[in.a], end, out); break;
      case Code::Historically: historically_[state_[i]].update(signal_[in.a], end, out); break;
      case Code::Since: since_[state_[i]].update(signal_[in.a], signal_[in.b], end, out); break;
      case Code::Bind:  // data references run in data::DenseMonitor, never here
      case Code::Exists:
      case Code::Forall: out.constant(begin, false); break;
    }
  }
  return signal_[n - 1];
}

}  // namespace rvc::engine::dense
