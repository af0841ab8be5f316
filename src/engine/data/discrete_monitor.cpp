#include "engine/data/discrete_monitor.hpp"

#include "engine/data/walker.hpp"

namespace rvc::engine::data {
namespace {

discrete::Step to_step(double v) {
  return v >= static_cast<double>(discrete::kForever) ? discrete::kForever : static_cast<discrete::Step>(v);
}

}  // namespace

DiscreteMonitor::DiscreteMonitor(const Program& program, const std::string& property, uint32_t max_values)
    : program_(program),
      code_(program.code),
      bindings_(program, property, max_values),
      value_(program.code.size()),
      set_(program.code.size(), 0),
      state_(program.code.size(), -1) {
  const std::vector<Mask> mask = free_variables(program);
  const Domains& domains = bindings_.domains();
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    value_[i].init(domains, mask[i], 0);
    const discrete::Step lo = to_step(in.bounds.lo), hi = to_step(in.bounds.hi);
    switch (in.code) {
      case Code::Pre:
        state_[i] = static_cast<int32_t>(pre_.size());
        pre_.emplace_back().init(domains, mask[i], discrete::Pre{});
        break;
      case Code::Once:
        state_[i] = static_cast<int32_t>(once_.size());
        once_.emplace_back().init(domains, mask[i], discrete::Once{lo, hi, {}});
        break;
      case Code::Historically:
        state_[i] = static_cast<int32_t>(historically_.size());
        historically_.emplace_back().init(domains, mask[i], discrete::Historically{discrete::Once{lo, hi, {}}});
        break;
      case Code::Since:
        state_[i] = static_cast<int32_t>(since_.size());
        since_.emplace_back().init(domains, mask[i], discrete::Since{lo, hi, {}});
        break;
      default: break;
    }
  }
}

template <class F>
void DiscreteMonitor::each_table(F&& f) {
  for (auto& t : value_) f(t);
  for (auto& t : pre_) f(t);
  for (auto& t : once_) f(t);
  for (auto& t : historically_) f(t);
  for (auto& t : since_) f(t);
}

bool DiscreteMonitor::step(const uint8_t* atoms, const uint32_t* bound) {
  // Values met for the first time get their entries before the step,
  // copied from "any other value" as it was after the previous step.
  bindings_.update(bound, [&](int var, uint32_t index, const Domains* before) {
    each_table([&](auto& table) { grow_table(table, bindings_.domains(), var, index, before); });
  }, static_cast<double>(now_));
  const Domains& domains = bindings_.domains();
  const discrete::Step now = now_;
  for (size_t i = 0; i < code_.size(); ++i) {
    const Instr& in = code_[i];
    Table<uint8_t>& out = value_[i];
    const Table<uint8_t>* a = in.a >= 0 ? &value_[static_cast<size_t>(in.a)] : nullptr;
    const Table<uint8_t>* b = in.b >= 0 ? &value_[static_cast<size_t>(in.b)] : nullptr;
    uint8_t* r = out.cells.data();
    const auto unary = [&](auto&& f) {
      domains.for_each<2>(out.mask, {out.strides, a->strides}, [&](const std::array<size_t, 2>& o) {
        r[o[0]] = f(a->cells[o[1]]);
      });
    };
    const auto binary = [&](auto&& f) {
      domains.for_each<3>(out.mask, {out.strides, a->strides, b->strides}, [&](const std::array<size_t, 3>& o) {
        r[o[0]] = f(a->cells[o[1]], b->cells[o[2]]);
      });
    };
    // A temporal operator's state table has the node's own layout.
    const auto temporal = [&](auto& states, auto&& f) {
      auto& s = states[static_cast<size_t>(state_[i])];
      domains.for_each<3>(out.mask, {out.strides, a->strides, s.strides}, [&](const std::array<size_t, 3>& o) {
        r[o[0]] = f(s.cells[o[2]], a->cells[o[1]]);
      });
    };
    switch (in.code) {
      case Code::True: r[0] = 1; break;
      case Code::False: r[0] = 0; break;
      case Code::Atom: r[0] = atoms[in.atom] != 0; break;
      case Code::Bind: {  // one entry true at most: move it (O(1), not a pass over the table)
        const size_t stride = out.strides.of[static_cast<size_t>(in.var)];
        const uint32_t k = bindings_.index(i);
        if (set_[i] != k) {
          if (set_[i]) r[set_[i] * stride] = 0;
          if (k) r[k * stride] = 1;
          set_[i] = k;
        }
        break;
      }
      case Code::Not: unary([](uint8_t x) { return static_cast<uint8_t>(!x); }); break;
      case Code::And: binary([](uint8_t x, uint8_t y) { return static_cast<uint8_t>(x & y); }); break;
      case Code::Or: binary([](uint8_t x, uint8_t y) { return static_cast<uint8_t>(x | y); }); break;
      case Code::Implies: binary([](uint8_t x, uint8_t y) { return static_cast<uint8_t>((x ^ 1) | y); }); break;
      case Code::Pre: temporal(pre_, [](discrete::Pre& s, uint8_t x) { return s.update(x); }); break;
      case Code::Once: temporal(once_, [now](discrete::Once& s, uint8_t x) { return s.update(now, x); }); break;
      case Code::Historically:
        temporal(historically_, [now](discrete::Historically& s, uint8_t x) { return s.update(now, x); });
        break;
      case Code::Since: {
        auto& s = since_[static_cast<size_t>(state_[i])];
        domains.for_each<4>(out.mask, {out.strides, a->strides, b->strides, s.strides},
                             [&](const std::array<size_t, 4>& o) {
                               r[o[0]] = s.cells[o[3]].update(now, a->cells[o[1]], b->cells[o[2]]);
                             });
        break;
      }
      case Code::Exists:
      case Code::Forall: {
        const uint8_t unit = in.code == Code::Forall;  // the empty disjunction / conjunction
        domains.for_each<1>(out.mask, {out.strides}, [&](const std::array<size_t, 1>& o) { r[o[0]] = unit; });
        // Over a's variables: out has no stride for the quantified one, so
        // all its values fold into one entry.
        domains.for_each<2>(a->mask, {out.strides, a->strides}, [&](const std::array<size_t, 2>& o) {
          r[o[0]] = unit ? (r[o[0]] & a->cells[o[1]]) : (r[o[0]] | a->cells[o[1]]);
        });
        break;
      }
    }
  }
  now_ = now + 1;
  return value_.back().cells[0] != 0;
}

size_t DiscreteMonitor::entries() const {
  size_t n = 0;
  for (const auto& t : value_) n += bindings_.domains().live(t.mask);
  return n;
}

namespace {

class DiscreteWalker : public DataWalker {
 public:
  DiscreteWalker(const Program& program, discrete::Step now, const Bindings& bindings,
                 const std::vector<Table<uint8_t>>& value, const explain::ValueNames* names)
      : DataWalker(program, false, static_cast<double>(now), bindings, names), value_(value), now_(now) {}

 protected:
  bool value(size_t i) const override { return value_[i].cells[offset(value_[i])] != 0; }
  std::string held(size_t) const override { return "at step " + std::to_string(now_); }

 private:
  const std::vector<Table<uint8_t>>& value_;
  discrete::Step now_;
};

}  // namespace

std::vector<std::string> DiscreteMonitor::explain(const explain::ValueNames* names) const {
  return DiscreteWalker(program_, now_ - 1, bindings_, value_, names).run();
}

}  // namespace rvc::engine::data
