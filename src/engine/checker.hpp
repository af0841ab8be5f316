// A set of named properties checked together over one stream of messages.
// The properties share one atom table (so one decode per message) and one
// clock; each keeps its own monitor and reports verdicts through a callback:
// only changes by default (condensed, like Reelay), every step with emit_all.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "engine/atom_table.hpp"
#include "engine/data/dense_monitor.hpp"
#include "engine/data/discrete_monitor.hpp"
#include "engine/dense/monitor.hpp"
#include "engine/discrete/monitor.hpp"
#include "engine/explain.hpp"
#include "engine/program.hpp"
#include "engine/robust/dense_monitor.hpp"
#include "engine/robust/monitor.hpp"

namespace rvc::engine {

struct Verdict {
  const std::string& property;
  double time;  // step index in discrete time
  bool value;   // with robustness: robustness > 0
  bool robust = false;    // robustness semantics (--robustness): `robustness` is the verdict
  double robustness = 0;
  // --explain, at the start of a violation: why (Monitor::explain); else null.
  const std::vector<std::string>* explanation = nullptr;
  // Bounded future (issue 29): `time` is the instant the verdict is about and
  // known_at the instant it became known (time + the property's horizon;
  // docs/semantics.md, "Bounded future"). NaN for past-only properties,
  // whose verdicts are known at their own time.
  double known_at = std::numeric_limits<double>::quiet_NaN();
  // Dense time (exact): `time` and `known_at` in integer nanoseconds, the
  // origin added back (spec/exact_time.hpp) — what outputs print, exactly;
  // `time`/`known_at` above are the same instants as double seconds, for
  // consumers that only need a number (stores, the dashboard).
  bool exact = false;
  int64_t time_ns = 0;
  int64_t known_ns = 0;
};
using VerdictCallback = std::function<void(const Verdict&)>;

struct PropertySpec {
  std::string name;
  std::string spec;
};

class Checker {
 public:
  Checker(TimeModel model, bool emit_all, VerdictCallback on_verdict);

  // Robustness (quantitative) semantics instead of Boolean verdicts: call
  // before add_property; step_robust() then drives it.
  void enable_robustness();
  // --explain: each violation's verdict carries why (discrete and dense
  // time, data references too; not robustness values: throws
  // std::invalid_argument after enable_robustness).
  void enable_explain();
  // --explain with data references: names bound values by id (the decoder's
  // io::BoundValues) in the sentences; without it they are named by the
  // test and step that bound them.
  void set_value_names(explain::ValueNames names) { value_names_ = std::move(names); }
  bool robustness() const { return robustness_; }
  // Data references: the most distinct values one quantified variable may
  // take (--max-data-values); beyond, step() throws data::DataLimitError.
  void set_max_data_values(uint32_t n) { max_data_values_ = n; }
  bool has_data_references() const { return !data_.empty() || !dense_data_.empty(); }

  // Change-driven stepping (on by default): discrete Boolean properties
  // without data references step only the operators whose operands changed
  // (discrete::Monitor::step_changed), and only properties whose value may
  // have changed are looked at. Verdicts are the same either way; off
  // (--plain-eval) steps everything, to compare.
  void set_incremental(bool on) { incremental_ = on; }

  // Parses and compiles; throws spec::SpecError naming the column.
  void add_property(const PropertySpec& property);

  AtomTable& atoms() { return atoms_; }
  const AtomTable& atoms() const { return atoms_; }
  TimeModel model() const { return model_; }
  size_t size() const { return names_.size(); }
  const std::vector<std::string>& names() const { return names_; }

  // Discrete time: one step with the atoms' values after the message and,
  // for properties with data references, the bound values' ids (the
  // decoder's bound(); null when no test binds).
  void step(const uint8_t* atoms, const uint32_t* bound = nullptr);
  // Robustness, discrete time: one step with the atoms' margins.
  void step_robust(const double* margins);
  // Robustness, dense time: the atoms' margins held over [begin, end).
  void step_robust(double begin, double end, const double* margins);
  // Dense time: the atoms' values held over [begin, end).
  void step(double begin, double end, const uint8_t* atoms, const uint32_t* bound = nullptr);

  // ---- Clock-driven monitoring (dense time; docs/semantics.md, "Ticks") ----
  //
  // A tick is an empty message: every field holds its value. tick(now, ...)
  // closes [clock(), now) with the held values (verdict changes inside it are
  // reported at their exact times, however late the tick comes) and then
  // reports the value at `now` itself, which a message would only report
  // with the segment after it. Verdicts are those of the same trace with a
  // message repeating the last values at `now`; the next message (or tick)
  // goes on from `now`. Ticks and deadlines cost nothing until called.
  //
  // The instant the monitors have reached: the end of the last step or tick
  // (0 before any).
  double clock() const { return clock_; }
  // Dense time runs in nanoseconds from an origin (spec/exact_time.hpp):
  // every time given to step/tick and returned by clock/next_deadline is
  // (instant - origin) in ns, and verdicts carry the instant itself
  // (Verdict::time_ns, and `time` in seconds). Set before the first step.
  void set_origin(int64_t origin_ns) { origin_ns_ = origin_ns; }
  // The monitors themselves are unit-agnostic (times and bounds in one unit,
  // as Reelay's): by default the bounds as written and the times as given.
  // count_nanoseconds() (before add_property; the runtime calls it for dense
  // time) runs them on nanoseconds: bounds become the exact nanoseconds of
  // their text, and verdicts carry exact instants (Verdict::exact).
  void count_nanoseconds() { nanoseconds_ = model_ == TimeModel::Dense; }
  bool nanoseconds() const { return nanoseconds_; }
  int64_t origin() const { return origin_ns_; }
  // `atoms`/`bound`/`margins`: the values held since the last message (the
  // decoder's committed values, as the next step() will be given). A tick
  // before the clock does nothing; a tick at the clock only reports the
  // value there (right after a message: its own verdict, without waiting
  // for the next one). Throws data::DataLimitError as step() does.
  void tick(double now, const uint8_t* atoms, const uint32_t* bound = nullptr);
  void tick_robust(double now, const double* margins);
  // When to tick next: the first instant >= clock() at which some verdict
  // can change if the held values stay (the clock itself when the value
  // there has not been reported yet); +inf when none can. Never later than
  // the change; it may be earlier (a tick then reports nothing: ask again).
  // From the operators' windows, O(operators) per call (data references:
  // per table entry, as a step). The runtime calls it after every message
  // and tick it makes, and sleeps until then (or until the next message).
  double next_deadline(const uint8_t* atoms, const uint32_t* bound = nullptr);
  double next_deadline_robust(const double* margins);

