// Dense-time monitor of one property. Each message at time t closes the
// segment [t_prev, t) during which the previous values held; step() returns
// the property's value over that segment, with every change point inside it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/dense/historically.hpp"
#include "engine/dense/once.hpp"
#include "engine/dense/signal.hpp"
#include "engine/dense/since.hpp"
#include "engine/program.hpp"

namespace rvc::engine::dense {

class Monitor {
 public:
  explicit Monitor(const Program& program);
  const Signal& step(double begin, double end, const uint8_t* atoms);

  // After step(): why the property has its value at time t of the segment
  // just stepped (--explain, at a violation's start), as sentences naming
  // sub-formulas and intervals ("{brake} is false throughout [3.5, 5)"). It
  // reads the signals step() left over the segment: no cost before.
  std::vector<std::string> explain(double t) const;

 private:
  Program program_;  // explain(): the sub-formulas' texts
  double begin_ = 0, end_ = 0;  // the segment last stepped
  std::vector<Instr> code_;
  std::vector<Signal> signal_;
  std::vector<int32_t> state_;
  std::vector<Once> once_;
  std::vector<Historically> historically_;
  std::vector<Since> since_;
};

}  // namespace rvc::engine::dense
