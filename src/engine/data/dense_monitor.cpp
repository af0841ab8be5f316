#include "engine/data/dense_monitor.hpp"

#include "engine/data/walker.hpp"

namespace rvc::engine::data {

DenseMonitor::DenseMonitor(const Program& program, const std::string& property, uint32_t max_values)
    : program_(program), code_(program.code), bindings_(program, property, max_values), signal_(program.code.size()),
      state_(program.code.size(), -1) {
  const std::vector<Mask> mask = free_variables(program);
  const Domains& domains = bindings_.domains();
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    signal_[i].init(domains, mask[i], dense::Signal{});
    switch (in.code) {
      case Code::Once:
        state_[i] = static_cast<int32_t>(once_.size());
        once_.emplace_back().init(domains, mask[i], dense::Once{in.bounds.lo, in.bounds.hi, {}});
        break;
      case Code::Historically: {
        state_[i] = static_cast<int32_t>(historically_.size());
        dense::Historically h;
        h.violations.lo = in.bounds.lo;
        h.violations.hi = in.bounds.hi;
        historically_.emplace_back().init(domains, mask[i], h);
        break;
      }
      case Code::Since: {
        state_[i] = static_cast<int32_t>(since_.size());
        dense::Since s;
        s.lo = in.bounds.lo;
        s.hi = in.bounds.hi;
        s.right_suffices = !in.bounds.explicit_bounds;  // as Reelay's dense data monitors (since.hpp)
        since_.emplace_back().init(domains, mask[i], s);
        break;
      }
      default: break;
    }
  }
}

template <class F>
void DenseMonitor::each_table(F&& f) {
  for (auto& t : signal_) f(t);
  for (auto& t : once_) f(t);
  for (auto& t : historically_) f(t);
  for (auto& t : since_) f(t);
}

const dense::Signal& DenseMonitor::step(double begin, double end, const uint8_t* atoms, const uint32_t* bound) {
  bindings_.update(bound, [&](int var, uint32_t index, const Domains* before) {
    each_table([&](auto& table) { grow_table(table, bindings_.domains(), var, index, before); });
  }, begin);
  begin_ = begin;
  end_ = end;
  const Domains& domains = bindings_.domains();
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    Table<dense::Signal>& out = signal_[i];
    Table<dense::Signal>* a = in.a >= 0 ? &signal_[static_cast<size_t>(in.a)] : nullptr;
    Table<dense::Signal>* b = in.b >= 0 ? &signal_[static_cast<size_t>(in.b)] : nullptr;
    const auto binary = [&](auto&& f) {
      domains.for_each<3>(out.mask, {out.strides, a->strides, b->strides}, [&](const std::array<size_t, 3>& o) {
        dense::Signal& r = out.at(o[0]);
        r.clear();
        zip(a->at(o[1]), b->at(o[2]), [&](double t, bool l, bool rv) { r.set(t, f(l, rv)); });
      });
    };
    const auto temporal = [&](auto& states) {
      auto& s = states[static_cast<size_t>(state_[i])];
      domains.for_each<3>(out.mask, {out.strides, a->strides, s.strides}, [&](const std::array<size_t, 3>& o) {
        s.at(o[2]).update(a->at(o[1]), end, out.at(o[0]));
      });
    };
    switch (in.code) {
      case Code::True: out.at(0).constant(begin, true); break;
      case Code::False: out.at(0).constant(begin, false); break;
      case Code::Atom: out.at(0).constant(begin, atoms[in.atom] != 0); break;
      case Code::Bind:
        domains.for_each<1>(out.mask, {out.strides}, [&](const std::array<size_t, 1>& o) {
          out.at(o[0]).constant(begin, false);
        });
        if (const uint32_t k = bindings_.index(i)) out.at(k * out.strides.of[static_cast<size_t>(in.var)]).constant(begin, true);
        break;
      case Code::Not:
        domains.for_each<2>(out.mask, {out.strides, a->strides}, [&](const std::array<size_t, 2>& o) {
          dense::Signal& r = out.at(o[0]);
          r.clear();
          for (const dense::Piece& p : a->at(o[1]).pieces) r.set(p.t, !p.v);
        });
        break;
      case Code::And: binary([](bool l, bool r) { return l && r; }); break;
      case Code::Or: binary([](bool l, bool r) { return l || r; }); break;
      case Code::Implies: binary([](bool l, bool r) { return !l || r; }); break;
      case Code::Pre: out.at(0).constant(begin, false); break;  // refused by the compiler in dense time
      case Code::Once: temporal(once_); break;
      case Code::Historically: temporal(historically_); break;
      case Code::Since: {
        auto& s = since_[static_cast<size_t>(state_[i])];
        domains.for_each<4>(out.mask, {out.strides, a->strides, b->strides, s.strides},
                            [&](const std::array<size_t, 4>& o) {
                              s.at(o[3]).update(a->at(o[1]), b->at(o[2]), end, out.at(o[0]));
                            });
        break;
      }
      case Code::Exists:
      case Code::Forall: {
        const bool all = in.code == Code::Forall;
        domains.for_each<1>(out.mask, {out.strides}, [&](const std::array<size_t, 1>& o) {
          out.at(o[0]).constant(begin, all);
        });
        domains.for_each<2>(a->mask, {out.strides, a->strides}, [&](const std::array<size_t, 2>& o) {
          dense::Signal& r = out.at(o[0]);
          scratch_.clear();
          zip(r, a->at(o[1]), [&](double t, bool l, bool v) { scratch_.set(t, all ? (l && v) : (l || v)); });
          r.pieces.swap(scratch_.pieces);
        });
        break;
      }
    }
  }
  return signal_.back().at(0);
}

