#include "engine/robust/monitor.hpp"

#include <algorithm>
#include <limits>

namespace rvc::engine::robust {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Step to_step(double v) { return v >= static_cast<double>(kForever) ? kForever : static_cast<Step>(v); }

}  // namespace

Monitor::Monitor(const Program& program) : program_(program) {
  const size_t n = program_.code.size();
  value_.assign(n, 0);
  previous_.assign(n, -std::numeric_limits<double>::max());  // Reelay's pre before the first step
  state_.assign(n, -1);
  for (size_t i = 0; i < n; ++i) {
    const Instr& in = program_.code[i];
    const Step lo = to_step(in.bounds.lo), hi = to_step(in.bounds.hi);
    switch (in.code) {
      case Code::Once: state_[i] = static_cast<int32_t>(once_.size()); once_.emplace_back(lo, hi, in.bounds.explicit_bounds); break;
      case Code::Historically:
        state_[i] = static_cast<int32_t>(historically_.size());
        historically_.emplace_back(lo, hi, in.bounds.explicit_bounds);
        break;
      case Code::Since:  // no candidate yet: -inf (Reelay's since, unlike its once, starts there)
        state_[i] = static_cast<int32_t>(since_.size());
        since_.push_back(-kInf);
        // Written bounds [lo:hi]: also the minimum of that value over the
        // steps 0..lo back and the maximum of ψ over the steps lo..hi back.
        bounded_of_.push_back(in.bounds.explicit_bounds ? static_cast<int32_t>(bounded_since_.size()) : -1);
        if (in.bounds.explicit_bounds) bounded_since_.emplace_back(lo, hi);
        break;
      default: break;
    }
  }
}

double Monitor::step(const double* margins) {
  const size_t n = program_.code.size();
  for (size_t i = 0; i < n; ++i) {
    const Instr& in = program_.code[i];
    const double a = in.a >= 0 ? value_[in.a] : 0, b = in.b >= 0 ? value_[in.b] : 0;
    double r = 0;
    switch (in.code) {
      case Code::True: r = kInf; break;
      case Code::False: r = -kInf; break;
      case Code::Atom: r = margins[in.atom]; break;
      case Code::Not: r = -a; break;
      case Code::And: r = std::min(a, b); break;
      case Code::Or: r = std::max(a, b); break;
      case Code::Implies: r = std::max(-a, b); break;
      case Code::Pre:
        r = previous_[i];
        previous_[i] = a;
        break;
      case Code::Once: r = once_[state_[i]].update(now_, a); break;
      case Code::Historically: r = historically_[state_[i]].update(now_, a); break;
      case Code::Since: {
        double& held = since_[state_[i]];
        held = std::max(b, std::min(a, held));
        r = held;
        if (const int32_t k = bounded_of_[state_[i]]; k >= 0) {
          BoundedSince& bounded = bounded_since_[k];
          r = std::min(bounded.hold.update(now_, held), bounded.window.update(now_, b));
        }
        break;
      }
      case Code::Bind:  // refused by the Checker: no robustness for data references
      case Code::Exists:
      case Code::Forall: break;
    }
    value_[i] = r;
  }
  ++now_;
  return value_[n - 1];
}

}  // namespace rvc::engine::robust
