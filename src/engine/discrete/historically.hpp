// historically[a:b] φ (H φ): φ held at every step j with now - j in [a, b];
// true while that window is still empty (the first a steps), as in Reelay.
// It is the dual of once: not once[a:b] (not φ).
#pragma once

#include "engine/discrete/once.hpp"

namespace rvc::engine::discrete {

struct Historically {
  Once violations;  // once[a:b] of (not φ)
  bool update(Step now, bool input) { return !violations.update(now, !input); }
};

}  // namespace rvc::engine::discrete