bool DenseMonitor::at(double now, const uint8_t* atoms, const uint32_t* bound) {
  bindings_.update(bound, [&](int var, uint32_t index, const Domains* before) {
    each_table([&](auto& table) { grow_table(table, bindings_.domains(), var, index, before); });
  }, now);
  const Domains& domains = bindings_.domains();
  at_.resize(code_.size());
  for (size_t i = 0; i < code_.size(); ++i) at_[i].init(domains, signal_[i].mask, 0);  // laid out as the signals
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    Table<uint8_t>& out = at_[i];
    const Table<uint8_t>* a = in.a >= 0 ? &at_[static_cast<size_t>(in.a)] : nullptr;
    const Table<uint8_t>* b = in.b >= 0 ? &at_[static_cast<size_t>(in.b)] : nullptr;
    const auto binary = [&](auto&& f) {
      domains.for_each<3>(out.mask, {out.strides, a->strides, b->strides}, [&](const std::array<size_t, 3>& o) {
        out.cells[o[0]] = f(a->cells[o[1]] != 0, b->cells[o[2]] != 0);
      });
    };
    const auto temporal = [&](const auto& states) {
      const auto& s = states[static_cast<size_t>(state_[i])];
      domains.for_each<3>(out.mask, {out.strides, a->strides, s.strides}, [&](const std::array<size_t, 3>& o) {
        out.cells[o[0]] = s.cells[o[2]].at(a->cells[o[1]] != 0, now);
      });
    };
    switch (in.code) {
      case Code::True: out.cells[0] = 1; break;
      case Code::Atom: out.cells[0] = atoms[in.atom] != 0; break;
      case Code::Bind:  // all 0 (init) but the value bound now
        if (const uint32_t k = bindings_.index(i)) out.cells[k * out.strides.of[static_cast<size_t>(in.var)]] = 1;
        break;
      case Code::Not:
        domains.for_each<2>(out.mask, {out.strides, a->strides}, [&](const std::array<size_t, 2>& o) {
          out.cells[o[0]] = !a->cells[o[1]];
        });
        break;
      case Code::And: binary([](bool l, bool r) { return l && r; }); break;
      case Code::Or: binary([](bool l, bool r) { return l || r; }); break;
      case Code::Implies: binary([](bool l, bool r) { return !l || r; }); break;
      case Code::Once: temporal(once_); break;
      case Code::Historically: temporal(historically_); break;
      case Code::Since: {
        const auto& s = since_[static_cast<size_t>(state_[i])];
        domains.for_each<4>(out.mask, {out.strides, a->strides, b->strides, s.strides},
                            [&](const std::array<size_t, 4>& o) {
                              out.cells[o[0]] = s.cells[o[3]].at(a->cells[o[1]] != 0, b->cells[o[2]] != 0, now);
                            });
        break;
      }
      case Code::Exists:
      case Code::Forall: {
        const bool all = in.code == Code::Forall;
        domains.for_each<1>(out.mask, {out.strides}, [&](const std::array<size_t, 1>& o) { out.cells[o[0]] = all; });
        domains.for_each<2>(a->mask, {out.strides, a->strides}, [&](const std::array<size_t, 2>& o) {
          const bool v = a->cells[o[1]] != 0;
          out.cells[o[0]] = all ? (out.cells[o[0]] && v) : (out.cells[o[0]] || v);
        });
        break;
      }
      default: break;  // False, Pre: false
    }
  }
  return at_.back().cells[0] != 0;
}

