// The values of the timing atoms and window aggregates of one run
// ({x.@arrived}, {x.@age <= d}, {x.@latency < d}, {count[a:b](x.@arrived) >= n},
// {avg[a:b](x.speed) > v}): tests in the atom table that no decoder
// evaluates, since they depend on when messages came, not on what they hold.
// The runtime tells this class when time moves on and which input's message
// arrived; it writes the atoms' values into the array the checker steps on.
//
// Time is the stream's: steps in discrete time, message times (stamps) in
// dense time. In dense time these atoms change without any message (an age
// passes its bound, a sample leaves a window); next_change() says when, so
// the runtime steps the monitors through each such instant in order
// (docs/semantics.md, "Timing atoms and window aggregates").
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "engine/atom_table.hpp"
#include "engine/program.hpp"
#include "engine/timed/expr_eval.hpp"
#include "engine/timed/window_aggregate.hpp"

namespace rvc::engine::timed {

class TimedAtoms {
 public:
  // `inputs`: the inputs' names in feed order (one "" for a single unnamed
  // input). A field aggregate needs its field's value: two hidden tests,
  // {field: *} and {field}, are interned into `atoms` for it, and their
  // committed value and margin (the decoder's, DecoderOptions::robustness)
  // give the sample. Throws std::invalid_argument for an atom on no input.
  // Dense time runs in engine nanoseconds (runtime/engine_time.hpp): every
  // time given and returned, and the bounds, which it reads exactly.
  TimedAtoms(AtomTable& atoms, const std::vector<std::string>& inputs, TimeModel model);

  bool empty() const { return atoms_.empty() && exprs_.empty(); }
  // Some aggregate or expression reads a field: the decoder must compute margins.
  bool needs_field_values() const { return field_values_; }
  // Some atom reads @latency: the runtime must know each message's arrival.
  bool needs_arrival() const { return latency_; }

  // Time moves on to t (>= the current time; earlier is ignored): samples
  // enter and leave windows, ages grow, and in discrete time a new step
  // starts (no input has arrived in it yet).
  void advance(double t);
  // A message of `input` at the current time, `latency` = its arrival minus
  // its stamp (NaN: unknown). `values`/`margins`: the committed values of the
  // atom table (margins may be null without field aggregates).
  void arrive(uint32_t input, double latency, const uint8_t* values, const double* margins);
  // The first instant after the current time at which an atom may change
  // value with no message (+inf: none; always +inf in discrete time).
  double next_change() const;
  double now() const { return now_; }

  // The atoms' values at the current time (dense: the value that holds from
  // it on) into `values`, indexed by atom id; margins likewise.
  void write(uint8_t* values) const;
  void write_margins(double* margins) const;

  // --explain: the numbers an expression atom computed with, "a = 1, b = 2.5"
  // ("b: no number yet"); "" for any other atom.
  std::string describe(int atom_id) const;
  bool has_expressions() const { return !exprs_.empty(); }

 private:
  struct Atom {
    int id;               // in the atom table
    uint32_t input;
    spec::Timed::Kind kind;
    spec::FieldTest::Op op;
    double bound;         // the number compared with
    int window = -1;      // Aggregate: index in windows_
  };
  struct Source {         // what feeds windows_[k]
    uint32_t input;
    bool of_arrivals;
    int present = -1, value = -1;  // hidden tests: {field: *}, {field}
  };
  struct InputState {
    bool any = false;     // a message has arrived
    double last = 0;      // its time
    double latency = 0;   // its arrival - stamp (NaN: unknown)
    double arrived_at = -1;  // discrete: the step it last arrived in
  };
  // An arithmetic comparison ({abs(a.x - b.x) < 0.1}, issue 29): its fields
  // are hidden {field as a number} tests (FieldTest::Op::Value) whose
  // committed value says the field was ever seen and whose margin holds its
  // number. Its value changes only when a message arrives.
  struct ExprAtom {
    int id;
    spec::FieldTest::Op op;
    CompiledExpr lhs, rhs;
    std::vector<int> leaves;  // indexes into leaves_ it reads
    bool holds = false;
    double margin = -std::numeric_limits<double>::infinity();
  };
  struct Leaf {
    int id;  // the hidden Value test
    std::string key;  // the field, as written
    double number = 0;
    bool seen = false;
  };
  void evaluate_exprs();
  double measure(const Atom& a) const;  // the atom's number now (age, latency, aggregate)
  bool holds(const Atom& a) const;

  bool dense_;
  bool field_values_ = false, latency_ = false;
  double now_ = 0;
  std::vector<Atom> atoms_;
  std::vector<InputState> inputs_;
  std::vector<WindowAggregate> windows_;
  std::vector<Source> sources_;
  std::vector<ExprAtom> exprs_;
  std::vector<Leaf> leaves_;
  std::vector<double> leaf_numbers_, stack_;
};

}  // namespace rvc::engine::timed
