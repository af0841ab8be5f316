// Change-driven stepping of the discrete monitor (see monitor.hpp,
// step_changed): per message, work in proportion to what changed (atoms
// that flipped, operators whose operands flipped, bounded windows still in
// flight) rather than to the number of operators.
#include <algorithm>
#include <cstdint>

#include "engine/discrete/monitor.hpp"

namespace rvc::engine::discrete {
namespace {

constexpr uint32_t kNoOp = UINT32_MAX;

template <class W>
bool covers_rest_of_time(const W& window, Step now) {  // the front interval holds from now on, forever
  return window.size() == 1 && window.front().hi >= kForever && window.front().lo <= now;
}

}  // namespace

uint8_t Monitor::evaluate(const Op& op, uint8_t* v, Step now) {
  const uint8_t a = v[op.a] ^ op.negate_a;
  const uint8_t b = v[op.b] ^ op.negate_b;
  const uint8_t last = v[op.out];
  uint8_t r = 0;
  switch (op.kind) {
    case Kind::And: r = a & b; break;
    case Kind::Or: r = a | b; break;
    case Kind::Implies: r = (a ^ 1) | b; break;
    case Kind::Pre: r = pre_[op.slot].update(a); break;
    case Kind::Once: r = once_[op.slot].update(now, a); break;
    case Kind::OnceAll: r = last | a; break;
    case Kind::Historically: r = historically_[op.slot].update(now, a); break;
    case Kind::HistoricallyAll: r = last & a; break;
    case Kind::Since: r = since_[op.slot].update(now, a, b); break;
    case Kind::SinceAll: r = b | (a & last); break;
  }
  v[op.out] = r;
  return r;
}

// After stepping op at `now`: would stepping it again at now + 1 with the
// same operands change nothing (state or output)?
bool Monitor::quiet(const Op& op, const uint8_t* v, Step now) const {
  const uint8_t a = v[op.a] ^ op.negate_a;
  const uint8_t b = v[op.b] ^ op.negate_b;
  switch (op.kind) {
    case Kind::Pre: return v[op.out] == a;  // its next output is a: the same
    case Kind::Once: {
      const auto& w = once_[op.slot].window;
      return (w.empty() && !a) || covers_rest_of_time(w, now);
    }
    case Kind::Historically: {
      const auto& w = historically_[op.slot].violations.window;
      return (w.empty() && a) || covers_rest_of_time(w, now);
    }
    case Kind::Since: {
      const auto& c = since_[op.slot].candidates;
      return (c.empty() && !b) || (a && covers_rest_of_time(c, now));
    }
    default: return true;  // connectives and unbounded latches are idempotent
  }
}

bool Monitor::frozen_value(const Op& op, uint8_t r) const {
  return (op.kind == Kind::HistoricallyAll && r == 0) || (op.kind == Kind::OnceAll && r == 1);
}

void Monitor::release(uint32_t first) {
  std::vector<uint32_t> todo{first};
  while (!todo.empty()) {
    const Op& op = ops_[todo.back()];
    todo.pop_back();
    const bool binary = op.kind == Kind::And || op.kind == Kind::Or || op.kind == Kind::Implies ||
                        op.kind == Kind::Since || op.kind == Kind::SinceAll;
    for (uint16_t s : {op.a, op.b}) {
      const uint32_t producer = op_of_slot_[s];
      // (A producer already skipped is a frozen latch: it released its operands then.)
      if (producer != kNoOp && --live_readers_[producer] == 0 && !skip_[producer]) {
        skip_[producer] = 1;
        todo.push_back(producer);
      }
      if (!binary) break;
    }
  }
}

void Monitor::mark_readers(uint16_t slot, std::vector<uint32_t>& roots) {
  for (uint32_t k = reader_begin_[slot], end = reader_begin_[slot + 1]; k < end; ++k)
    if (!skip_[readers_[k]]) mark(readers_[k]);
  for (uint32_t k = root_begin_[slot], end = root_begin_[slot + 1]; k < end; ++k) roots.push_back(roots_[k]);
}

void Monitor::prepare_changes() {
  prepared_ = true;
  uint32_t max_atom = 0;
  for (uint32_t id : atom_ids_) max_atom = std::max(max_atom, id + 1);
  slot_of_atom_.assign(max_atom, kNoSlot);
  for (size_t k = 0; k < atom_ids_.size(); ++k) slot_of_atom_[atom_ids_[k]] = atom_slots_[k];
  const size_t slots = value_.size();
  op_of_slot_.assign(slots, kNoOp);
  for (size_t i = 0; i < ops_.size(); ++i) op_of_slot_[ops_[i].out] = static_cast<uint32_t>(i);
  // Readers per slot, as compressed rows: count, prefix sums, fill.
  auto operands = [](const Op& op, auto&& f) {
    f(op.a);
    if (op.kind == Kind::And || op.kind == Kind::Or || op.kind == Kind::Implies || op.kind == Kind::Since ||
        op.kind == Kind::SinceAll)
      f(op.b);
  };
  reader_begin_.assign(slots + 1, 0);
  for (const Op& op : ops_) operands(op, [&](uint16_t s) { ++reader_begin_[s + 1]; });
  for (size_t s = 0; s < slots; ++s) reader_begin_[s + 1] += reader_begin_[s];
  readers_.assign(reader_begin_[slots], 0);
  {
    std::vector<uint32_t> fill(reader_begin_.begin(), reader_begin_.end() - 1);
    for (size_t i = 0; i < ops_.size(); ++i)
      operands(ops_[i], [&](uint16_t s) { readers_[fill[s]++] = static_cast<uint32_t>(i); });
  }
  root_begin_.assign(slots + 1, 0);
  for (const Property& p : properties_) ++root_begin_[p.root.slot + 1];
  for (size_t s = 0; s < slots; ++s) root_begin_[s + 1] += root_begin_[s];
  roots_.assign(root_begin_[slots], 0);
  {
    std::vector<uint32_t> fill(root_begin_.begin(), root_begin_.end() - 1);
    for (size_t k = 0; k < properties_.size(); ++k) roots_[fill[properties_[k].root.slot]++] = static_cast<uint32_t>(k);
  }
  live_readers_.assign(ops_.size(), 0);
  for (size_t i = 0; i < ops_.size(); ++i) {
    const uint16_t out = ops_[i].out;
    live_readers_[i] = (reader_begin_[out + 1] - reader_begin_[out]) + (root_begin_[out + 1] - root_begin_[out]);
  }
  skip_.assign(ops_.size(), 0);
  dirty_.assign((ops_.size() + 63) / 64, 0);
  dirty_words_.assign((dirty_.size() + 63) / 64, 0);
}

void Monitor::step_changed(const uint8_t* atoms, const uint32_t* changed, size_t n_changed,
                           std::vector<uint32_t>& roots) {
  if (!prepared_) prepare_changes();
  const Step now = now_;
  uint8_t* v = value_.data();
  if (now == 0) {  // everything is new: a plain step, then who stays busy
    step(atoms);
    for (uint32_t k = 0; k < properties_.size(); ++k) roots.push_back(k);
    busy_.clear();
    for (uint32_t i = 0; i < ops_.size(); ++i) {
      if (!quiet(ops_[i], v, now)) busy_.push_back(i);
      if (prune_dead_ && frozen_value(ops_[i], v[ops_[i].out]) && !skip_[i]) {
        skip_[i] = 1;
        release(i);
      }
    }
    stepped_ = ops_.size();
    return;
  }
  for (size_t k = 0; k < n_changed; ++k) {
    const uint32_t id = changed[k];
    if (id >= slot_of_atom_.size()) continue;
    const uint16_t slot = slot_of_atom_[id];
    if (slot == kNoSlot || v[slot] == atoms[id]) continue;
    v[slot] = atoms[id];
    mark_readers(slot, roots);
  }
  for (uint32_t i : busy_)
    if (!skip_[i]) mark(i);
  next_busy_.clear();
  size_t stepped = 0;
  // Ops in index order: an operator's readers come after it, so one pass
  // sees every change before the operators it reaches.
  for (size_t top = 0; top < dirty_words_.size(); ++top) {
    while (dirty_words_[top]) {
      const int bit = __builtin_ctzll(dirty_words_[top]);
      const size_t w = top * 64 + static_cast<size_t>(bit);
      while (dirty_[w]) {
        const uint32_t i = static_cast<uint32_t>(w * 64 + static_cast<size_t>(__builtin_ctzll(dirty_[w])));
        dirty_[w] &= dirty_[w] - 1;
        if (skip_[i]) continue;
        const Op& op = ops_[i];
        const uint8_t before = v[op.out];
        const uint8_t r = evaluate(op, v, now);
        ++stepped;
        if (!quiet(op, v, now)) next_busy_.push_back(i);
        if (r != before) mark_readers(op.out, roots);
        if (prune_dead_ && frozen_value(op, r)) {
          skip_[i] = 1;
          release(i);
        }
      }
      dirty_words_[top] &= ~(uint64_t{1} << bit);
    }
  }
  busy_.swap(next_busy_);
  stepped_ = stepped;
  now_ = now + 1;
}

}  // namespace rvc::engine::discrete
