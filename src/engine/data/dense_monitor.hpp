// Dense-time monitor of one property with data references: the dense
// counterpart of DiscreteMonitor. Each sub-formula is a table of signals
// over the current segment [begin, end), one per assignment of its free
// variables; each temporal operator a table of the plain dense operators'
// states. Quantifiers fold a table's signals into one (union for exists,
// intersection for forall), change points included.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/data/tables.hpp"
#include "engine/dense/historically.hpp"
#include "engine/dense/once.hpp"
#include "engine/dense/signal.hpp"
#include "engine/dense/since.hpp"
#include "engine/explain.hpp"
#include "engine/program.hpp"

namespace rvc::engine::data {

class DenseMonitor {
 public:
  DenseMonitor(const Program& program, const std::string& property, uint32_t max_values);

  // The atoms' values (and bound values' ids) held over [begin, end); returns
  // the property's value over it. Throws DataLimitError past max_values.
  const dense::Signal& step(double begin, double end, const uint8_t* atoms, const uint32_t* bound);

  // Clock-driven monitoring (dense::Monitor::at, next_change, explain_at),
  // per assignment: after a step that ended at `now`, the atoms and bound
  // values held from there on, the property's value at `now` (a value bound
  // for the first time joins the tables, as the next step would have it
  // join: may throw DataLimitError); then the first time after `now` at
  // which an entry of any operator can change. O(table entries), as a step.
  bool at(double now, const uint8_t* atoms, const uint32_t* bound);
  double next_change(double now) const;
  std::vector<std::string> explain_at(double now, const explain::ValueNames* names = nullptr) const;

  // --explain: call before the first step, so the values met can be named.
  void enable_explain() { bindings_.keep_origins(); }
  // After step(): why the property has its value at time t of the segment
  // just stepped, naming sub-formulas, intervals and the values of the
  // quantified variables that decide (DiscreteMonitor::explain).
  std::vector<std::string> explain(double t, const explain::ValueNames* names = nullptr) const;

 private:
  template <class F>
  void each_table(F&& f);

  Program program_;  // explain(): the sub-formulas' texts and variables
  double begin_ = 0, end_ = 0;  // the segment last stepped
  std::vector<Instr> code_;
  Bindings bindings_;
  std::vector<Table<dense::Signal>> signal_;  // per instruction
  std::vector<int32_t> state_;
  std::vector<Table<dense::Once>> once_;
  std::vector<Table<dense::Historically>> historically_;
  std::vector<Table<dense::Since>> since_;
  dense::Signal scratch_;
  std::vector<Table<uint8_t>> at_;  // at(): each sub-formula's values at the clock
};

}  // namespace rvc::engine::data
