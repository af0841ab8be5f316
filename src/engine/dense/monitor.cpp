#include "engine/dense/monitor.hpp"

#include "engine/explain.hpp"

namespace rvc::engine::dense {

Monitor::Monitor(const Program& program) : program_(program), code_(program.code), signal_(program.code.size()), state_(program.code.size(), -1) {
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
  begin_ = begin;
  end_ = end;
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

bool Monitor::at(double now, const uint8_t* atoms) {
  const size_t n = code_.size();
  at_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Instr& in = code_[i];
    const bool a = in.a >= 0 && at_[static_cast<size_t>(in.a)];
    const bool b = in.b >= 0 && at_[static_cast<size_t>(in.b)];
    bool v = false;
    switch (in.code) {
      case Code::True: v = true; break;
      case Code::Atom: v = atoms[in.atom] != 0; break;
      case Code::Not: v = !a; break;
      case Code::And: v = a && b; break;
      case Code::Or: v = a || b; break;
      case Code::Implies: v = !a || b; break;
      case Code::Once: v = once_[state_[i]].at(a, now); break;
      case Code::Historically: v = historically_[state_[i]].at(a, now); break;
      case Code::Since: v = since_[state_[i]].at(a, b, now); break;
      default: break;  // False, Pre, Bind, Exists, Forall: false, as step() has them
    }
    at_[i] = v;
  }
  return at_[n - 1] != 0;
}

double Monitor::next_change(double now) const {
  double next = kNever;
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    const bool a = in.a >= 0 && at_[static_cast<size_t>(in.a)];
    const bool b = in.b >= 0 && at_[static_cast<size_t>(in.b)];
    double t = kNever;
    switch (in.code) {
      case Code::Once: t = once_[state_[i]].next_change(a, now); break;
      case Code::Historically: t = historically_[state_[i]].next_change(a, now); break;
      case Code::Since: t = since_[state_[i]].next_change(a, b, now); break;
      default: break;  // the others change only when their operands do
    }
    if (t < next) next = t;
  }
  return next;
}

namespace {

// Each sub-formula's value at the clock (Monitor::at), the atoms held.
class ClockWalker : public explain::Walker {
 public:
  ClockWalker(const Program& program, const std::vector<uint8_t>& at, double now)
      : Walker(program, true, now), at_(at), now_(now) {}

 protected:
  bool value(size_t i) const override { return at_[i] != 0; }
  std::string held(size_t) const override { return "at time " + explain::seconds(now_) + " (held since the last message)"; }

 private:
  const std::vector<uint8_t>& at_;
  double now_;
};

// Each sub-formula's value at time t: read from its signal over the segment.
class DenseWalker : public explain::Walker {
 public:
  DenseWalker(const Program& program, const std::vector<Signal>& signal, double t, double begin, double end)
      : Walker(program, true, t), signal_(signal), t_(t), begin_(begin), end_(end) {}

 protected:
  bool value(size_t i) const override { return value_at(signal_[i], t_); }
  std::string held(size_t) const override {  // an atom holds its message's value over the whole segment
    return "throughout [" + explain::seconds(begin_) + ", " + explain::seconds(end_) + ")";
  }

 private:
  const std::vector<Signal>& signal_;
  double t_, begin_, end_;
};

}  // namespace

std::vector<std::string> Monitor::explain(double t) const { return DenseWalker(program_, signal_, t, begin_, end_).run(); }

std::vector<std::string> Monitor::explain_at(double now) const { return ClockWalker(program_, at_, now).run(); }

}  // namespace rvc::engine::dense
