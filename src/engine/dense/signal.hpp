// A Boolean signal restricted to the current segment [begin, end): the list of
// (time, value) pieces, each holding until the next piece or `end`. The first
// piece starts at `begin`; consecutive pieces differ in value (normalized).
// Each node of a dense monitor owns one and reuses its capacity every event.
#pragma once

#include <cstddef>
#include <vector>

namespace rvc::engine::dense {

struct Piece {
  double t;
  bool v;
};

struct Signal {
  std::vector<Piece> pieces;

  void clear() { pieces.clear(); }
  // Appends a change at t (t >= last piece's time), keeping the list normalized.
  void set(double t, bool v) {
    if (!pieces.empty()) {
      Piece& last = pieces.back();
      if (last.v == v) return;
      if (last.t == t) {  // replaces a piece of zero length
        pieces.pop_back();
        if (!pieces.empty() && pieces.back().v == v) return;
      }
    }
    pieces.push_back({t, v});
  }
  void constant(double begin, bool v) {
    pieces.clear();
    pieces.push_back({begin, v});
  }
};

// Walks the pieces of two signals over the same segment in time order, calling
// f(t, left_value, right_value) at each point where either changes.
template <class F>
void zip(const Signal& a, const Signal& b, F&& f) {
  std::size_t i = 0, j = 0;
  bool va = a.pieces[0].v, vb = b.pieces[0].v;
  double t = a.pieces[0].t;
  i = j = 1;
  f(t, va, vb);
  while (i < a.pieces.size() || j < b.pieces.size()) {
    double ta = i < a.pieces.size() ? a.pieces[i].t : 0, tb = j < b.pieces.size() ? b.pieces[j].t : 0;
    if (j >= b.pieces.size() || (i < a.pieces.size() && ta < tb)) {
      va = a.pieces[i++].v;
      t = ta;
    } else if (i >= a.pieces.size() || tb < ta) {
      vb = b.pieces[j++].v;
      t = tb;
    } else {
      va = a.pieces[i++].v;
      vb = b.pieces[j++].v;
      t = ta;
    }
    f(t, va, vb);
  }
}

}  // namespace rvc::engine::dense
