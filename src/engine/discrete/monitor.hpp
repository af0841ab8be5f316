// Discrete-time monitor of many properties at once: one call to step() per
// message evaluates them all.
//
// Properties share what they have in common: an identical sub-formula over
// the same operands (once{q} in a hundred properties) is one operator,
// stepped once per message for all of them. Sharing is structural and
// bottom-up, so it finds every common sub-formula, however it was written.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <tuple>
#include <vector>

#include "engine/discrete/historically.hpp"
#include "engine/discrete/once.hpp"
#include "engine/discrete/pre.hpp"
#include "engine/discrete/since.hpp"
#include "engine/program.hpp"

namespace rvc::engine::discrete {

class Monitor {
 public:
  Monitor();
  // Adds a property (before the first step). False, and nothing added, if
  // it would not fit (65,000 slots): the caller starts another Monitor.
  // Throws std::length_error for a property that alone is too large.
  bool add(const Program& program);
  size_t size() const { return properties_.size(); }

  // Advances one step with the current atom values (indexed by the shared
  // atom table); then value(k) is property k's verdict.
  void step(const uint8_t* atoms);
  bool value(size_t k) const { return read(properties_[k].root); }
  Step now() const { return now_; }  // index of the next step
  size_t operators() const { return ops_.size(); }  // after sharing (benchmarks, tests)

  // ---- Change-driven stepping (Checker's default; the plain step() above is
  // kept for --plain-eval and the differential tests) ----
  //
  // step_changed() gives the same values as step(), evaluating only the
  // operators whose operands changed since the previous step, plus the
  // bounded ones (and pre) whose state can still change with unchanged
  // operands. Skipping any other operator is exact: connectives and the
  // unbounded latches are idempotent under repeated operands (once: last | a
  // is last again), and a bounded operator with an empty window and an input
  // that adds nothing (once[a:b] of false, since with false right side) does
  // nothing when stepped. A window whose front covers the rest of time
  // (once[3:] after its input held) is as stable. Every slot therefore holds
  // the value step() would have given (explain() reads them), except, with
  // prune_dead, inside dead cones: an unbounded historically that has fallen
  // false (once that has risen true) never changes again, so the operators
  // only it reads are never stepped again, nor is it.
  //
  // `changed`: the atom table ids whose values differ from the previous
  // step's (ignored at the first step, which steps everything). Appends to
  // `roots` the properties whose root slot changed (all at the first step).
  void set_prune_dead(bool on) { prune_dead_ = on; }
  void step_changed(const uint8_t* atoms, const uint32_t* changed, size_t n_changed, std::vector<uint32_t>& roots);
  // Operators stepped by the last step_changed (benchmarks, tests).
  size_t stepped() const { return stepped_; }

  // After step(): why property k has its current value, as sentences naming
  // sub-formulas and steps ("{x > 3} is false at step 12"). For --explain, at
  // a violation: it reads this step's values, so it costs nothing before.
  std::vector<std::string> explain(size_t k) const;

 private:
  // Operands are slots of one value array: the constants 0 and 1, the atoms
  // read, and each operator's output. Atoms, constants and negations are not
  // operators at all: `not` is a flag on the operand that reads it.
  struct Operand {
    uint16_t slot = 0;
    uint8_t negate = 0;
  };
  // What an operator does each step. Once, historically and since over all
  // the past (no bounds) need no window: each is a latch over its own
  // previous output, read back from its slot (`All` kinds).
  enum class Kind : uint8_t { And, Or, Implies, Pre, Once, OnceAll, Historically, HistoricallyAll, Since, SinceAll };
  struct Op {
    Kind kind;
    uint8_t negate_a = 0, negate_b = 0;
    uint8_t unused = 0;
    uint16_t a = 0, b = 0;  // operand slots
    uint16_t out = 0;       // result slot
    uint16_t slot = 0;      // index into the state array of its operator
  };
  struct Property {
    Program program;                // for explain(): codes, operands, bounds, texts
    std::vector<Operand> operand;   // per instruction: where its value is
    Operand root;
  };
  // What makes two operators the same: code, operands, bounds.
  using Key = std::tuple<Code, uint16_t, uint8_t, uint16_t, uint8_t, double, double>;

  static Kind kind_of(const Instr& in);
  bool read(Operand o) const { return value_[o.slot] ^ o.negate; }
  void why(const Property& p, size_t instruction, Step at, std::vector<std::string>& out) const;

  std::vector<Op> ops_;
  std::vector<uint8_t> value_;
  std::vector<uint32_t> atom_ids_;    // the shared atom table's ids read, ...
  std::vector<uint16_t> atom_slots_;  // ... and their slots
  std::map<uint32_t, uint16_t> atom_slot_of_;
  std::map<Key, uint16_t> shared_;    // operator -> its output slot
  std::vector<Property> properties_;
  std::vector<Pre> pre_;
  std::vector<Once> once_;
  std::vector<Historically> historically_;
  std::vector<Since> since_;
  Step now_ = 0;

  // Change-driven stepping (built at the first step_changed).
  void prepare_changes();
  uint8_t evaluate(const Op& op, uint8_t* v, Step now);
  bool quiet(const Op& op, const uint8_t* v, Step now) const;  // skipping it next step is exact
  bool frozen_value(const Op& op, uint8_t r) const;         // an unbounded latch that can no longer change
  void release(uint32_t op);                                 // op no longer read: its operands may die
  void mark_readers(uint16_t slot, std::vector<uint32_t>& roots);
  bool prune_dead_ = false;
  bool prepared_ = false;
  static constexpr uint16_t kNoSlot = 0xFFFF;
  std::vector<uint16_t> slot_of_atom_;      // atom table id -> this monitor's slot (kNoSlot: not read)
  std::vector<uint32_t> reader_begin_, readers_;  // per slot: the ops reading it (CSR)
  std::vector<uint32_t> root_begin_, roots_;      // per slot: the properties whose root it is (CSR)
  std::vector<uint32_t> op_of_slot_;        // an op's output slot -> the op (UINT32_MAX: atom, constant)
  std::vector<uint32_t> live_readers_;      // prune_dead: readers still stepped + properties rooted there
  std::vector<uint8_t> skip_;               // 1: dead or frozen, never stepped again
  std::vector<uint64_t> dirty_, dirty_words_;  // ops to step (bitset) and its non-empty words (bitset)
  std::vector<uint32_t> busy_, next_busy_;  // bounded ops and pre that are not quiet: stepped next step too
  size_t stepped_ = 0;
  void mark(uint32_t op) {
    dirty_[op >> 6] |= uint64_t{1} << (op & 63);
    dirty_words_[op >> 12] |= uint64_t{1} << ((op >> 6) & 63);
  }
};

}  // namespace rvc::engine::discrete
