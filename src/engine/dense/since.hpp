// Dense-time φ since[a:b] ψ.
//
// The segment is cut where φ or ψ changes; on each piece [u, w) both are
// constant. Candidates are times where ψ held since φ last failed, stored
// shifted by the bounds like once:
//   φ true:  if ψ holds, [u, w) joins the candidates as [u+a, w+b); the output
//            on [u, w) is the union of the candidates.
//   φ false: the output is false (even for a = 0, as in Reelay); candidates
//            are dropped, and if ψ holds the piece leaves one candidate at its
//            right end w (φ may hold from there on): [w+a, w+b).
// The result does not depend on how messages cut time: a message that
// changes nothing changes no verdict (Reelay 25 differs; docs/semantics.md).
//
// `right_suffices`: ψ holding on a piece makes the output true there even
// while φ is false (s = t in "ψ at s, φ on (s, t]"). Reelay 25's dense data
// monitors read `since` written without bounds so; its plain ones do not.
#pragma once

#include "engine/dense/lookahead.hpp"
#include "engine/dense/signal.hpp"
#include "engine/interval_queue.hpp"
#include "spec/ast.hpp"

namespace rvc::engine::dense {

struct Since {
  double lo = 0, hi = spec::kInfinity;
  bool right_suffices = false;
  IntervalQueue<double> candidates;

  // Clock-driven monitoring (lookahead.hpp), after a step that ended at
  // `now`, the operands holding `left` and `right` from there on. While the
  // left side fails the output is constant (candidates are dropped at every
  // cut); while it holds, since is once over the candidates.
  bool at(bool left, bool right, double now) const {
    if (!left) return right_suffices && right;
    return window_at(candidates, right, lo, now);
  }
  double next_change(bool left, bool right, double now) const {
    if (!left) return kNever;
    return window_next_change(candidates, right, lo, now);
  }

  void update(const Signal& left, const Signal& right, double end, Signal& out) {
    out.clear();
    cuts_.clear();
    zip(left, right, [&](double t, bool l, bool r) { cuts_.push_back({t, l, r}); });
    for (size_t k = 0; k < cuts_.size(); ++k) {
      const Cut& c = cuts_[k];
      double until = k + 1 < cuts_.size() ? cuts_[k + 1].t : end;
      if (c.t >= until) continue;
      out.set(c.t, right_suffices && !c.left && c.right);
      if (!c.left) {
        candidates.clear();
        if (c.right) candidates.add(until + lo, until + hi, 0);
        continue;
      }
      if (c.right) candidates.add(c.t + lo, until + hi, 0);
      candidates.drop_until(c.t);
      for (size_t i = 0; i < candidates.size(); ++i) {
        const auto& iv = candidates.at(i);
        if (iv.lo >= until) break;
        out.set(iv.lo > c.t ? iv.lo : c.t, true);
        if (iv.hi < until) out.set(iv.hi, false);
      }
    }
    candidates.drop_until(end);
  }

 private:
  struct Cut {
    double t;
    bool left, right;
  };
  std::vector<Cut> cuts_;
};

}  // namespace rvc::engine::dense
