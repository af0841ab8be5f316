// Discrete-time monitor of one property: one call to step() per message.
#pragma once

#include <cstdint>
#include <string>
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

  // After step(): why the property has its current value, as sentences
  // naming sub-formulas and steps ("{x > 3} is false at step 12", "once[0:5]
  // ({q}) is false: ({q}) held at no step in 7..12"). For `--explain`, at a
  // violation: it reads the values of this step, so it costs nothing before.
  std::vector<std::string> explain() const;

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
  bool value_of(size_t instruction) const {
    return value_[operand_[instruction].slot] ^ operand_[instruction].negate;
  }
  void why(size_t instruction, Step at, std::vector<std::string>& out) const;

  Program program_;                // kept for explain(): codes, operands, bounds, texts
  std::vector<Operand> operand_;   // per instruction: where its value is this step
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
