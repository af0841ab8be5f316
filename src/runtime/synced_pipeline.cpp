#include "runtime/synced_pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <set>
#include <stdexcept>

#include "io/cdr_codec.hpp"
#include "io/cdr_decoder.hpp"
#include "runtime/typed_specs.hpp"
#include "spec/parser.hpp"
#include "spec/spec_error.hpp"

namespace rvc::runtime {

// One input: its own tests (the global ones without the "name." prefix), its
// own decoder, and where each of its tests sits in the checker's table.
struct SyncedPipeline::Input {
  SyncInput spec;
  bool arrival_stamp = false;
  std::unique_ptr<engine::AtomTable> atoms = std::make_unique<engine::AtomTable>();
  std::unique_ptr<Pipeline> pipeline;
  std::vector<std::pair<int, int>> slots;  // (checker atom id, this input's atom id)
  InputCounters counters;
  std::string last_text;  // its latest set member as JSON (rvc sync)
  // Ordered inputs (SyncOptions::ordered): its next message, decoded and
  // waiting for the merge by stamp; whether it has ended; its last stamp.
  bool has_pending = false, ended = false, any_stamp = false;
  bool excluded = false;  // the merge no longer waits for it (silent, or ended)
  sync::Member pending;
  double last_stamp = 0;
  std::string position_name;  // "input gear line", "input gear seq": names its messages
  std::string pipeline_position(uint64_t position) const { return position_name + " " + std::to_string(position); }
};

// A message between arrival and release.
struct SyncedPipeline::Held {
  uint32_t input = 0;
  bool used = false;
  double stamp = 0;       // its own stamp (a late message checked with --late process goes out later)
  int64_t stamp_ns = 0;   // ... exactly (dense time)
  uint64_t position = 0;  // its line or sequence number, for messages about it
  double arrival = 0;     // when rvc received it ({input.@latency})
  std::vector<uint8_t> values;  // in the input's atom order
  std::vector<double> margins;  // likewise, when field aggregates read them
  std::string text;             // as JSON, only when sets are published
};

namespace {

constexpr uint64_t kLateShown = 10;  // late messages named one by one; the rest are counted

std::string stamp_text(double stamp) {
  std::string s;
  io::append_number(s, stamp);
  return s;
}

double wall_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

bool is_identifier(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return true;
}

std::string names_of(const std::vector<SyncInput>& inputs) {
  std::string s;
  for (const auto& i : inputs) s += (s.empty() ? "" : ", ") + i.name;
  return s;
}

// Every field a property tests must start with an input's name and go on
// into that input's message: caught here with the test's column, not as a
// field that is silently never present.
void check_paths(const std::vector<engine::PropertySpec>& properties, const std::vector<SyncInput>& inputs,
                 bool dense) {
  spec::ParseOptions options;
  options.dense = dense;
  for (const auto& p : properties) {
    spec::NodePtr ast = spec::parse(p.spec, options);
    std::function<void(const spec::Node&)> walk = [&](const spec::Node& n) {
      if (n.op == spec::Op::Test && n.test.is_timed() && n.test.timed.kind != spec::Timed::Kind::Aggregate &&
          n.test.path.size() == 1)
        throw spec::SpecError("in property '" + p.name + "': with several inputs, say whose " + n.test.path[0] +
                                  " it is: {input." + n.test.path[0] + " ...} (inputs: " + names_of(inputs) + ")",
                              p.spec, n.test.column);
      if (n.op == spec::Op::Test && n.test.is_expr()) {  // each field of an expression names its input
        std::vector<const spec::Expr*> fields;
        spec::expr_fields(*n.test.lhs, fields);
        spec::expr_fields(*n.test.rhs, fields);
        for (const spec::Expr* f : fields) {
          bool known = false;
          for (const auto& i : inputs) known = known || f->path[0] == i.name;
          if (known && f->path.size() > 1) continue;
          spec::FieldTest named;
          named.path = f->path;
          throw spec::SpecError("in property '" + p.name + "': field '" + named.key() +
                                    "' names no input's field; with several inputs a field is input.field (inputs: " +
                                    names_of(inputs) + ")",
                                p.spec, f->column);
        }
      } else if (n.op == spec::Op::Test) {
        const auto& path = n.test.path;
        bool known = false;
        for (const auto& i : inputs) known = known || path[0] == i.name;
        if (!known)
          throw spec::SpecError("in property '" + p.name + "': field '" + n.test.key() +
                                    "' names no input; with several inputs a field is input.field (inputs: " +
                                    names_of(inputs) + ")",
                                p.spec, n.test.column);
        if (path.size() < 2)
          throw spec::SpecError("in property '" + p.name + "': '" + path[0] +
                                    "' is an input; test one of its fields ({" + path[0] + ".field})",
                                p.spec, n.test.column);
      }
      if (n.left) walk(*n.left);
      if (n.right) walk(*n.right);
    };
    walk(*ast);
  }
}

bool has_field(const msg::MessageType& type, const std::string& name) {
  for (const auto& f : type.fields)
    if (f.name == name) return true;
  return false;
}

}  // namespace

SyncedPipeline::SyncedPipeline(const std::vector<engine::PropertySpec>& properties, const PipelineOptions& options,
                               std::vector<SyncInput> inputs, const SyncOptions& sync,
                               engine::VerdictCallback on_verdict, SetCallback on_set)
    : checker_(options.model, options.emit_all, std::move(on_verdict)),
      options_(options),
      sync_(sync),
      on_set_(std::move(on_set)) {
  checker_.set_incremental(options.incremental);
  checker_.count_nanoseconds();  // dense time: exact nanoseconds (runtime/engine_time.hpp)
  time_ = EngineTime(options.origin);
  if (inputs.empty()) throw std::invalid_argument("no inputs to synchronize");
  if (options.robustness)
    throw std::invalid_argument("--robustness checks one input for now (not several synchronized ones)");
  std::set<std::string> seen;
  for (const auto& i : inputs) {
    if (!is_identifier(i.name))
      throw std::invalid_argument("input name '" + i.name + "' is not a name (letters, digits, _): NAME=URI");
    if (i.name == "time")
      throw std::invalid_argument("input name 'time' is taken: a set's stamp is its \"time\" field");
    if (!seen.insert(i.name).second) throw std::invalid_argument("two inputs are named '" + i.name + "'");
  }
  const bool dense = options.model == engine::TimeModel::Dense;
  if (options.explain) checker_.enable_explain();  // before the properties, as Pipeline does
  for (const auto& p : properties) {
    try {
      checker_.add_property(p);
    } catch (const spec::SpecError& e) {
      throw spec::SpecError("in property '" + p.name + "': " + e.message(), e.source(), e.column());
    }
  }
  if (checker_.has_data_references())
    throw std::invalid_argument("data references (exists/forall) check one input for now (not several synchronized ones)");
  check_paths(properties, inputs, dense);
  bool timed = false;
  for (const auto& t : checker_.atoms().tests()) timed = timed || t.is_timed();
  if (timed) {  // before the inputs' tables: field aggregates add tests
    std::vector<std::string> names;
    for (const auto& i : inputs) names.push_back(i.name);
    timed_ = std::make_unique<engine::timed::TimedAtoms>(checker_.atoms(), names, options.model);
  }

  inputs_.resize(inputs.size());
  for (size_t k = 0; k < inputs.size(); ++k) {
    Input& in = inputs_[k];
    in.spec = std::move(inputs[k]);
    // The input's tests, as its decoder sees them.
    const auto& tests = checker_.atoms().tests();
    for (size_t id = 0; id < tests.size(); ++id) {
      if (tests[id].is_timed() || tests[id].path[0] != in.spec.name) continue;
      spec::FieldTest local = tests[id];
      local.path.erase(local.path.begin());
      in.slots.emplace_back(static_cast<int>(id), in.atoms->intern(local));
    }
    // Its stamp.
    std::string stamp = in.spec.stamp;
    if (stamp.empty()) {
      if (in.spec.type) {
        stamp = io::CdrDecoder::default_time_field(*in.spec.type, "time");
        if (stamp == "time" && !has_field(*in.spec.type, "time")) stamp = "arrival";
      } else {
        stamp = options.time_field;
      }
    }
    in.arrival_stamp = stamp == "arrival";
    PipelineOptions po = options;
    po.model = in.arrival_stamp ? engine::TimeModel::Discrete : engine::TimeModel::Dense;
    po.time_field = in.arrival_stamp ? "time" : stamp;
    po.type = in.spec.type;
    po.position_name = "input " + in.spec.name + " " + options.position_name;
    in.position_name = po.position_name;
    po.input_name = in.spec.name;
    po.robustness = timed_ && timed_->needs_field_values();  // margins: the fields' values
    if (in.spec.type) bind_message_type(*in.atoms, properties, *in.spec.type, dense, po.time_field, in.spec.name);
    const auto input = static_cast<uint32_t>(k);
    in.pipeline = std::make_unique<Pipeline>(
        *in.atoms, po, [this, input](const uint8_t* values, double time, uint64_t position) {
          accept(input, values, time, position);
        });
  }
  combined_.assign(checker_.atoms().size(), 0);
  if (timed_) {
    combined_margins_.assign(checker_.atoms().size(), -std::numeric_limits<double>::infinity());
    timed_->write(combined_.data());
  }
  sync::PolicyOptions po = sync.policy_options;
  po.inputs = inputs_.size();
  policy_ = sync::make_policy(sync.policy, po, *this);
}

SyncedPipeline::~SyncedPipeline() = default;

size_t SyncedPipeline::inputs() const { return inputs_.size(); }

const SyncedPipeline::InputCounters& SyncedPipeline::counters(size_t input) const { return inputs_[input].counters; }

void SyncedPipeline::report(const std::string& text) {
  if (reported_++ < options_.max_reported) std::fprintf(stderr, "rvc: %s\n", text.c_str());
}

void SyncedPipeline::feed_input(uint32_t input, std::string_view payload, uint64_t position) {
  feed_at(input, payload, position, wall_now());
}

void SyncedPipeline::feed_at(uint32_t input, std::string_view payload, uint64_t position, double arrival) {
  Input& in = inputs_[input];
  feeding_ = input;
  arrival_ = arrival;
  if (first_arrival_ == 0) first_arrival_ = arrival;
  in.counters.last_arrival = arrival;
  // A batch of JSON lines is several messages: each is decoded (and kept as
  // text) on its own, so a set's JSON holds one message per input.
  if (!in.spec.type && payload.find('\n') != std::string_view::npos) {
    size_t begin = 0;
    while (begin < payload.size()) {
      size_t end = payload.find('\n', begin);
      if (end == std::string_view::npos) end = payload.size();
      std::string_view line = payload.substr(begin, end - begin);
      begin = end + 1;
      if (line.find_first_not_of(" \t\r") == std::string_view::npos) continue;
      ++in.counters.received;
      message_ = line;
      in.pipeline->feed(line, position);
    }
  } else {
    ++in.counters.received;
    message_ = payload;
    in.pipeline->feed(payload, position);
  }
  if ((in.counters.received & 1023) == 0) check_health(arrival);
}

// A message the input's decoder accepted: held under a token until the
// policy releases it.
void SyncedPipeline::accept(uint32_t input, const uint8_t* values, double time, uint64_t position) {
  Input& in = inputs_[input];
  const double stamp = in.arrival_stamp ? arrival_ : time;
  if (sync_.ordered) {
    // Files are merged by stamp, so each must be in stamp order: a stamp that
    // goes back is this line's fault, and refused here with its line.
    if (in.any_stamp && stamp < in.last_stamp) {
      ++in.counters.out_of_order;
      report(in.pipeline_position(position) + ": stamp " + stamp_text(stamp) +
             " is before the previous message's " + stamp_text(in.last_stamp) +
             " (several files are merged by stamp: each must be in stamp order); message skipped");
      return;
    }
    in.any_stamp = true;
    in.last_stamp = stamp;
  }
  uint32_t token;
  if (free_.empty()) {
    token = static_cast<uint32_t>(held_.size());
    held_.emplace_back();
  } else {
    token = free_.back();
    free_.pop_back();
  }
  Held& h = held_[token];
  h.input = input;
  h.used = false;
  h.stamp = stamp;
  h.stamp_ns = in.arrival_stamp ? std::llround(stamp * 1e9) : in.pipeline->message_time_ns();
  h.position = position;
  h.arrival = arrival_;
  h.values.assign(values, values + in.atoms->size());
  if (timed_ && timed_->needs_field_values())
    h.margins.assign(in.pipeline->committed_margins(), in.pipeline->committed_margins() + in.atoms->size());
  h.text.clear();
  if (on_set_) {
    if (in.spec.type) {
      io::CdrError error;
      io::cdr_to_json(*in.spec.type, message_, h.text, error);  // the decoder accepted it: it converts
    } else {
      h.text.assign(message_.data(), message_.size());
    }
  }
  ++in.counters.decoded;
  if (in.excluded && !in.ended) {  // back after a silence: the merge waits for it again
    in.excluded = false;
    in.counters.reported_dead = false;  // a second silence is reported again
    policy_->exclude(input, false);
  }
  const sync::Member member{input, stamp, token};
  if (sync_.ordered) {
    in.pending = member;
    in.has_pending = true;
    return;
  }
  policy_->add(member);
}

// The k-way merge of ordered inputs: while every input that has not ended
// has its next message decoded, the earliest of those goes to the policy
// (ties: the lower input); otherwise the first input without one is read.
int SyncedPipeline::next_input() {
  for (;;) {
    int earliest = -1;
    for (size_t i = 0; i < inputs_.size(); ++i) {
      const Input& in = inputs_[i];
      if (!in.ended && !in.has_pending) return static_cast<int>(i);
      if (in.has_pending && (earliest < 0 || in.pending.stamp < inputs_[earliest].pending.stamp))
        earliest = static_cast<int>(i);
    }
    if (earliest < 0) return -1;
    inputs_[earliest].has_pending = false;
    policy_->add(inputs_[earliest].pending);
  }
}

void SyncedPipeline::input_ended(uint32_t input) {
  if (input >= inputs_.size()) return;
  inputs_[input].ended = true;
  inputs_[input].excluded = true;  // nothing more will come: do not wait for it
  policy_->exclude(input, true);
}

uint64_t SyncedPipeline::received() const {
  uint64_t n = 0;
  for (const Input& in : inputs_) n += in.counters.received;
  return n;
}

void SyncedPipeline::add_dropped(io::JsonObject& out) const {
  for (size_t r = 0; r < sync::kReleaseKinds; ++r) {
    if (r == static_cast<size_t>(sync::Release::Used)) continue;
    uint64_t n = 0;
    for (const Input& in : inputs_) n += in.counters.released[r];
    if (n) out.add(sync::to_string(static_cast<sync::Release>(r)), n);
  }
}

// Late messages: the first few named with their input, position and stamp,
// all counted, and a summary at the end (finish_report).
void SyncedPipeline::report_late(const sync::Member& message, double after, bool checked, bool replaced) {
  const Held& h = held_[message.token];
  if (late_reported_++ >= std::min<uint64_t>(options_.max_reported, kLateShown)) return;
  if (replaced) {
    std::fprintf(stderr,
                 "rvc: warning: %s: stamp %s: dropped, replaced by the input's next message with the same stamp (merge "
                 "keeps one message per input and stamp)\n",
                 inputs_[message.input].pipeline_position(h.position).c_str(), stamp_text(h.stamp).c_str());
    return;
  }
  std::fprintf(stderr, "rvc: warning: %s: stamp %s came after the event at %s was checked: %s\n",
               inputs_[message.input].pipeline_position(h.position).c_str(), stamp_text(h.stamp).c_str(),
               stamp_text(after).c_str(),
               checked ? "checked late, as the next event (--late process)"
                       : "dropped as late (--late process checks such messages; --max-delay S waits longer)");
}

void SyncedPipeline::on_set(const sync::Member* members, size_t count, double set_stamp) {
  // The set's instant exactly: the stamp of the member it is (every policy
  // stamps a set with one of its members' stamps).
  int64_t set_ns = std::llround(set_stamp * 1e9);
  for (size_t m = 0; m < count; ++m)
    if (held_[members[m].token].stamp == set_stamp) set_ns = held_[members[m].token].stamp_ns;
  if (options_.model == engine::TimeModel::Dense && !time_.started()) {
    time_.start(set_ns);
    checker_.set_origin(time_.origin_ns());
  }
  const double set_engine = time_.engine(set_ns);
  if (options_.model == engine::TimeModel::Dense) {
    // Dense time needs strictly increasing times; every policy but latest
    // guarantees it, latest follows its pivot input's own order.
    if (has_time_ && !(set_stamp > last_time_)) {
      ++sets_rejected_;
      report("set at time " + std::to_string(set_stamp) + " is not after the previous set's time " +
             std::to_string(last_time_) + " (dense time needs strictly increasing times; set skipped)");
      return;
    }
    if (has_time_ && set_engine <= checker_.clock() && checker_.clock() > last_engine_ && late_to_clock_++ == 0)
      std::fprintf(stderr,
                   "rvc: warning: set at time %s is not after %s, where the clock's ticks had taken the monitors: "
                   "checked as if at that instant (counted as late_to_clock; warned once)\n",
                   stamp_text(set_stamp).c_str(), stamp_text(time_.seconds(checker_.clock())).c_str());
    // The set closes [previous time, its time) with the previous values,
    // stepping first through the instants where timed atoms change (those
    // a tick has already passed were stepped through by it).
    double begin = has_time_ ? last_engine_ : 0;
    if (!options_.parse_only) {
      for (double c; (c = timed_next_change()) < set_engine; begin = c) {
        checker_.step(begin, c, held_values());
        advance_timed(c);
      }
      checker_.step(begin, set_engine, held_values());
    }
  }
  if (timed_) timed_->advance(options_.model == engine::TimeModel::Dense ? set_engine : static_cast<double>(sets_));
  for (size_t m = 0; m < count; ++m) {
    Held& h = held_[members[m].token];
    Input& in = inputs_[members[m].input];
    if (sync_.policy == sync::PolicyKind::Merge && h.stamp < set_stamp) {  // late, checked (--late process)
      ++in.counters.late_checked;
      ++late_checked_;
      report_late(members[m], has_time_ ? last_time_ : set_stamp, true, false);
    }
    for (const auto& [global, local] : in.slots) combined_[global] = h.values[local];
    if (!h.margins.empty())
      for (const auto& [global, local] : in.slots) combined_margins_[global] = h.margins[local];
    if (!h.used) {
      h.used = true;
      ++in.counters.used;
      // Its first set: the input arrives ({in.@arrived}, its age restarts, a sample).
      if (timed_)
        timed_->arrive(members[m].input,
                       in.arrival_stamp ? 0
                       : options_.model == engine::TimeModel::Dense ? std::round((h.arrival - h.stamp) * 1e9)
                                                                     : h.arrival - h.stamp,
                       combined_.data(),
                       combined_margins_.empty() ? nullptr : combined_margins_.data());
    }
    if (on_set_) in.last_text = h.text;
  }
  if (options_.model == engine::TimeModel::Discrete && !options_.parse_only) checker_.step(held_values());
  has_time_ = true;
  last_time_ = set_stamp;
  last_engine_ = set_engine;
  ++sets_;
  if (on_set_) {
    io::JsonObject set;
    if (options_.model == engine::TimeModel::Dense) set.add_raw("time", spec::seconds_text(set_ns));  // exactly
    else set.add("time", set_stamp);
    for (const Input& in : inputs_)
      if (!in.last_text.empty()) set.add_raw(in.spec.name, in.last_text);
    json_ = set.str();
    on_set_(json_, set_stamp);
  }
}

void SyncedPipeline::advance_timed(double t) {
  if (timed_) timed_->advance(t);
}

const uint8_t* SyncedPipeline::held_values() {
  if (timed_) timed_->write(combined_.data());  // the timed atoms' own slots: no input writes them
  return combined_.data();
}

void SyncedPipeline::on_release(const sync::Member& message, sync::Release why) {
  ++inputs_[message.input].counters.released[static_cast<size_t>(why)];
  // merge drops nothing by design: a message it cannot check (late, or
  // replaced by its input's next one at the same stamp) is a loss, warned
  // and reflected in the exit status. The other policies drop by design.
  if (why == sync::Release::Late || (why == sync::Release::Replaced && sync_.policy == sync::PolicyKind::Merge)) {
    ++late_dropped_;
    report_late(message, last_time_, false, why == sync::Release::Replaced);
  }
  held_[message.token].text.clear();
  free_.push_back(static_cast<uint32_t>(message.token));
}

void SyncedPipeline::check_health(double now) {
  if (sync_.dead_after <= 0) return;
  double newest = 0;
  for (const Input& in : inputs_) newest = std::max(newest, in.counters.last_arrival);
  if (now - newest > sync_.dead_after) return;  // everything is quiet, not one input
  for (Input& in : inputs_) {
    const double silent = in.counters.received ? now - in.counters.last_arrival : -1;
    if (in.counters.reported_dead || (in.counters.received && silent <= sync_.dead_after)) continue;
    if (!in.counters.received && now - first_arrival_ <= sync_.dead_after) continue;
    in.counters.reported_dead = true;
    // Do not hold the others' messages for it any longer (merge).
    in.excluded = true;
    policy_->exclude(static_cast<uint32_t>(&in - inputs_.data()), true);
    std::string what = sync_.policy == sync::PolicyKind::Merge
                           ? "its fields hold their last values, and the others' messages no longer wait for it"
                           : std::string("no ") + sync::to_string(sync_.policy) + " set can form without it";
    std::fprintf(stderr, "rvc: warning: input '%s' (%s): %s while the others deliver: %s\n", in.spec.name.c_str(),
                 in.spec.uri.c_str(),
                 in.counters.received ? ("no message for " + std::to_string(static_cast<int>(silent)) + " s").c_str()
                                      : "nothing received yet",
                 what.c_str());
  }
}

void SyncedPipeline::idle() {
  const double now = wall_now();
  check_health(now);
  // Stamps that follow the clock (arrival stamps, live ROS stamps): the
  // merge watermark moves on while nothing comes, so the last messages are
  // checked without waiting for the next one.
  bool clocked = true;
  for (const Input& in : inputs_) clocked = clocked && in.arrival_stamp;
  if (clocked) policy_->advance(now);
}

double SyncedPipeline::next_deadline() {
  if (!ticking()) return std::numeric_limits<double>::infinity();
  deadline_engine_ = std::min(checker_.next_deadline(held_values()), timed_next_change());
  deadline_seconds_ = time_.seconds(deadline_engine_);
  return deadline_seconds_;
}

// As Pipeline::engine_of: the instants handed out map back exactly.
double SyncedPipeline::engine_of(double stream_seconds) const {
  if (stream_seconds == last_time_) return last_engine_;
  if (stream_seconds == deadline_seconds_) return deadline_engine_;
  return time_.from_seconds(stream_seconds);
}

void SyncedPipeline::tick(double stream_seconds) {
  if (!ticking()) return;
  const double stream_now = engine_of(stream_seconds);
  // Timed atoms that change by `stream_now` ({imu.@age <= 0.1} falling):
  // the monitors close [clock, c) with the values before the change, as a
  // set's step does, and go on from c with the changed ones.
  for (double c; (c = timed_next_change()) <= stream_now;) {
    if (c > checker_.clock()) checker_.step(checker_.clock(), c, held_values());
    advance_timed(c);
  }
  step_to(stream_now);
}

void SyncedPipeline::step_to(double instant) { checker_.tick(instant, held_values()); }

void SyncedPipeline::end_of_input() {
  if (ended_) return;
  ended_ = true;
  if (sync_.ordered) {  // what the merge by stamp still holds, in order
    for (Input& in : inputs_) in.ended = true;
    next_input();
  }
  policy_->finish();
}

void SyncedPipeline::warn(const io::LineError& warning) { inputs_[0].pipeline->warn(warning); }

void SyncedPipeline::finish_report() {
  for (auto& in : inputs_) in.pipeline->finish_report();
  if (reported_ > options_.max_reported)
    std::fprintf(stderr, "rvc: %llu more errors were not shown\n",
                 static_cast<unsigned long long>(reported_ - options_.max_reported));
  if (late_dropped_ + late_checked_ == 0) return;
  auto per_input = [&](bool checked) {
    std::string s;
    for (const Input& in : inputs_) {
      const auto& r = in.counters.released;
      const uint64_t n = checked ? in.counters.late_checked
                                 : r[static_cast<size_t>(sync::Release::Late)] +
                                       (sync_.policy == sync::PolicyKind::Merge ? r[static_cast<size_t>(sync::Release::Replaced)] : 0);
      if (n) s += (s.empty() ? "" : ", ") + in.spec.name + ": " + std::to_string(n);
    }
    return s;
  };
  if (late_dropped_)
    std::fprintf(stderr,
                 "rvc: warning: %llu message%s dropped, not checked (%s): late (stamped before events already "
                 "checked; --late process checks them, --max-delay S waits longer) or replaced (a repeated stamp)\n",
                 static_cast<unsigned long long>(late_dropped_), late_dropped_ == 1 ? "" : "s",
                 per_input(false).c_str());
  if (late_checked_)
    std::fprintf(stderr, "rvc: warning: %llu late message%s checked as the next event (%s)\n",
                 static_cast<unsigned long long>(late_checked_), late_checked_ == 1 ? "" : "s",
                 per_input(true).c_str());
}

const PipelineStats& SyncedPipeline::stats() const {
  stats_ = PipelineStats{0, sets_rejected_, 0};
  stats_.late_to_clock = late_to_clock_;
  for (const Input& in : inputs_) {
    stats_.accepted += in.counters.used;
    stats_.rejected += in.pipeline->stats().rejected + in.counters.out_of_order;
    stats_.warnings += in.pipeline->stats().warnings;
  }
  return stats_;
}

void SyncedPipeline::add_stats(io::JsonObject& out) const {
  io::JsonArray per_input;
  const double now = wall_now();
  for (const Input& in : inputs_) {
    const InputCounters& c = in.counters;
    io::JsonObject dropped;
    for (size_t r = 0; r < sync::kReleaseKinds; ++r)
      if (r != static_cast<size_t>(sync::Release::Used) && c.released[r])
        dropped.add(sync::to_string(static_cast<sync::Release>(r)), c.released[r]);
    io::JsonObject o;
    o.add("name", in.spec.name)
        .add("uri", in.spec.uri)
        .add("received", c.received)
        .add("rejected", in.pipeline->stats().rejected + c.out_of_order)
        .add("used", c.used)
        .add("dropped", dropped);
    if (c.late_checked) o.add("late_checked", c.late_checked);
    if (c.received) o.add_fixed("silent_s", now - c.last_arrival, 3);
    per_input.add(o);
  }
  out.add_raw("sync", io::JsonObject()
                          .add("policy", sync::to_string(sync_.policy))
                          .add("sets", sets_)
                          .add("sets_rejected", sets_rejected_)
                          .add("held", policy_->held())
                          .add_raw("inputs", per_input.str())
                          .str());
}

}  // namespace rvc::runtime
