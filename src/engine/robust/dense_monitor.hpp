// Dense-time robustness monitor of one property (`--robustness --dense`):
// the discrete robustness monitor's semantics over real-valued signals that
// hold from one message to the next. Atoms hold their margin over the
// segment; not, and, or, implies are pointwise; once and historically take
// the maximum / minimum over their window (dense_window.hpp).
//
// `φ since ψ` over each stretch where both operands are constant, in time
// order: max(ψ, min(φ, the value before)), from -inf (repeating it over a
// piece changes nothing, so where pieces are cut does not matter). With
// written bounds, as in discrete time and as Reelay does: the minimum of
// that value over [t-lo, t] and the maximum of ψ over [t-hi, t-lo], two
// windows with the same contributions as historically[0:lo] and
// once[lo:hi]: O(1) amortized per piece whatever the bounds.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/program.hpp"
#include "engine/robust/dense_window.hpp"

namespace rvc::engine::robust {

class DenseMonitor {
 public:
  explicit DenseMonitor(const Program& program);
  // The atoms' margins held over [begin, end): the property's robustness over it.
  const RealSignal& step(double begin, double end, const double* margins);

  // Clock-driven monitoring (dense::Monitor::at and next_change): after a
  // step that ended at `now`, the margins held from there on, the
  // robustness at `now`; then the first time after it at which it can change.
  double at(double now, const double* margins);
  double next_change(double now) const;

 private:
  struct Since {
    double held;  // the unbounded value at the end of the last piece
    int32_t bounded = -1;  // index into bounded_, -1 without written bounds
  };
  struct BoundedSince {
    BoundedSince(double lo, double hi) : hold(0, lo, -1.0), window(lo, hi, 1.0) {}
    DenseWindow hold, window;
    RealSignal unbounded, held, windowed;  // scratch, reused every segment
  };
  void since(const Instr& in, Since& s, double end, RealSignal& out);
  // The unbounded since's value at the clock, its operands held (at_ filled).
  double since_at(const Instr& in, const Since& s) const;

  std::vector<Instr> code_;
  std::vector<RealSignal> signal_;
  std::vector<double> at_;  // at(): each sub-formula's robustness at the clock
  std::vector<int32_t> state_;
  std::vector<DenseWindow> window_;
  std::vector<Since> since_;
  std::vector<BoundedSince> bounded_;
};

}  // namespace rvc::engine::robust
