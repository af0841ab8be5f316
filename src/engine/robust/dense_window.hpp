// Dense-time robustness of once[a:b] φ (the maximum of φ over [t-b, t-a])
// and, negated, historically[a:b] φ (the minimum).
//
// A piece of φ holding v on [u, w) lies in the window of every t in
// [u+a, w+b): it is a contribution of v over that interval. Pieces come in
// time order, so contributions start and end in order too; the maximum over
// the active ones is the front of a deque of decreasing values (a newer
// contribution at least as large outlives and outweighs the older ones).
// Each event costs O(1) amortized plus the changes it outputs, whatever a
// and b are. An empty window is -inf (once) or +inf (historically).
#pragma once

#include <deque>
#include <limits>

#include "engine/robust/dense_signal.hpp"

namespace rvc::engine::robust {

class DenseWindow {
 public:
  // sign +1: once (maximum); -1: historically (minimum, as -max of -φ).
  DenseWindow(double lo, double hi, double sign) : lo_(lo), hi_(hi), sign_(sign) {}

  void update(const RealSignal& input, double end, RealSignal& out) {
    const auto& p = input.pieces;
    for (size_t i = 0; i < p.size(); ++i) {
      const double until = i + 1 < p.size() ? p[i + 1].t : end;
      if (p[i].t < until) pending_.push_back({p[i].t + lo_, until + hi_, sign_ * p[i].v});
    }
    out.clear();
    double t = p[0].t;
    for (;;) {
      while (!pending_.empty() && pending_.front().start <= t) {  // contributions starting by t
        const Contribution c = pending_.front();
        pending_.pop_front();
        while (!active_.empty() && active_.back().value <= c.value) active_.pop_back();
        active_.push_back(c);
      }
      while (!active_.empty() && active_.front().stop <= t) active_.pop_front();
      const double best = active_.empty() ? -kInf : active_.front().value;
      out.set(t, sign_ * best);
      double next = kInf;
      if (!pending_.empty()) next = pending_.front().start;
      if (!active_.empty() && active_.front().stop < next) next = active_.front().stop;
      if (!(next < end)) break;
      t = next;
    }
  }

 private:
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  struct Contribution {
    double start, stop;  // [start, stop)
    double value;        // times sign
  };
  double lo_, hi_, sign_;
  std::deque<Contribution> pending_;  // not started yet, by start
  std::deque<Contribution> active_;   // started, values decreasing, stops increasing
};

}  // namespace rvc::engine::robust
