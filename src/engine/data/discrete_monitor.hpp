// Discrete-time monitor of one property with data references:
// exists[x]. / forall[x]. over tests that bind x ({id: *x}).
//
// Each sub-formula is a table of Booleans over its free variables (see
// tables.hpp), each temporal operator a table of the same discrete operator
// states the plain monitor uses, one per assignment. A step evaluates every
// live entry: its cost grows with the distinct values seen (O(1) per entry
// whatever the time bounds), its memory too, never with the trace's length.
//
// Semantics as Reelay 25's discrete data monitors, with one exception: a
// bounded historically[a:b] under a quantifier is true while its window is
// still empty, as everywhere else in rvc (Reelay reads it false for the first
// a+1 steps; docs/semantics.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "engine/data/tables.hpp"
#include "engine/discrete/historically.hpp"
#include "engine/discrete/once.hpp"
#include "engine/discrete/pre.hpp"
#include "engine/discrete/since.hpp"
#include "engine/explain.hpp"
#include "engine/program.hpp"

namespace rvc::engine::data {

class DiscreteMonitor {
 public:
  // `max_values`: the most distinct values one variable may take.
  DiscreteMonitor(const Program& program, const std::string& property, uint32_t max_values);

  // One step: the atoms' values and, for the tests that bind, the ids of
  // their fields' values (io::BoundValues; 0: none yet). Returns the verdict.
  // Throws DataLimitError when a variable outgrows max_values.
  bool step(const uint8_t* atoms, const uint32_t* bound);

  size_t entries() const;  // live table entries, all sub-formulas (tests, docs)

  // --explain: call before the first step, so the values met can be named.
  void enable_explain() { bindings_.keep_origins(); }
  // After step(): why the property has its current value, as sentences naming
  // sub-formulas, steps and the values of the quantified variables that
  // decide ("for f = \"a.txt\": {file: *f} is true at step 3"). `names`
  // names bound values by id (null: by where they were bound).
  std::vector<std::string> explain(const explain::ValueNames* names = nullptr) const;

 private:
  template <class F>
  void each_table(F&& f);

  Program program_;  // explain(): the sub-formulas' texts and variables
  std::vector<Instr> code_;
  Bindings bindings_;
  std::vector<Table<uint8_t>> value_;   // per instruction
  std::vector<uint32_t> set_;           // per Bind instruction: the index its table holds true, 0 none
  std::vector<int32_t> state_;          // per instruction: its table in the vector of its kind
  std::vector<Table<discrete::Pre>> pre_;
  std::vector<Table<discrete::Once>> once_;
  std::vector<Table<discrete::Historically>> historically_;
  std::vector<Table<discrete::Since>> since_;
  discrete::Step now_ = 0;
};

}  // namespace rvc::engine::data