  uint64_t violations() const { return violations_; }  // verdicts reported false

  // ---- Bounded future (issue 29; docs/semantics.md, "Bounded future") ----
  // A property with future operators is checked with a delay equal to its
  // horizon (spec/pastify.hpp): its verdict for t is reported when the
  // stream reaches t + horizon, with known_at set. 0 for past-only ones.
  double delay(size_t property) const { return delay_[property]; }
  double max_delay() const { return max_delay_; }
  // End of stream: settles the verdicts still pending (the last `horizon`
  // time units of each delayed property), with every future operator's
  // window cut at the end: eventually/until need a witness inside the
  // stream, always only the steps it has. Reports nothing past the end
  // (discrete: the last step; dense: the clock). Call once, after the last
  // step or tick; nothing to do without delayed properties.
  void finish();

 private:
  void report(size_t property, double time, bool value, const std::vector<std::string>* explanation = nullptr);
  // A delayed property's verdict at monitor time `time`: false when it is not
  // reported (it refers to before the start, or past the end while
  // settling); else `time` becomes the instant referred to and `known` the
  // instant it became known. Dense time keeps the last value before the
  // delay (`stash`) for the start, told when the first later change comes.
  bool refer(size_t property, double& time, double& known, double value);
  void emit(size_t property, double time, bool value, double known, const std::vector<std::string>* explanation);
  void emit_robust(size_t property, double time, double r, double known);
  void flush_stash();
  spec::NodePtr pastified(const spec::Node& ast, double horizon, const std::string& source);
  void add_name(const std::string& name, double delay);
  void report_robust(size_t property, double time, double robustness);
  // Each property's value at the clock, the held values (tick, next_deadline).
  bool value_at_clock(size_t property, const uint8_t* atoms, const uint32_t* bound);
  void step_changes(const uint8_t* atoms);
  void report_discrete(size_t property, double now);

  TimeModel model_;
  bool emit_all_;
  VerdictCallback on_verdict_;
  AtomTable atoms_;
  std::vector<std::string> names_;
  // Discrete time: all properties in shared monitors (common sub-formulas
  // stepped once), a new one when the last is full; property k is in
  // discrete_[where_[k].first] at index where_[k].second.
  std::vector<discrete::Monitor> discrete_;
  // where_[k].first == kData: property k has data references, in data_.
  std::vector<std::pair<uint32_t, uint32_t>> where_;
  static constexpr uint32_t kData = UINT32_MAX;
  std::vector<data::DiscreteMonitor> data_;
  std::vector<data::DenseMonitor> dense_data_;
  uint32_t max_data_values_ = 100000;
  std::vector<dense::Monitor> dense_;
  bool robustness_ = false;
  bool explain_ = false;
  explain::ValueNames value_names_;
  std::vector<robust::Monitor> robust_;
  std::vector<robust::DenseMonitor> robust_dense_;
  std::vector<double> last_robustness_;
  int64_t now_robust_ = 0;
  int64_t now_discrete_ = 0;
  double clock_ = 0;  // dense time: where the last step or tick ended
  int64_t origin_ns_ = 0;  // dense time: the instant engine time 0 stands for
  bool nanoseconds_ = false;
  Verdict verdict(size_t property, double time, bool value, double known) const;
  // Dense time: the instant a tick last reported the value at (NaN: none).
  // With emit_all, the step that starts there does not report it again.
  double told_at_ = std::numeric_limits<double>::quiet_NaN();
  std::vector<int8_t> last_;  // last reported value per property, -1 before the first
  // Change-driven stepping: the atoms of the previous step, the atoms that
  // differ now, the properties whose root changed, and per monitor its
  // properties' indices.
  bool incremental_ = true;
  bool started_ = false;
  std::vector<uint8_t> previous_atoms_;
  std::vector<uint32_t> changed_atoms_, changed_roots_, changed_properties_;
  std::vector<std::vector<uint32_t>> property_of_;
  uint64_t violations_ = 0;
  // Bounded future: per property its delay, and in dense time the value
  // waiting for the start (NaN: none); the atoms/margins of the last step
  // (kept only with a delayed property) for finish(); end_: no verdict
  // from there on (+inf until finish()).
  std::vector<double> delay_, stash_;
  std::vector<uint32_t> delayed_;  // properties with a delay
  double max_delay_ = 0;
  int end_atom_ = -1;
  double end_ = std::numeric_limits<double>::infinity();
  double end_known_ = std::numeric_limits<double>::infinity();  // finish(): the stream's last instant
  std::vector<uint8_t> last_atoms_;
  std::vector<double> last_margins_;
  bool finished_ = false;
};

}  // namespace rvc::engine
