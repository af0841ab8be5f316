// A real-valued signal over the current segment [begin, end) of dense time:
// the robustness counterpart of dense::Signal. Pieces (t, value) hold until
// the next piece or `end`; consecutive pieces differ (normalized).
#pragma once

#include <cstddef>
#include <vector>

namespace rvc::engine::robust {

struct RealPiece {
  double t;
  double v;
};

struct RealSignal {
  std::vector<RealPiece> pieces;

  void clear() { pieces.clear(); }
  // Appends a change at t (t >= the last piece's time).
  void set(double t, double v) {
    if (!pieces.empty()) {
      RealPiece& last = pieces.back();
      if (last.v == v) return;
      if (last.t == t) {  // replaces a piece of zero length
        pieces.pop_back();
        if (!pieces.empty() && pieces.back().v == v) return;
      }
    }
    pieces.push_back({t, v});
  }
  void constant(double begin, double v) {
    pieces.clear();
    pieces.push_back({begin, v});
  }
};

// f(t, left, right) at every point where either signal changes, in time order.
template <class F>
void zip(const RealSignal& a, const RealSignal& b, F&& f) {
  size_t i = 1, j = 1;
  double va = a.pieces[0].v, vb = b.pieces[0].v;
  f(a.pieces[0].t, va, vb);
  while (i < a.pieces.size() || j < b.pieces.size()) {
    const bool take_a = j >= b.pieces.size() || (i < a.pieces.size() && a.pieces[i].t <= b.pieces[j].t);
    const bool take_b = i >= a.pieces.size() || (j < b.pieces.size() && b.pieces[j].t <= a.pieces[i].t);
    const double t = take_a ? a.pieces[i].t : b.pieces[j].t;
    if (take_a) va = a.pieces[i++].v;
    if (take_b) vb = b.pieces[j++].v;
    f(t, va, vb);
  }
}

}  // namespace rvc::engine::robust