double DenseMonitor::next_change(double now) const {
  const Domains& domains = bindings_.domains();
  double next = dense::kNever;
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    if (in.code != Code::Once && in.code != Code::Historically && in.code != Code::Since) continue;
    const Table<uint8_t>& a = at_[static_cast<size_t>(in.a)];
    const Table<uint8_t>& b = at_[static_cast<size_t>(in.b >= 0 ? in.b : in.a)];
    const auto each = [&](const auto& states, auto&& change) {
      const auto& s = states[static_cast<size_t>(state_[i])];
      domains.for_each<3>(signal_[i].mask, {a.strides, b.strides, s.strides}, [&](const std::array<size_t, 3>& o) {
        const double t = change(s.cells[o[2]], a.cells[o[0]] != 0, b.cells[o[1]] != 0);
        if (t < next) next = t;
      });
    };
    if (in.code == Code::Once) each(once_, [&](const dense::Once& s, bool l, bool) { return s.next_change(l, now); });
    if (in.code == Code::Historically)
      each(historically_, [&](const dense::Historically& s, bool l, bool) { return s.next_change(l, now); });
    if (in.code == Code::Since)
      each(since_, [&](const dense::Since& s, bool l, bool r) { return s.next_change(l, r, now); });
  }
  return next;
}

namespace {

class DenseWalker : public DataWalker {
 public:
  DenseWalker(const Program& program, double t, double begin, double end, const Bindings& bindings,
              const std::vector<Table<dense::Signal>>& signal, const explain::ValueNames* names)
      : DataWalker(program, true, t, bindings, names), signal_(signal), t_(t), begin_(begin), end_(end) {}

 protected:
  bool value(size_t i) const override { return dense::value_at(signal_[i].cells[offset(signal_[i])], t_); }
  std::string held(size_t) const override {
    return "throughout [" + explain::seconds(begin_) + ", " + explain::seconds(end_) + ")";
  }

 private:
  const std::vector<Table<dense::Signal>>& signal_;
  double t_, begin_, end_;
};

// Each sub-formula's values at the clock (DenseMonitor::at), the atoms held.
class ClockWalker : public DataWalker {
 public:
  ClockWalker(const Program& program, double now, const Bindings& bindings, const std::vector<Table<uint8_t>>& at,
              const explain::ValueNames* names)
      : DataWalker(program, true, now, bindings, names), at_(at), now_(now) {}

 protected:
  bool value(size_t i) const override { return at_[i].cells[offset(at_[i])] != 0; }
  std::string held(size_t) const override {
    return "at time " + explain::seconds(now_) + " (held since the last message)";
  }

 private:
  const std::vector<Table<uint8_t>>& at_;
  double now_;
};

}  // namespace

std::vector<std::string> DenseMonitor::explain_at(double now, const explain::ValueNames* names) const {
  return ClockWalker(program_, now, bindings_, at_, names).run();
}

std::vector<std::string> DenseMonitor::explain(double t, const explain::ValueNames* names) const {
  return DenseWalker(program_, t, begin_, end_, bindings_, signal_, names).run();
}

}  // namespace rvc::engine::data
