// Tables indexed by assignments of quantified variables: the storage of the
// data-reference monitors (exists[x]. ... {id: *x} ...).
//
// A sub-formula with free variables S has one value (and one operator state)
// per assignment of S. Each variable ranges over the values it has been
// bound to so far plus one more entry, index 0, "any other value": every
// value never seen behaves alike (no field has held it, so every test
// binding it has been false), so one entry stands for all of them. A value
// seen for the first time starts as a copy of that entry: it has the same
// history.
//
// So memory grows with the distinct values seen (times the other free
// variables' values), never with the trace's length.
//
// Layout: a table over S is a flat array; variable v's index is multiplied by
// the product of the capacities of the variables of S before it. Capacities
// double when a domain outgrows them, so adding values costs O(1) amortized
// per table entry.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/program.hpp"

namespace rvc::engine::data {

using Mask = uint32_t;  // a set of variables: bit v for variable v
inline Mask bit(int v) { return Mask{1} << v; }

// Per variable: how far its index moves a table's offset (0: not in the table).
struct Strides {
  std::array<size_t, kMaxVariables> of{};
};

class Domains {
 public:
  explicit Domains(size_t variables) : size_(variables, 1), capacity_(variables, 1) {}

  size_t variables() const { return size_.size(); }
  uint32_t size(int v) const { return size_[static_cast<size_t>(v)]; }  // live indexes, "other" included

  // Adds an index to variable v; true if its capacity grew (tables over v
  // must then be laid out again).
  bool add(int v) {
    auto& n = size_[static_cast<size_t>(v)];
    auto& cap = capacity_[static_cast<size_t>(v)];
    ++n;
    if (n <= cap) return false;
    cap *= 2;
    return true;
  }

  Strides strides(Mask mask) const {
    Strides s;
    size_t step = 1;
    for (size_t v = 0; v < size_.size(); ++v)
      if (mask & bit(static_cast<int>(v))) {
        s.of[v] = step;
        step *= capacity_[v];
      }
    return s;
  }
  size_t capacity(Mask mask) const {
    size_t n = 1;
    for (size_t v = 0; v < size_.size(); ++v)
      if (mask & bit(static_cast<int>(v))) n *= capacity_[v];
    return n;
  }
  size_t live(Mask mask) const {  // assignments in use
    size_t n = 1;
    for (size_t v = 0; v < size_.size(); ++v)
      if (mask & bit(static_cast<int>(v))) n *= size_[v];
    return n;
  }

  // Calls f(offsets) once per live assignment of the variables in `over`,
  // offsets[k] being the assignment's position in a table with strides[k]
  // (a table without some of those variables repeats its entries: broadcast).
  template <size_t N, class F>
  void for_each(Mask over, const std::array<Strides, N>& strides, F&& f) const {
    int vars[kMaxVariables];
    int k = 0;
    for (size_t v = 0; v < size_.size(); ++v)
      if (over & bit(static_cast<int>(v))) vars[k++] = static_cast<int>(v);
    std::array<size_t, N> off{};
    uint32_t index[kMaxVariables] = {};
    for (;;) {
      f(off);
      int j = 0;
      for (; j < k; ++j) {  // an odometer over the variables' indexes
        const auto v = static_cast<size_t>(vars[j]);
        if (++index[j] < size_[v]) {
          for (size_t n = 0; n < N; ++n) off[n] += strides[n].of[v];
          break;
        }
        for (size_t n = 0; n < N; ++n) off[n] -= (index[j] - 1) * strides[n].of[v];
        index[j] = 0;
      }
      if (j == k) return;
    }
  }

 private:
  std::vector<uint32_t> size_;
  std::vector<uint32_t> capacity_;
};

// A table of T over a set of variables.
template <class T>
struct Table {
  Mask mask = 0;
  std::vector<T> cells;
  Strides strides;

  void init(const Domains& d, Mask m, const T& initial) {
    mask = m;
    strides = d.strides(m);
    cells.assign(d.capacity(m), initial);
  }
  T& at(size_t offset) { return cells[offset]; }

