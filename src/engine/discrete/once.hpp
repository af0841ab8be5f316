// once[a:b] φ (P φ): φ held at some step j with now - j in [a, b].
//
// Each step where φ holds contributes the closed interval [j+a, j+b] of steps
// at which it makes once true; the queue keeps those intervals merged, so the
// answer is whether the front interval has started. Unbounded b collapses the
// queue to one interval. Cost per step: O(1) amortized, independent of a and b.
#pragma once

#include <cstdint>
#include <limits>

#include "engine/interval_queue.hpp"

namespace rvc::engine::discrete {

using Step = int64_t;
inline constexpr Step kForever = std::numeric_limits<Step>::max() / 4;

struct Once {
  Step lo = 0, hi = kForever;  // bounds; kForever = no upper bound
  IntervalQueue<Step> window;

  bool update(Step now, bool input) {
    if (input) window.add(now + lo, hi >= kForever ? kForever : now + hi, 1);
    window.drop_before(now);
    return !window.empty() && window.front().lo <= now;
  }
};

}  // namespace rvc::engine::discrete
