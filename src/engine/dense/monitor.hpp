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

  // Clock-driven monitoring (Checker::tick, Checker::next_deadline). After a
  // step that ended at `now`, the atoms holding `atoms` from there on: the
  // property's value at `now` itself (the first piece the next step would
  // start with; the state is not changed). Reads only the operators' state:
  // O(operators).
  bool at(double now, const uint8_t* atoms);
  // After at(now, atoms): the first time after `now` at which the property
  // can change while the atoms hold (never later than the change; maybe
  // earlier, then it changes nothing). Each operator's operand is constant
  // until the first change of any sub-formula, so the earliest of the
  // operators' own next changes, their operands held, is that first change.
  // kNever (+inf) when nothing can change.
  double next_change(double now) const;
  // After at(now, atoms): why the property has its value at `now` (as explain()).
  std::vector<std::string> explain_at(double now) const;

 private:
  Program program_;  // explain(): the sub-formulas' texts
  double begin_ = 0, end_ = 0;  // the segment last stepped
  std::vector<Instr> code_;
  std::vector<Signal> signal_;
  std::vector<uint8_t> at_;  // at(): each sub-formula's value at the clock
  std::vector<int32_t> state_;
  std::vector<Once> once_;
  std::vector<Historically> historically_;
  std::vector<Since> since_;
};

}  // namespace rvc::engine::dense
