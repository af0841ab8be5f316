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

#include <algorithm>
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
      if (p[i].t < until) add({p[i].t + lo_, until + hi_, sign_ * p[i].v});
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

  // Clock-driven monitoring (engine/dense/lookahead.hpp), after an update
  // that ended at `now`, the operand holding `input` from there on: the
  // value at `now` (the first piece the next update would start with), and
  // the first time after `now` at which the value can change: some
  // contribution's start or stop, the held operand's starting at now + lo
  // included. Those that cannot move the maximum are left out where that is
  // cheap to see, so a steady input gives no deadline: never late, maybe
  // early. O(1) but for contributions starting or ending exactly at `now`.
  double at(double input, double now) const {
    double best = lo_ == 0 ? sign_ * input : -kInf;
    for (const Contribution& c : active_)
      if (c.stop > now) {  // the first one alive is the largest (values decrease)
        best = std::max(best, c.value);
        break;
      }
    for (const Contribution& c : pending_) {  // those starting at now (earlier ones were taken)
      if (c.start > now) break;
      if (c.stop > now) best = std::max(best, c.value);
    }
    return sign_ * best;
  }
  double next_change(double input, double now) const {
    const double held = sign_ * input, ray = now + lo_;
    // An event at t of a contribution worth v cannot move the maximum once
    // the held operand's contribution (worth `held`) has started, if v <= held.
    const auto matters = [&](double t, double v) { return t < ray || v > held; };
    double next = kInf;
    for (const Contribution& c : active_) {
      if (c.stop <= now) continue;
      if (matters(c.stop, c.value)) next = std::min(next, c.stop);
      break;  // later ones stop later and are worth less
    }
    for (const Contribution& c : pending_) {
      if (c.start > now) {  // every pending start is before now + lo (its piece ended by now)
        next = std::min(next, c.start);
        break;
      }
      if (c.stop > now && matters(c.stop, c.value)) next = std::min(next, c.stop);
    }
    if (lo_ > 0 && ray < next && !continued(held, ray)) next = ray;
    return next;
  }

 private:
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  struct Contribution {
    double start, stop;  // [start, stop)
    double value;        // times sign
  };
  // Appends a piece's contribution; one worth the same as the last and
  // touching it extends it instead (the maximum is the same), so an operand
  // cut into many equal pieces (ticks) keeps one contribution.
  void add(const Contribution& c) {
    Contribution* last = !pending_.empty() ? &pending_.back() : !active_.empty() ? &active_.back() : nullptr;
    if (last && last->value == c.value && c.start <= last->stop) {
      last->stop = std::max(last->stop, c.stop);
      return;
    }
    pending_.push_back(c);
  }
  // Whether a contribution worth at least `held` covers both sides of t
  // (then the held operand's contribution starting at t changes nothing there).
  bool continued(double held, double t) const {
    for (const std::deque<Contribution>* q : {&pending_, &active_})
      if (!q->empty()) {
        const Contribution& c = q->back();
        if (c.value >= held && c.start < t && c.stop >= t) return true;
      }
    return false;
  }

  double lo_, hi_, sign_;
  std::deque<Contribution> pending_;  // not started yet, by start
  std::deque<Contribution> active_;   // started, values decreasing, stops increasing
};

}  // namespace rvc::engine::robust
