// Discrete-time monitor of one property: one call to step() per message.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/discrete/historically.hpp"
#include "engine/discrete/once.hpp"
#include "engine/discrete/pre.hpp"
#include "engine/discrete/since.hpp"
#include "engine/program.hpp"

namespace rvc::engine::discrete {

class Monitor {
 public:
  explicit Monitor(const Program& program);
  // Advances one step with the current atom values; returns the verdict.
  bool step(const uint8_t* atoms);
  Step now() const { return now_; }  // index of the next step

 private:
  // Operands are slots of one value array: this property's atoms first, then the
  // constants 0 and 1, then each operator's output. Atoms, constants and
  // negations are not operators at all: `not` is a flag on the operand that
  // reads it. A Timescales property shrinks from 12 nodes to 6 this way.
  struct Op {
    Code code;
    uint8_t negate_a = 0, negate_b = 0;
    uint8_t unused = 0;
    uint16_t a = 0, b = 0;  // operand slots
    uint16_t out = 0;       // result slot
    uint16_t slot = 0;      // index into the state array of its operator
  };
  struct Operand {
    uint16_t slot;
    uint8_t negate;
  };
  std::vector<Op> ops_;
  std::vector<uint8_t> value_;
  std::vector<uint32_t> atoms_;  // the shared atom table's ids this property reads, in slot order
  Operand root_{};
  std::vector<Pre> pre_;
  std::vector<Once> once_;
  std::vector<Historically> historically_;
  std::vector<Since> since_;
  Step now_ = 0;
};

}  // namespace rvc::engine::discrete
