// φ since[a:b] ψ (φ S ψ): ψ held at some step j with now - j in [a, b], and φ
// held at every step after j up to now.
//
// Candidates are the steps where ψ held since φ last failed; each is stored
// shifted by the bounds, [j+a, j+b], like once. A step where φ fails drops
// every earlier candidate (but ψ at that very step still counts).
#pragma once

#include "engine/discrete/once.hpp"

namespace rvc::engine::discrete {

struct Since {
  Step lo = 0, hi = kForever;
  IntervalQueue<Step> candidates;

  bool update(Step now, bool left, bool right) {
    if (!left) candidates.clear();
    if (right) candidates.add(now + lo, hi >= kForever ? kForever : now + hi, 1);
    candidates.drop_before(now);
    return !candidates.empty() && candidates.front().lo <= now;
  }
};

}  // namespace rvc::engine::discrete
