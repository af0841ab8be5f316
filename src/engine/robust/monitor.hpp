// Discrete-time robustness monitor of one property (`rvc check --robustness`):
// how far each step is from changing the verdict, with Reelay's quantitative
// semantics. Atoms give a margin ({x > 3}: x - 3, {x < 3}: 3 - x, {x == 3}:
// -|x - 3|, a Boolean field: 1 or 0, a string test: +inf or -inf); `not`
// negates, `and`/`or` take the minimum/maximum, `once` and `historically`
// the maximum/minimum over their window, `since` the maximum over the
// candidate steps of the minimum along the way. A positive value means the
// property holds with that margin; a negative one, that it is violated by it.
#pragma once

#include <cstdint>
#include <vector>

#include "engine/program.hpp"
#include "engine/robust/window.hpp"

namespace rvc::engine::robust {

class Monitor {
 public:
  // Throws std::invalid_argument for what it cannot evaluate (see supported()).
  explicit Monitor(const Program& program);
  // One step with the atoms' margins (indexed by the shared atom table).
  double step(const double* margins);

  // "" if the program can be monitored for robustness, else why not.
  static std::string unsupported(const Program& program);

 private:
  const Program program_;
  std::vector<double> value_;        // per instruction, this step
  std::vector<double> previous_;     // Pre: the operand's value at the previous step
  std::vector<int32_t> state_;       // per instruction: index into its operator's state
  std::vector<Window<true>> once_;
  std::vector<Window<false>> historically_;
  std::vector<double> since_;        // unbounded since: the value at the previous step
  Step now_ = 0;
};

}  // namespace rvc::engine::robust
