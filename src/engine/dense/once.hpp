// Dense-time once[a:b] φ: true at t when φ held at some s with t - s in [a, b].
//
// Signals are piecewise constant on right-open pieces (values hold until the
// next message, as in Reelay). A piece [x, y) where φ holds makes once true on
// [x+a, y+b); the queue keeps these shifted pieces merged, so each event costs
// O(1) amortized plus the changes it outputs, whatever a and b are.
#pragma once

#include "engine/dense/lookahead.hpp"
#include "engine/dense/signal.hpp"
#include "engine/interval_queue.hpp"
#include "spec/ast.hpp"

namespace rvc::engine::dense {

struct Once {
  double lo = 0, hi = spec::kInfinity;
  IntervalQueue<double> window;

  void update(const Signal& input, double end, Signal& out) {
    const auto& p = input.pieces;
    for (size_t i = 0; i < p.size(); ++i) {
      double until = i + 1 < p.size() ? p[i + 1].t : end;
      if (p[i].v && p[i].t < until) window.add(p[i].t + lo, until + hi, 0);
    }
    emit(p[0].t, end, out);
  }

  // Clock-driven monitoring (lookahead.hpp), after a step that ended at
  // `now`, the operand holding `input` from there on: the value at `now`,
  // and the first time after it when the value can change.
  bool at(bool input, double now) const { return window_at(window, input, lo, now); }
  double next_change(bool input, double now) const { return window_next_change(window, input, lo, now); }

  // Writes the union of the queued intervals restricted to [begin, end).
  void emit(double begin, double end, Signal& out) {
    out.clear();
    out.set(begin, false);
    window.drop_until(begin);
    for (size_t i = 0; i < window.size(); ++i) {
      const auto& iv = window.at(i);
      if (iv.lo >= end) break;
      out.set(iv.lo > begin ? iv.lo : begin, true);
      if (iv.hi < end) out.set(iv.hi, false);
    }
    window.drop_until(end);
  }
};

}  // namespace rvc::engine::dense
