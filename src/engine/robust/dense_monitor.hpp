// Dense-time robustness monitor of one property (`--robustness --dense`):
// the discrete robustness monitor's semantics over real-valued signals that
// hold from one message to the next. Atoms hold their margin over the
// segment; not, and, or, implies are pointwise; once and historically take
// the maximum / minimum over their window (dense_window.hpp). `since` is
// refused: Reelay 25's dense robustness for it follows neither its discrete
// recurrence nor the textbook definition on every trace.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/program.hpp"
#include "engine/robust/dense_window.hpp"

namespace rvc::engine::robust {

class DenseMonitor {
 public:
  explicit DenseMonitor(const Program& program);
  // The atoms' margins held over [begin, end): the property's robustness over it.
  const RealSignal& step(double begin, double end, const double* margins);

  static std::string unsupported(const Program& program);

 private:
  std::vector<Instr> code_;
  std::vector<RealSignal> signal_;
  std::vector<int32_t> state_;
  std::vector<DenseWindow> window_;
};

}  // namespace rvc::engine::robust
