// A signal restricted to the current segment [begin, end): the list of
// (time, value) pieces, each holding until the next piece or `end`. The first
// piece starts at `begin`; consecutive pieces differ in value (normalized).
// Boolean signals carry verdicts; real-valued ones (robust/dense_monitor)
// carry robustness. Each node of a dense monitor owns one and reuses its
// capacity every event.
#pragma once

#include <cstddef>
#include <vector>

namespace rvc::engine::dense {

template <class V>
struct BasicPiece {
  double t;
  V v;
};

template <class V>
struct BasicSignal {
  std::vector<BasicPiece<V>> pieces;

  void clear() { pieces.clear(); }
  // Appends a change at t (t >= last piece's time), keeping the list normalized.
  void set(double t, V v) {
    if (!pieces.empty()) {
      BasicPiece<V>& last = pieces.back();
      if (last.v == v) return;
      if (last.t == t) {  // replaces a piece of zero length
        pieces.pop_back();
        if (!pieces.empty() && pieces.back().v == v) return;
      }
    }
    pieces.push_back({t, v});
  }
  void constant(double begin, V v) {
    pieces.clear();
    pieces.push_back({begin, v});
  }
};

using Piece = BasicPiece<bool>;
using Signal = BasicSignal<bool>;

// The signal's value at time t of its segment (--explain reads sub-formulas so).
inline bool value_at(const Signal& s, double t) {
  bool v = !s.pieces.empty() && s.pieces.front().v;
  for (const Piece& p : s.pieces) {
    if (p.t > t) break;
    v = p.v;
  }
  return v;
}

// Walks the pieces of two signals over the same segment in time order, calling
// f(t, left_value, right_value) at each point where either changes.
template <class V, class F>
void zip(const BasicSignal<V>& a, const BasicSignal<V>& b, F&& f) {
  std::size_t i = 1, j = 1;
  V va = a.pieces[0].v, vb = b.pieces[0].v;
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

}  // namespace rvc::engine::dense
