// Discrete-time robustness monitor of one property (`rvc check --robustness`):
// how far each step is from changing the verdict, with Reelay's quantitative
// semantics. Atoms give a margin ({x > 3}: x - 3, {x < 3}: 3 - x, {x == 3}:
// -|x - 3|, a Boolean field: 1 or 0, a string test: +inf or -inf); `not`
// negates, `and`/`or` take the minimum/maximum, `once` and `historically`
// the maximum/minimum over their window, `since` the maximum over the
// candidate steps of the minimum along the way. A positive value means the
// property holds with that margin; a negative one, that it is violated by it.
//
// `φ since[lo:hi] ψ` is Reelay's rewriting (Donzé, Ferrère, Maler, "Efficient
// robust monitoring for STL"): min(historically[0:lo](φ since ψ),
// once[lo:hi] ψ). It is what Reelay computes, and it is at least the
// textbook max over s in [t-hi, t-lo] of min(ψ(s), φ over (s, t]): the
// since value at t-lo..t may come from a ψ later than t-lo. Both parts are
// robust windows (window.hpp): O(1) amortized per step whatever lo and hi.
// Reelay 25's discrete since[lo:] (no upper bound) gives other values: it
// drops its once[lo:] ψ part to -inf every few steps (on a constant trace it
// alternates between ψ and -inf), which its own rewriting written out and its
// dense time do not do; rvc gives the rewriting's value there too.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/program.hpp"
#include "engine/robust/window.hpp"

namespace rvc::engine::robust {

class Monitor {
 public:
  explicit Monitor(const Program& program);
  // One step with the atoms' margins (indexed by the shared atom table).
  double step(const double* margins);

 private:
  struct BoundedSince {
    BoundedSince(Step lo, Step hi) : hold(0, lo, true), window(lo, hi, true) {}
    Window<false> hold;   // historically[0:lo] of the unbounded since value
    Window<true> window;  // once[lo:hi] of ψ: -inf until step lo
  };
  const Program program_;
  std::vector<double> value_;        // per instruction, this step
  std::vector<double> previous_;     // Pre: the operand's value at the previous step
  std::vector<int32_t> state_;       // per instruction: index into its operator's state
  std::vector<Window<true>> once_;
  std::vector<Window<false>> historically_;
  std::vector<double> since_;        // since: the unbounded value at the previous step
  std::vector<int32_t> bounded_of_;  // per since: index into bounded_since_, -1 without written bounds
  std::vector<BoundedSince> bounded_since_;
  Step now_ = 0;
};

}  // namespace rvc::engine::robust
