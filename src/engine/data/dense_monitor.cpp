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

}  // namespace

std::vector<std::string> DenseMonitor::explain(double t, const explain::ValueNames* names) const {
  return DenseWalker(program_, t, begin_, end_, bindings_, signal_, names).run();
}

}  // namespace rvc::engine::data
