// pre φ (Y φ): φ held at the previous step; false at the first step.
#pragma once

namespace rvc::engine::discrete {

struct Pre {
  bool previous = false;
  bool update(bool input) {
    bool out = previous;
    previous = input;
    return out;
  }
};

}  // namespace rvc::engine::discrete