  // After `before` became `after` by adding an index to v whose capacity
  // grew: moves every live entry to its new place.
  void relayout(const Domains& before, const Domains& after) {
    std::vector<T> next(after.capacity(mask));
    const Strides to = after.strides(mask);
    before.for_each<2>(mask, {strides, to}, [&](const std::array<size_t, 2>& o) { next[o[1]] = std::move(cells[o[0]]); });
    cells.swap(next);
    strides = to;
  }
  // Variable v gained index `index`: its entries start as copies of the
  // "any other value" entries (index 0).
  void extend(const Domains& d, int v, uint32_t index) {
    if (!(mask & bit(v))) return;
    const size_t shift = index * strides.of[static_cast<size_t>(v)];
    d.for_each<1>(mask & ~bit(v), {strides}, [&](const std::array<size_t, 1>& o) { cells[o[0] + shift] = cells[o[0]]; });
  }
};

// Per variable: which index each bound value (io::BoundValues id) has.
class ValueIndex {
 public:
  // 0 if the value is new (the caller adds it, then calls set()).
  uint32_t find(uint32_t value) const { return value < index_.size() ? index_[value] : 0; }
  void set(uint32_t value, uint32_t index) {
    if (value >= index_.size()) index_.resize(value + 1 + value / 2, 0);
    index_[value] = index;
  }

 private:
  std::vector<uint32_t> index_;
};

// A variable took more distinct values than allowed (--max-data-values).
class DataLimitError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The variables of one property: their domains, which index each bound
// value has, and this step's index for each test that binds.
class Bindings {
 public:
  Bindings(const Program& program, const std::string& property, uint32_t max_values);

  const Domains& domains() const { return domains_; }
  // Instruction i (a Bind): the index of the value its field holds now; 0: none yet.
  uint32_t index(size_t i) const { return index_of_instr_[i]; }

  // --explain names the values that decide: where each index came from
  // (kept only once keep_origins() was called, before the first update).
  struct Origin {
    uint32_t id = 0;     // the value (io::BoundValues id)
    uint32_t instr = 0;  // the Bind instruction that met it first
    double time = 0;     // the step (discrete) or time (dense) it was met at
  };
  void keep_origins() { origins_.assign(domains_.variables(), std::vector<Origin>(1)); }
  // Variable v's index k (k >= 1); null when not kept.
  const Origin* origin(int var, uint32_t k) const {
    if (origins_.empty() || k >= origins_[static_cast<size_t>(var)].size()) return nullptr;
    return &origins_[static_cast<size_t>(var)][k];
  }

  // Reads this step's bound values (io::BoundValues ids per atom; null:
  // none). A value new to its variable gets an index first, and
  // `grow(var, index, before)` is called so every table over var can make
  // room (relayout when the capacity grew, then extend). Throws
  // DataLimitError past max_values.
  // `time`: the step or time of the values, for origin().
  template <class Grow>
  void update(const uint32_t* bound, Grow&& grow, double time = 0) {
    for (size_t i = 0; i < code_.size(); ++i) {
      const Instr& in = code_[i];
      if (in.code != Code::Bind) continue;
      const uint32_t value = bound ? bound[in.atom] : 0;
      auto& index = value_index_[static_cast<size_t>(in.var)];
      if (value != 0 && index.find(value) == 0) {
        check_limit(in.var);
        const Domains before = domains_;
        const bool grew = domains_.add(in.var);
        if (grew) check_size(before);
        index.set(value, domains_.size(in.var) - 1);
        if (!origins_.empty()) origins_[static_cast<size_t>(in.var)].push_back({value, static_cast<uint32_t>(i), time});
        grow(in.var, domains_.size(in.var) - 1, grew ? &before : nullptr);
      }
      index_of_instr_[i] = value ? index.find(value) : 0;
    }
  }

 private:
  void check_limit(int var) const;
  void check_size(const Domains& before);  // restores `before` and throws past kMaxEntries

  // The most entries one table may have: a sub-formula over several
  // variables takes the product of their values.
  static constexpr size_t kMaxEntries = size_t{1} << 24;

  std::vector<Instr> code_;
  std::vector<std::string> variables_;
  std::string property_;
  uint32_t max_values_;
  Domains domains_;
  std::vector<ValueIndex> value_index_;  // per variable
  std::vector<uint32_t> index_of_instr_;
  std::vector<Mask> masks_;  // of the tables (free variables of each sub-formula)
  std::vector<std::vector<Origin>> origins_;  // per variable, per index (--explain only)
};

// Makes room in `table` for variable var's new index (Bindings::update).
template <class T>
void grow_table(Table<T>& table, const Domains& now, int var, uint32_t index, const Domains* before) {
  if (!(table.mask & bit(var))) return;
  if (before) table.relayout(*before, now);
  table.extend(now, var, index);
}

// The free variables of each instruction (its table's mask).
std::vector<Mask> free_variables(const Program& program);

}  // namespace rvc::engine::data
