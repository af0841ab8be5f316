#include "engine/robust/dense_monitor.hpp"

#include <algorithm>
#include <limits>

namespace rvc::engine::robust {

DenseMonitor::DenseMonitor(const Program& program)
    : code_(program.code), signal_(program.code.size()), state_(program.code.size(), -1) {
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    if (in.code == Code::Since) {
      state_[i] = static_cast<int32_t>(since_.size());
      since_.push_back({-std::numeric_limits<double>::infinity()});
      if (in.bounds.explicit_bounds) {
        since_.back().bounded = static_cast<int32_t>(bounded_.size());
        bounded_.emplace_back(in.bounds.lo, in.bounds.hi);
      }
      continue;
    }
    if (in.code != Code::Once && in.code != Code::Historically) continue;
    state_[i] = static_cast<int32_t>(window_.size());
    window_.emplace_back(in.bounds.lo, in.bounds.hi, in.code == Code::Once ? 1.0 : -1.0);
  }
}

void DenseMonitor::since(const Instr& in, Since& s, double end, RealSignal& out) {
  const RealSignal& phi = signal_[static_cast<size_t>(in.a)];
  const RealSignal& psi = signal_[static_cast<size_t>(in.b)];
  RealSignal& unbounded = s.bounded < 0 ? out : bounded_[static_cast<size_t>(s.bounded)].unbounded;
  unbounded.clear();
  zip(phi, psi, [&](double t, double l, double r) {
    s.held = std::max(r, std::min(l, s.held));
    unbounded.set(t, s.held);
  });
  if (s.bounded < 0) return;
  BoundedSince& b = bounded_[static_cast<size_t>(s.bounded)];
  b.hold.update(b.unbounded, end, b.held);
  b.window.update(psi, end, b.windowed);
  out.clear();
  zip(b.held, b.windowed, [&](double t, double l, double r) { out.set(t, std::min(l, r)); });
}

const RealSignal& DenseMonitor::step(double begin, double end, const double* margins) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    RealSignal& out = signal_[i];
    const auto binary = [&](auto&& f) {
      out.clear();
      zip(signal_[static_cast<size_t>(in.a)], signal_[static_cast<size_t>(in.b)],
          [&](double t, double l, double r) { out.set(t, f(l, r)); });
    };
    switch (in.code) {
      case Code::True: out.constant(begin, kInf); break;
      case Code::False: out.constant(begin, -kInf); break;
      case Code::Atom: out.constant(begin, margins[in.atom]); break;
      case Code::Not:
        out.clear();
        for (const RealPiece& p : signal_[static_cast<size_t>(in.a)].pieces) out.set(p.t, -p.v);
        break;
      case Code::And: binary([](double l, double r) { return std::min(l, r); }); break;
      case Code::Or: binary([](double l, double r) { return std::max(l, r); }); break;
      case Code::Implies: binary([](double l, double r) { return std::max(-l, r); }); break;
      case Code::Once:
      case Code::Historically:
        window_[static_cast<size_t>(state_[i])].update(signal_[static_cast<size_t>(in.a)], end, out);
        break;
      case Code::Since: since(in, since_[static_cast<size_t>(state_[i])], end, out); break;
      case Code::Pre:  // refused by the compiler in dense time
      case Code::Bind:   // refused by the Checker
      case Code::Exists:
      case Code::Forall: out.constant(begin, -kInf); break;
    }
  }
  return signal_.back();
}

double DenseMonitor::since_at(const Instr& in, const Since& s) const {
  // Repeating max(ψ, min(φ, value before)) over a constant stretch changes nothing, so it
  // keeps this value for as long as the operands hold.
  return std::max(at_[static_cast<size_t>(in.b)], std::min(at_[static_cast<size_t>(in.a)], s.held));
}

double DenseMonitor::at(double now, const double* margins) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  at_.resize(code_.size());
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    const double a = in.a >= 0 ? at_[static_cast<size_t>(in.a)] : 0;
    const double b = in.b >= 0 ? at_[static_cast<size_t>(in.b)] : 0;
    double v = -kInf;  // False, Pre, Bind, Exists, Forall: as step() has them
    switch (in.code) {
      case Code::True: v = kInf; break;
      case Code::Atom: v = margins[in.atom]; break;
      case Code::Not: v = -a; break;
      case Code::And: v = std::min(a, b); break;
      case Code::Or: v = std::max(a, b); break;
      case Code::Implies: v = std::max(-a, b); break;
      case Code::Once:
      case Code::Historically: v = window_[static_cast<size_t>(state_[i])].at(a, now); break;
      case Code::Since: {
        const Since& s = since_[static_cast<size_t>(state_[i])];
        v = since_at(in, s);
        if (s.bounded >= 0) {
          const BoundedSince& bs = bounded_[static_cast<size_t>(s.bounded)];
          v = std::min(bs.hold.at(v, now), bs.window.at(b, now));
        }
        break;
      }
      default: break;
    }
    at_[i] = v;
  }
  return at_.back();
}

double DenseMonitor::next_change(double now) const {
  double next = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    double t = next;
    if (in.code == Code::Once || in.code == Code::Historically) {
      t = window_[static_cast<size_t>(state_[i])].next_change(at_[static_cast<size_t>(in.a)], now);
    } else if (in.code == Code::Since) {  // unbounded: constant while its operands are
      const Since& s = since_[static_cast<size_t>(state_[i])];
      if (s.bounded >= 0) {
        const BoundedSince& bs = bounded_[static_cast<size_t>(s.bounded)];
        t = std::min(bs.hold.next_change(since_at(in, s), now),
                     bs.window.next_change(at_[static_cast<size_t>(in.b)], now));
      }
    }
    next = std::min(next, t);
  }
  return next;
}

}  // namespace rvc::engine::robust
