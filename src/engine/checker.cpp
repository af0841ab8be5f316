#include "engine/checker.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "spec/exact_time.hpp"
#include "spec/parser.hpp"
#include "spec/pastify.hpp"
#include "spec/spec_error.hpp"

namespace rvc::engine {

Checker::Checker(TimeModel model, bool emit_all, VerdictCallback on_verdict)
    : model_(model), emit_all_(emit_all), on_verdict_(std::move(on_verdict)) {}

void Checker::enable_robustness() {
  if (!names_.empty()) throw std::logic_error("enable_robustness after add_property");
  robustness_ = true;
}

void Checker::enable_explain() {
  // A robustness value is decided by one sub-formula's value at one step, not
  // by the Boolean reasons the sentences give: refused rather than half-said.
  if (robustness_)
    throw std::invalid_argument("--explain explains true/false verdicts for now (not --robustness values)");
  explain_ = true;
  for (auto& m : data_) m.enable_explain();  // properties added before: name the values they meet
  for (auto& m : dense_data_) m.enable_explain();
}

namespace {
void in_nanoseconds(spec::Node& n);
}  // namespace

void Checker::add_property(const PropertySpec& property) {
  spec::ParseOptions options;
  options.dense = model_ == TimeModel::Dense;
  options.robustness = robustness_;
  spec::NodePtr ast = spec::parse(property.spec, options);
  if (nanoseconds_) in_nanoseconds(*ast);
  const double h = spec::horizon(*ast);
  if (nanoseconds_ && h > static_cast<double>(spec::kExactSpanNs))
    throw spec::SpecError("the future horizon is " + spec::seconds_text(static_cast<int64_t>(std::min(h, 9e18))) +
                              " s: dense time is exact to the nanosecond up to 9007199.254740992 s (2^53 ns, about "
                              "104 days), and a horizon must lie within it",
                          property.spec, 1);
  const bool future = spec::has_future(*ast);
  if (future) ast = pastified(*ast, h, property.spec);  // h may be 0: until[0:0]
  Program program = compile(*ast, atoms_, model_, property.spec, !future);  // a rewrite's texts: never shown
  if (program.has_data()) {
    if (robustness_)
      throw spec::SpecError("--robustness has no meaning for data references (exists/forall), as in Reelay",
                            property.spec, 1);
    if (model_ == TimeModel::Dense) {
      dense_data_.emplace_back(program, property.name, max_data_values_);
      if (explain_) dense_data_.back().enable_explain();
      where_.emplace_back(kData, static_cast<uint32_t>(dense_data_.size() - 1));
    } else {
      data_.emplace_back(program, property.name, max_data_values_);
      if (explain_) data_.back().enable_explain();
      where_.emplace_back(kData, static_cast<uint32_t>(data_.size() - 1));
    }
    add_name(property.name, h);
    return;
  }
  if (robustness_ && model_ == TimeModel::Dense) {
    robust_dense_.emplace_back(program);
    last_robustness_.push_back(std::numeric_limits<double>::quiet_NaN());
    add_name(property.name, h);
    return;
  }
  if (robustness_) {
    robust_.emplace_back(program);
    last_robustness_.push_back(std::numeric_limits<double>::quiet_NaN());
  }
  try {
    if (model_ == TimeModel::Discrete) {
      if (discrete_.empty() || !discrete_.back().add(program)) {
        discrete_.emplace_back();
        discrete_.back().add(program);  // alone in a new monitor: fits, or throws length_error
      }
      where_.emplace_back(static_cast<uint32_t>(discrete_.size() - 1),
                          static_cast<uint32_t>(discrete_.back().size() - 1));
    } else {
      dense_.emplace_back(program);
      where_.emplace_back(0, static_cast<uint32_t>(dense_.size() - 1));
    }
  } catch (const std::length_error& e) {  // the monitor's size limit: a spec problem, not a runtime failure
    throw spec::SpecError(std::string(e.what()) + "; split it into several properties", property.spec, 1);
  }
  add_name(property.name, h);
}

namespace {
// Dense monitors run in nanoseconds: the formula's bounds become the exact
// nanoseconds the parser read from their text.
void in_nanoseconds(spec::Node& n) {
  n.bounds.lo = n.bounds.lo_ns;
  n.bounds.hi = n.bounds.hi_ns;
  n.bounds.in_ns = true;
  if (n.left) in_nanoseconds(*n.left);
  if (n.right) in_nanoseconds(*n.right);
}
}  // namespace

namespace {
bool has_quantifier(const spec::Node& n) {
  if (n.op == spec::Op::Exists || n.op == spec::Op::Forall) return true;
  return (n.left && has_quantifier(*n.left)) || (n.right && has_quantifier(*n.right));
}
// The end-of-stream marker's field: no message has it (a control character
// starts it), so it is false until finish() sets it (spec/pastify.hpp).
constexpr const char* kEndMarkerField = "\x01rvc-end-of-stream";
}  // namespace

spec::NodePtr Checker::pastified(const spec::Node& ast, double h, const std::string& source) {
  if (explain_) throw spec::SpecError("--explain does not explain bounded-future properties yet", source, 1);
  if (has_quantifier(ast))
    throw spec::SpecError("bounded future (eventually, always, until, next) with exists/forall is not supported yet",
                          source, 1);
  // The end of a discrete stream settles a verdict per step of the horizon
  // (finish): bounded so that ending a run never takes minutes.
  constexpr double kMaxDiscreteHorizon = 1e7;
  if (model_ == TimeModel::Discrete && h > kMaxDiscreteHorizon)
    throw spec::SpecError("the future horizon is " + std::to_string(static_cast<uint64_t>(h)) +
                              " steps; discrete time allows up to 10000000 (the verdicts of the last horizon are "
                              "settled one step each at the end of the stream)",
                          source, 1);
  if (end_atom_ < 0) {
    spec::FieldTest end;
    end.path = {kEndMarkerField};
    end_atom_ = atoms_.intern(end);
  }
  return spec::pastify(ast, h, atoms_.tests()[static_cast<size_t>(end_atom_)], model_ == TimeModel::Dense, source);
}

void Checker::add_name(const std::string& name, double delay) {
  names_.push_back(name);
  last_.push_back(-1);
  delay_.push_back(delay);
  stash_.push_back(std::numeric_limits<double>::quiet_NaN());
  if (delay > 0) {
    delayed_.push_back(static_cast<uint32_t>(names_.size() - 1));
    if (delay > max_delay_) max_delay_ = delay;
  }
}

bool Checker::refer(size_t i, double& time, double& known, double value) {
  const double d = delay_[i];
  known = std::numeric_limits<double>::quiet_NaN();
  if (d > 0) {
    if (time < d) {  // about an instant before the start: dense time keeps it for the start
      if (model_ == TimeModel::Dense) stash_[i] = value;
      return false;
    }
    if (time > d && !std::isnan(stash_[i])) {  // the start's value held until this change
      const double v = stash_[i];
      stash_[i] = std::numeric_limits<double>::quiet_NaN();
      const double at = finished_ ? std::min(d, end_known_) : d;
      if (robustness_) emit_robust(i, 0, v, at);
      else emit(i, 0, v != 0, at, nullptr);
    }
    stash_[i] = std::numeric_limits<double>::quiet_NaN();
    known = finished_ ? std::min(time, end_known_) : time;  // settled: known when the stream ended
    time -= d;
    // Dense time in seconds (not the runtime's nanoseconds, which are exact):
    // 1.2 - 1 is 0.19999999999999996; a difference within rounding error of
    // a whole nanosecond is that nanosecond.
    if (model_ == TimeModel::Dense && !nanoseconds_) {
      const double ns = std::round(time * 1e9) / 1e9;
      if (std::abs(ns - time) <= 1e-12 * std::max(1.0, std::abs(time))) time = ns;
    }
  }
  return time < end_;
}

// Dense time: a start value no change followed, once the clock passed it.
void Checker::flush_stash() {
  for (uint32_t i : delayed_) {
    if (std::isnan(stash_[i]) || !(clock_ > delay_[i])) continue;
    const double v = stash_[i];
    stash_[i] = std::numeric_limits<double>::quiet_NaN();
    if (0 >= end_) continue;
    const double at = finished_ ? std::min(delay_[i], end_known_) : delay_[i];
    if (robustness_) emit_robust(i, 0, v, at);
    else emit(i, 0, v != 0, at, nullptr);
  }
}

void Checker::finish() {
  if (finished_ || delayed_.empty()) return;
  finished_ = true;
  const auto end = static_cast<size_t>(end_atom_);
  if (model_ == TimeModel::Discrete) {
    if (last_atoms_.empty() && last_margins_.empty()) return;  // no step: nothing pending
    end_ = static_cast<double>(robustness_ ? now_robust_ : now_discrete_);
    end_known_ = end_ - 1;
    const auto steps = static_cast<int64_t>(max_delay_);
    if (robustness_) {
      std::vector<double> margins = last_margins_;
      margins[end] = std::numeric_limits<double>::infinity();
      for (int64_t k = 0; k < steps; ++k) step_robust(margins.data());
    } else {
      std::vector<uint8_t> atoms = last_atoms_;
      atoms[end] = 1;
      for (int64_t k = 0; k < steps; ++k) step(atoms.data());
    }
    return;
  }
  // Dense time: the stream covers [0, clock). A tick at the clock (the end
  // tick of a recording) told the value at that instant too: it stays part
  // of the stream, and the windows are cut just after it, 1 ns later (times
  // are integer nanoseconds: nothing rounds away).
  const double cut = told_at_ == clock_ ? clock_ + (nanoseconds_ ? 1 : 1e-9 * std::max(1.0, std::abs(clock_))) : clock_;
  end_ = cut;
  end_known_ = clock_;
  // Up to and with clock + delay (cut + delay may round down to it).
  const double until = std::nextafter(cut + max_delay_, std::numeric_limits<double>::infinity());
  if (robustness_) {
    if (last_margins_.empty()) last_margins_.assign(atoms_.size(), -std::numeric_limits<double>::infinity());
    std::vector<double> margins = last_margins_;
    if (cut > clock_) step_robust(clock_, cut, margins.data());
    margins[end] = std::numeric_limits<double>::infinity();
    step_robust(cut, until, margins.data());
  } else {
    if (last_atoms_.empty()) last_atoms_.assign(atoms_.size(), 0);
    std::vector<uint8_t> atoms = last_atoms_;
    if (cut > clock_) step(clock_, cut, atoms.data());
    atoms[end] = 1;
    step(cut, until, atoms.data());
  }
}

void Checker::report(size_t property, double time, bool value, const std::vector<std::string>* explanation) {
  double known;
  if (!refer(property, time, known, value ? 1 : 0)) return;
  emit(property, time, value, known, explanation);
}

void Checker::emit(size_t property, double time, bool value, double known,
                   const std::vector<std::string>* explanation) {
  if (!emit_all_ && last_[property] == static_cast<int8_t>(value)) return;
  last_[property] = static_cast<int8_t>(value);
  if (!value) ++violations_;
  if (!on_verdict_) return;
  Verdict v = verdict(property, time, value, known);
  v.explanation = explanation;
  on_verdict_(v);
}

void Checker::report_discrete(size_t i, double now) {
  const discrete::Monitor& m = discrete_[where_[i].first];
  const bool value = m.value(where_[i].second);
  if (explain_ && !value && last_[i] != 0) {  // a violation starts: say why
    const std::vector<std::string> why = m.explain(where_[i].second);
    report(i, now, value, &why);
  } else {
    report(i, now, value);
  }
}

// The change-driven step (set_incremental): the same verdicts as the plain
// loop below, in the same order, from the properties whose root changed.
void Checker::step_changes(const uint8_t* atoms) {
  const double now = static_cast<double>(now_discrete_++);
  const size_t n = atoms_.size();
  changed_atoms_.clear();
  if (!started_) {
    started_ = true;
    previous_atoms_.assign(atoms, atoms + n);
    property_of_.assign(discrete_.size(), {});
    for (size_t i = 0; i < where_.size(); ++i) property_of_[where_[i].first].push_back(static_cast<uint32_t>(i));
    // A dead cone's slots go stale: --explain reads them, so it keeps them all.
    for (auto& m : discrete_) m.set_prune_dead(!explain_);
  } else {
    // 64 atoms at a time (a loop the compiler vectorizes), then eight: most
    // messages change few of them.
    uint8_t* prev = previous_atoms_.data();
    size_t i = 0;
    for (; i + 64 <= n; i += 64) {
      uint64_t any = 0;
      for (size_t j = 0; j < 64; j += 8) {
        uint64_t x, y;
        std::memcpy(&x, atoms + i + j, 8);
        std::memcpy(&y, prev + i + j, 8);
        any |= x ^ y;
      }
      if (any == 0) continue;
      for (size_t j = i; j < i + 64; ++j)
        if (atoms[j] != prev[j]) changed_atoms_.push_back(static_cast<uint32_t>(j)), prev[j] = atoms[j];
    }
    for (; i + 8 <= n; i += 8) {
      uint64_t x, y;
      std::memcpy(&x, atoms + i, 8);
      std::memcpy(&y, prev + i, 8);
      if (x == y) continue;
      for (size_t j = i; j < i + 8; ++j)
        if (atoms[j] != prev[j]) changed_atoms_.push_back(static_cast<uint32_t>(j));
      std::memcpy(prev + i, &x, 8);
    }
    for (; i < n; ++i)
      if (atoms[i] != prev[i]) changed_atoms_.push_back(static_cast<uint32_t>(i)), prev[i] = atoms[i];
  }
  changed_properties_.clear();
  for (size_t k = 0; k < discrete_.size(); ++k) {
    changed_roots_.clear();
    discrete_[k].step_changed(atoms, changed_atoms_.data(), changed_atoms_.size(), changed_roots_);
    for (uint32_t local : changed_roots_) changed_properties_.push_back(property_of_[k][local]);
  }
  if (emit_all_) {
    for (size_t i = 0; i < where_.size(); ++i) report_discrete(i, now);
    return;
  }
  // A delayed property's first verdict comes at its delay, changed or not.
  for (uint32_t i : delayed_)
    if (delay_[i] == now) changed_properties_.push_back(i);
  // Properties in their order, as the plain loop reports them.
  std::sort(changed_properties_.begin(), changed_properties_.end());
  for (uint32_t i : changed_properties_) report_discrete(i, now);
}

void Checker::step(const uint8_t* atoms, const uint32_t* bound) {
  if (where_.empty()) return;
  if (!delayed_.empty() && !finished_) last_atoms_.assign(atoms, atoms + atoms_.size());
  if (incremental_ && data_.empty()) {
    step_changes(atoms);
    return;
  }
  const double now = static_cast<double>(now_discrete_++);
  for (auto& m : discrete_) m.step(atoms);
  for (size_t i = 0; i < where_.size(); ++i) {
    if (where_[i].first == kData) {
      data::DiscreteMonitor& d = data_[where_[i].second];
      const bool value = d.step(atoms, bound);
      if (explain_ && !value && last_[i] != 0) {  // a violation starts: say why
        const std::vector<std::string> why = d.explain(&value_names_);
        report(i, now, value, &why);
      } else {
        report(i, now, value);
      }
      continue;
    }
    report_discrete(i, now);
  }
}

void Checker::step_robust(const double* margins) {
  const double now = static_cast<double>(now_robust_++);
  if (!delayed_.empty() && !finished_) last_margins_.assign(margins, margins + atoms_.size());
  for (size_t i = 0; i < robust_.size(); ++i) {
    const double r = robust_[i].step(margins);
    double time = now, known;
    if (!refer(i, time, known, r)) continue;
    // Condensed as Reelay condenses: a value equal to the last one is no change.
    if (!emit_all_ && r == last_robustness_[i]) continue;
    last_robustness_[i] = r;
    const bool holds = r > 0;  // 0 is not a margin: a false Boolean field is 0
    if (!holds) ++violations_;
    if (on_verdict_) on_verdict_(Verdict{names_[i], time, holds, true, r, nullptr, known});
  }
}

void Checker::report_robust(size_t i, double time, double r) {
  double known;
  if (!refer(i, time, known, r)) return;
  emit_robust(i, time, r, known);
}

void Checker::emit_robust(size_t i, double time, double r, double known) {
  if (r == last_robustness_[i]) return;  // changes only, as for Booleans in dense time (emit_all too)
  last_robustness_[i] = r;
  const bool holds = r > 0;
  if (!holds) ++violations_;
  if (!on_verdict_) return;
  Verdict v = verdict(i, time, holds, known);
  v.robust = true;
  v.robustness = r;
  on_verdict_(v);
}

Verdict Checker::verdict(size_t property, double time, bool value, double known) const {
  Verdict v{names_[property], time, value, false, 0, nullptr, known};
  if (!nanoseconds_) return v;
  // Engine nanoseconds from the origin back to the instant (spec/exact_time.hpp).
  v.exact = true;
  v.time_ns = origin_ns_ + static_cast<int64_t>(std::llround(time));
  v.time = static_cast<double>(v.time_ns) / 1e9;
  if (known == known) {
    v.known_ns = origin_ns_ + static_cast<int64_t>(std::llround(known));
    v.known_at = static_cast<double>(v.known_ns) / 1e9;
  }
  return v;
}

void Checker::step_robust(double begin, double end, const double* margins) {
  if (begin < clock_) begin = clock_;  // a tick went there already
  if (!(begin < end)) return;
  clock_ = end;
  if (!delayed_.empty() && !finished_) last_margins_.assign(margins, margins + atoms_.size());
  for (size_t i = 0; i < robust_dense_.size(); ++i)
    for (const robust::RealPiece& p : robust_dense_[i].step(begin, end, margins).pieces) report_robust(i, p.t, p.v);
  if (!delayed_.empty()) flush_stash();
}

void Checker::step(double begin, double end, const uint8_t* atoms, const uint32_t* bound) {
  if (begin < clock_) begin = clock_;  // a tick went there already
  if (explain_) explain::origin_ns = origin_ns_, explain::nanoseconds = nanoseconds_;  // its sentences name instants
  if (!(begin < end)) return;  // an empty segment has no value to report
  clock_ = end;
  if (!delayed_.empty() && !finished_) last_atoms_.assign(atoms, atoms + atoms_.size());
  const bool told = emit_all_ && begin == told_at_;  // a tick at begin reported its value: not twice
  for (size_t i = 0; i < where_.size(); ++i) {
    const auto [kind, k] = where_[i];
    const dense::Signal& s =
        kind == kData ? dense_data_[k].step(begin, end, atoms, bound) : dense_[k].step(begin, end, atoms);
    for (const dense::Piece& p : s.pieces) {
      if (told && p.t == begin) continue;
      if (explain_ && !p.v && last_[i] != 0) {  // a violation starts at p.t: say why, from this segment's signals
        const std::vector<std::string> why =
            kind == kData ? dense_data_[k].explain(p.t, &value_names_) : dense_[k].explain(p.t);
        report(i, p.t, p.v, &why);
      } else {
        report(i, p.t, p.v);
      }
    }
  }
  if (!delayed_.empty()) flush_stash();
}

bool Checker::value_at_clock(size_t i, const uint8_t* atoms, const uint32_t* bound) {
  const auto [kind, k] = where_[i];
  return kind == kData ? dense_data_[k].at(clock_, atoms, bound) : dense_[k].at(clock_, atoms);
}

void Checker::tick(double now, const uint8_t* atoms, const uint32_t* bound) {
  if (model_ != TimeModel::Dense || !(now >= clock_)) return;  // behind the clock (or NaN): nothing to do
  if (explain_) explain::origin_ns = origin_ns_, explain::nanoseconds = nanoseconds_;
  if (now > clock_) step(clock_, now, atoms, bound);
  if (!delayed_.empty() && !finished_) last_atoms_.assign(atoms, atoms + atoms_.size());
  clock_ = now;
  for (size_t i = 0; i < where_.size(); ++i) {
    const bool v = value_at_clock(i, atoms, bound);
    if (explain_ && !v && last_[i] != 0) {  // a violation starts at the tick: say why, from the values there
      const auto [kind, k] = where_[i];
      const std::vector<std::string> why =
          kind == kData ? dense_data_[k].explain_at(now, &value_names_) : dense_[k].explain_at(now);
      report(i, now, v, &why);
    } else {
      report(i, now, v);
    }
  }
  told_at_ = now;
}

void Checker::tick_robust(double now, const double* margins) {
  if (model_ != TimeModel::Dense || !(now >= clock_)) return;
  if (now > clock_) step_robust(clock_, now, margins);
  if (!delayed_.empty() && !finished_) last_margins_.assign(margins, margins + atoms_.size());
  clock_ = now;
  for (size_t i = 0; i < robust_dense_.size(); ++i) report_robust(i, now, robust_dense_[i].at(now, margins));
  told_at_ = now;
}

double Checker::next_deadline(const uint8_t* atoms, const uint32_t* bound) {
  constexpr double kNever = std::numeric_limits<double>::infinity();
  if (model_ != TimeModel::Dense) return kNever;  // discrete time has no clock: steps are messages
  double next = kNever;
  for (size_t i = 0; i < where_.size(); ++i) {
    const bool v = value_at_clock(i, atoms, bound);  // first: next_change reads what it computed
    // A delayed property's value before its delay is about no instant of the
    // stream: its first verdict (for 0) is due at the delay.
    if (clock_ < delay_[i]) next = std::min(next, delay_[i]);
    else if (emit_all_ ? told_at_ != clock_ : last_[i] != static_cast<int8_t>(v)) return clock_;  // not told yet
    const auto [kind, k] = where_[i];
    const double t = kind == kData ? dense_data_[k].next_change(clock_) : dense_[k].next_change(clock_);
    if (t < next) next = t;
  }
  return next;
}

double Checker::next_deadline_robust(const double* margins) {
  constexpr double kNever = std::numeric_limits<double>::infinity();
  if (model_ != TimeModel::Dense) return kNever;
  double next = kNever;
  for (size_t i = 0; i < robust_dense_.size(); ++i) {
    const double r = robust_dense_[i].at(clock_, margins);
    if (clock_ < delay_[i]) next = std::min(next, delay_[i]);  // as in next_deadline
    else if (!(r == last_robustness_[i])) return clock_;  // not told yet
    const double t = robust_dense_[i].next_change(clock_);
    if (t < next) next = t;
  }
  return next;
}

}  // namespace rvc::engine
