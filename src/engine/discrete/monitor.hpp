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
  std::vector<Instr> code_;
  std::vector<uint8_t> value_;
  std::vector<int32_t> state_;  // per instruction: index into its operator's state array
  std::vector<Pre> pre_;
  std::vector<Once> once_;
  std::vector<Historically> historically_;
  std::vector<Since> since_;
  Step now_ = 0;
};

}  // namespace rvc::engine::discrete
