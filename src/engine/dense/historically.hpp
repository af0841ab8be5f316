// Dense-time historically[a:b] φ = not once[a:b] (not φ). Before time 0 there
// is no signal, so windows reaching before 0 hold vacuously, as in Reelay.
#pragma once

#include "engine/dense/once.hpp"

namespace rvc::engine::dense {

struct Historically {
  Once violations;
  Signal negated, scratch;

  // Clock-driven monitoring: as Once::at and Once::next_change.
  bool at(bool input, double now) const { return !violations.at(!input, now); }
  double next_change(bool input, double now) const { return violations.next_change(!input, now); }

  void update(const Signal& input, double end, Signal& out) {
    negated.clear();
    for (const Piece& pc : input.pieces) negated.set(pc.t, !pc.v);
    violations.update(negated, end, scratch);
    out.clear();
    for (const Piece& pc : scratch.pieces) out.set(pc.t, !pc.v);
  }
};

}  // namespace rvc::engine::dense
