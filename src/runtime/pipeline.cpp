#include "runtime/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "io/cdr_codec.hpp"
#include "io/verdict_writer.hpp"
#include "runtime/typed_specs.hpp"
#include "spec/exact_time.hpp"
#include "spec/parser.hpp"
#include "spec/spec_error.hpp"

namespace rvc::runtime {
namespace {

// One unnamed input: {steer.@age ..} names an input there is not.
void check_unnamed(const std::vector<engine::PropertySpec>& properties, const PipelineOptions& options) {
  spec::ParseOptions po;
  po.dense = options.model == engine::TimeModel::Dense;
  po.robustness = options.robustness;
  for (const auto& p : properties) {
    const spec::NodePtr ast = spec::parse(p.spec, po);
    std::vector<const spec::Node*> todo{ast.get()};
    while (!todo.empty()) {
      const spec::Node* n = todo.back();
      todo.pop_back();
      if (n->left) todo.push_back(n->left.get());
      if (n->right) todo.push_back(n->right.get());
      const spec::FieldTest& t = n->test;
      if (n->op != spec::Op::Test || !t.is_timed() || t.timed.kind == spec::Timed::Kind::Aggregate ||
          t.path.size() < 2)
        continue;
      throw spec::SpecError("in property '" + p.name + "': '" + t.path[0] + "." + t.path[1] +
                                "' names an input, and this run has one unnamed input: write {" + t.path[1] +
                                " ...} (named inputs come with several --input NAME=URI or --topic NAME=TOPIC)",
                            p.spec, t.column);
    }
  }
}

engine::Checker build(const std::vector<engine::PropertySpec>& properties, const PipelineOptions& options,
                      engine::VerdictCallback on_verdict) {
  engine::Checker checker(options.model, options.emit_all, std::move(on_verdict));
  checker.count_nanoseconds();  // dense time: exact nanoseconds (runtime/engine_time.hpp)
  checker.set_incremental(options.incremental);
  if (options.robustness) checker.enable_robustness();
  if (options.explain) checker.enable_explain();
  checker.set_max_data_values(options.max_data_values);
  for (const auto& p : properties) {
    try {
      checker.add_property(p);
    } catch (const spec::SpecError& e) {
      throw spec::SpecError("in property '" + p.name + "': " + e.message(), e.source(), e.column());
    }
  }
  check_unnamed(properties, options);
  if (options.type)
    bind_message_type(checker, properties, *options.type, options.model == engine::TimeModel::Dense,
                      options.time_field);
  return checker;
}

// Typed dense time keeps the default "time" only if the type has it; else
// the message's stamp (header.stamp, stamp), as ROS 2 users expect.
PipelineOptions with_defaults(PipelineOptions o) {
  if (o.type && o.model == engine::TimeModel::Dense)
    o.time_field = io::CdrDecoder::default_time_field(*o.type, o.time_field);
  return o;
}

std::string number(double v) {
  std::string s;
  io::append_number(s, v);
  return s;
}

// The run's timing atoms and aggregates, or null when its properties have none.
std::unique_ptr<engine::timed::TimedAtoms> make_timed(engine::Checker& checker) {
  bool any = false;
  for (const auto& t : checker.atoms().tests()) any = any || t.is_timed();
  if (!any) return nullptr;
  return std::make_unique<engine::timed::TimedAtoms>(checker.atoms(), std::vector<std::string>{""}, checker.model());
}

bool needs_margins(const PipelineOptions& o, const engine::timed::TimedAtoms* timed) {
  return o.robustness || (timed && timed->needs_field_values());
}

}  // namespace

Pipeline::Pipeline(const std::vector<engine::PropertySpec>& properties, const PipelineOptions& options,
                   engine::VerdictCallback on_verdict)
    : checker_(build(properties, with_defaults(options),
                     options.explain && options.model == engine::TimeModel::Discrete
                         ? engine::VerdictCallback([this, send = std::move(on_verdict)](const engine::Verdict& v) {
                             send_explained(send, v);
                           })
                         : std::move(on_verdict))),
      timed_(make_timed(checker_)),
      options_(with_defaults(options)),
      atoms_(checker_.atoms()),
      decoder_(atoms_, io::DecoderOptions{options.model == engine::TimeModel::Dense, options.time_field,
                                          options.strict, needs_margins(options, timed_.get()), options.layouts,
                                          options.incremental}),
      batch_reader_(*this, options.max_message_size) {
  time_ = EngineTime(options.origin);
  make_typed_decoder();
  if (timed_) {
    timed_values_.assign(atoms_.size(), 0);
    timed_margins_.assign(atoms_.size(), -std::numeric_limits<double>::infinity());
  }
  fast_commit_ = !timed_ && !typed_ && !options_.on_message && !options_.parse_only && !options_.robustness &&
                 options_.model == engine::TimeModel::Discrete;
  // --explain names the values a data reference decided on by their JSON
  // text; the decoders assign their ids. (A Pipeline never moves: its
  // reader already holds `this`.)
  if (options.explain && checker_.has_data_references())
    checker_.set_value_names([this](uint32_t id) {
      return typed_ ? typed_->bound_values().json(id) : decoder_.bound_values().json(id);
    });
}

void Pipeline::send_explained(const engine::VerdictCallback& send, const engine::Verdict& v) const {
  if (!send) return;
  if (!v.explanation || !timed_ || !timed_->has_expressions()) return send(v);
  std::vector<std::string> why = *v.explanation;
  const std::string now = " at step " + std::to_string(static_cast<uint64_t>(v.time));
  for (size_t id = 0; id < atoms_.size(); ++id) {
    if (!atoms_.tests()[id].is_expr()) continue;
    const std::string atom = "{" + atoms_.tests()[id].to_string() + "} is ";
    for (std::string& s : why)
      if (s.find(atom) != std::string::npos && s.size() >= now.size() &&
          s.compare(s.size() - now.size(), now.size(), now) == 0)
        s += " (" + timed_->describe(static_cast<int>(id)) + ")";
  }
  engine::Verdict explained = v;
  explained.explanation = &why;
  send(explained);
}

void Pipeline::make_typed_decoder() {
  if (!options_.type) return;
  typed_.emplace(atoms_, *options_.type,
                 io::DecoderOptions{options_.model == engine::TimeModel::Dense, options_.time_field, options_.strict,
                                    needs_margins(options_, timed_.get()), true, options_.incremental});
}

Pipeline::Pipeline(const engine::AtomTable& atoms, const PipelineOptions& options, MessageHook hook)
    : checker_(options.model, false, [](const engine::Verdict&) {}),
      options_(with_defaults(options)),
      atoms_(atoms),
      hook_(std::move(hook)),
      decoder_(atoms_, io::DecoderOptions{options.model == engine::TimeModel::Dense, options.time_field,
                                          options.strict, options.robustness, options.layouts, options.incremental}),
      batch_reader_(*this, options.max_message_size) {
  time_ = EngineTime(options.origin);
  make_typed_decoder();
}

void Pipeline::report(const std::string& text) {
  if (options_.on_report) return options_.on_report(text);
  if (reported_++ < options_.max_reported) std::fprintf(stderr, "rvc: %s\n", text.c_str());
}

void Pipeline::on_error(const io::LineError& error) {
  ++stats_.rejected;
  std::string where = batch_position_ ? options_.position_name + " " + std::to_string(batch_position_) + ", line " +
                                            std::to_string(error.line)
                                      : options_.position_name + " " + std::to_string(error.line);
  if (error.column) where += ", column " + std::to_string(error.column);
  report(where + ": " + error.message + " (message skipped)");
}

void Pipeline::on_warning(const io::LineError& w) {
  ++stats_.warnings;
  report("warning: " + options_.position_name + " " + std::to_string(w.line) + ": " + w.message);
}

io::ReadResult Pipeline::on_object(const io::Position& where, simdjson::ondemand::object object) {
  std::string error;
  warnings_.clear();
  if (!decoder_.decode(object, error, &warnings_)) {
    if (decoder_.malformed()) {  // the reader re-reads this stretch and reports it
      json_error_ = error;
      return io::ReadResult::Malformed;
    }
    // Valid JSON the properties cannot use. Reported at commit(), once the
    // reader knows the object is alone on its line: if text follows it, the
    // whole line is one bad message, reported once (found by fuzz_jsonl).
    pending_rejection_ = error;
  }
  pending_ = true;
  pending_matched_ = false;
  pending_where_.emplace(where);
  if (options_.on_message) pending_text_ = where.text();
  return io::ReadResult::Pending;
}

void Pipeline::read_matched(const io::Position& where) {
  std::string error;
  warnings_.clear();
  const bool decoded = decoder_.decode_matched(error, &warnings_);
  if (decoded && warnings_.empty() && fast_commit_) {
    // What commit() does for a plain discrete run, without the bookkeeping a
    // message that may still be refused needs (the usual case by far).
    decoder_.commit();
    step_checker(where, [&] { checker_.step(decoder_.values(), decoder_.bound()); });
    ++stats_.accepted;
    ++stats_.by_layout;
    return;
  }
  if (!decoded) pending_rejection_ = error;
  pending_ = true;
  pending_matched_ = true;
  pending_where_.emplace(where);
  if (options_.on_message) pending_text_ = where.text();
  commit();  // the layout covered the whole line: nothing can follow it
}

// A data reference past --max-data-values stops the run: the error names
// the message that brought the value too many.
template <class F>
void Pipeline::step_checker(const io::Position& where, F&& step) {
  try {
    step();
  } catch (const engine::data::DataLimitError& e) {
    throw engine::data::DataLimitError(options_.position_name + " " + std::to_string(where.number()) + ": " + e.what());
  }
}

void Pipeline::commit() {
  if (!pending_) return;
  pending_ = false;
  if (!pending_rejection_.empty()) {
    on_error(io::LineError{pending_where_->number(), 0, pending_rejection_});
    pending_rejection_.clear();
    return;
  }
  for (const std::string& w : warnings_) {
    ++stats_.warnings;
    report("warning: " + options_.position_name + " " + std::to_string(pending_where_->number()) + ": " + w);
  }
  if (options_.on_message) options_.on_message(options_.input_name, pending_text_, pending_where_->number());
  if (hook_) {
    const bool timed = options_.model == engine::TimeModel::Dense;
    const double t = timed ? message_time() : std::numeric_limits<double>::quiet_NaN();
    if (timed && message_time_ns() < 0) {
      on_error(io::LineError{pending_where_->number(), 0,
                             "time " + spec::seconds_text(message_time_ns()) + " is negative (not a time)"});
      return;
    }
    commit_values();
    hook_(values(), t, pending_where_->number());
  } else if (options_.parse_only) {
    commit_values();
  } else if (checker_.robustness() && checker_.model() == engine::TimeModel::Discrete) {
    commit_values();
    arrive_timed(static_cast<double>(steps_++));
    checker_.step_robust(held_margins());
  } else if (checker_.model() == engine::TimeModel::Discrete) {
    commit_values();
    arrive_timed(static_cast<double>(steps_++));
    step_checker(*pending_where_, [&] { checker_.step(held_values(), bound()); });
  } else {
    // Dense: this message closes [previous time, its time) with the previous
    // values. Times are exact nanoseconds (spec/exact_time.hpp); the engine
    // counts them from the origin (the first message, or 0).
    const int64_t ns = message_time_ns();
    if (ns < 0 || (has_time_ && ns <= last_ns_)) {
      std::string why = ns < 0 ? "time " + spec::seconds_text(ns) + " is negative (the timeline starts at 0)"
                               : "time " + spec::seconds_text(ns) + " is not after the previous message's time " +
                                     spec::seconds_text(last_ns_) + " (dense time needs strictly increasing times)";
      on_error(io::LineError{pending_where_->number(), 0, why});
      return;
    }
    if (!time_.started()) {
      time_.start(ns);
      checker_.set_origin(time_.origin_ns());
    }
    double t = time_.engine(ns);
    double begin = has_time_ ? last_time_ : 0;
    if (!warned_inexact_ && !EngineTime::exact(t)) {
      warned_inexact_ = true;
      report("warning: " + options_.position_name + " " + std::to_string(pending_where_->number()) + ": time " +
             spec::seconds_text(ns) + " is more than 9007199.254740992 s (2^53 ns, about 104 days) after the " +
             "timeline's start " + spec::seconds_text(time_.origin_ns()) +
             ": from here on times are no longer exact to the nanosecond (warned once)");
    }
    if (t <= checker_.clock() && checker_.clock() > last_time_) note_late(t);
    // Timed atoms that change before t: the monitors step to each change
    // with the values before it (a gap in a recording needs no clock).
    for (double c; (c = timed_next_change()) < t; begin = c) {
      if (checker_.robustness()) checker_.step_robust(begin, c, held_margins());
      else step_checker(*pending_where_, [&] { checker_.step(begin, c, held_values(), bound()); });
      advance_timed(c);
    }
    if (checker_.robustness()) checker_.step_robust(begin, t, held_margins());
    else step_checker(*pending_where_, [&] { checker_.step(begin, t, held_values(), bound()); });
    commit_values();
    arrive_timed(t);
    has_time_ = true;
    last_time_ = t;
    last_ns_ = ns;
  }
  ++stats_.accepted;
  stats_.by_layout += pending_matched_;
  // A message simdjson read teaches its layout, so the next ones like it are read by position.
  if (!pending_matched_ && !typed_ && decoder_.wants_layout()) decoder_.learn(pending_where_->text());
}

void Pipeline::advance_timed(double t) {
  if (timed_) timed_->advance(t);
}

// The committed message arrived at t (a step, or its time in dense time).
void Pipeline::arrive_timed(double t) {
  if (!timed_) return;
  timed_->advance(t);
  // NaN without an arrival (a file's lines); dense time: engine nanoseconds.
  const double latency = checker_.model() == engine::TimeModel::Dense ? time_.from_seconds(arrival_) - t : arrival_ - t;
  timed_->arrive(0, latency, values(), margins());
}

const uint8_t* Pipeline::held_values() {
  if (!timed_) return values();
  std::copy(values(), values() + atoms_.size(), timed_values_.begin());
  timed_->write(timed_values_.data());
  return timed_values_.data();
}

const double* Pipeline::held_margins() {
  if (!timed_) return margins();
  std::copy(margins(), margins() + atoms_.size(), timed_margins_.begin());
  timed_->write_margins(timed_margins_.data());
  return timed_margins_.data();
}

void Pipeline::feed_input(uint32_t, std::string_view payload, uint64_t position) {
  // Live: a message's arrival is now (wall clock), read only when a property asks.
  if (timed_ && timed_->needs_arrival())
    arrival_ = std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  feed(payload, position);
}

void Pipeline::feed_logged(uint32_t, std::string_view payload, uint64_t position, double log_time) {
  arrival_ = log_time;
  feed(payload, position);
}

std::string Pipeline::instant_text(double engine) const {
  if (!std::isfinite(engine)) return engine > 0 ? "inf" : "-inf";
  return spec::seconds_text(time_.origin_ns() + std::llround(engine));
}

void Pipeline::note_late(double t) {
  ++stats_.late_to_clock;
  if (warned_late_) return;
  warned_late_ = true;
  std::fprintf(stderr,
               "rvc: warning: %s %llu: time %s is not after %s, where the clock's ticks had taken the monitors: checked "
               "as if at %s (counted as late_to_clock; warned once)\n",
               options_.position_name.c_str(), static_cast<unsigned long long>(pending_where_->number()),
               instant_text(t).c_str(), instant_text(checker_.clock()).c_str(), instant_text(checker_.clock()).c_str());
}

double Pipeline::next_deadline() {
  if (!ticking()) return std::numeric_limits<double>::infinity();
  const double d = checker_.robustness() ? checker_.next_deadline_robust(held_margins())
                                         : checker_.next_deadline(held_values(), bound());
  deadline_engine_ = std::min(d, timed_next_change());
  deadline_seconds_ = time_.seconds(deadline_engine_);
  return deadline_seconds_;
}

// A Feed time (seconds) in engine time: the instants this pipeline handed
// out (the last stamp, the last deadline) map back exactly.
double Pipeline::engine_of(double stream_seconds) const {
  if (stream_seconds == last_stamp()) return last_time_;
  if (stream_seconds == deadline_seconds_) return deadline_engine_;
  return time_.from_seconds(stream_seconds);
}

void Pipeline::tick(double stream_seconds) {
  if (!ticking()) return;
  const double stream_now = engine_of(stream_seconds);
  // Timed atoms that change by `stream_now` ({@age <= 0.2} falling): the
  // monitors close [clock, c) with the values before the change, as a
  // message's step does, and go on from c with the changed ones.
  for (double c; (c = timed_next_change()) <= stream_now;) {
    if (c > checker_.clock()) {
      try {
        if (checker_.robustness()) checker_.step_robust(checker_.clock(), c, held_margins());
        else checker_.step(checker_.clock(), c, held_values(), bound());
      } catch (const engine::data::DataLimitError& e) {
        throw engine::data::DataLimitError("tick at time " + instant_text(c) + ": " + e.what());
      }
    }
    advance_timed(c);
  }
  step_to(stream_now);
}

void Pipeline::step_to(double instant) {
  try {
    if (checker_.robustness()) checker_.tick_robust(instant, held_margins());
    else checker_.tick(instant, held_values(), bound());
  } catch (const engine::data::DataLimitError& e) {  // named as a step's error names its message
    throw engine::data::DataLimitError("tick at time " + instant_text(instant) + ": " + e.what());
  }
}

bool Pipeline::oversized(std::string_view payload, uint64_t position) {
  if (payload.size() <= options_.max_message_size) return false;
  // Worded as the file reader words it: check and monitor report alike.
  on_error(io::LineError{position, 0,
                         "message longer than " + std::to_string(options_.max_message_size) +
                             " bytes (--max-message-size); skipped"});
  return true;
}

void Pipeline::feed(std::string_view payload, uint64_t position) {
  if (typed_) {  // one CDR sample per payload (never a batch)
    if (payload.size() <= options_.max_typed_message_size) return feed_typed(payload, position);
    ++stats_.oversized;
    on_error(io::LineError{position, 0,
                           "a sample of " + std::to_string(payload.size()) + " bytes, over the limit of " +
                               std::to_string(options_.max_typed_message_size) +
                               " bytes for typed input (raise it with --max-message-size)"});
    return;
  }
  if (payload.find('\n') != std::string_view::npos) {
    // A batch: the reader applies the size limit to each line.
    batch_position_ = position;
    batch_reader_.read(payload, 1);
    batch_position_ = 0;
    return;
  }
  if (oversized(payload, position)) return;
  if (decoder_.match(payload)) return read_matched(io::Position(position, payload));
  io::parse_one(parser_, payload, position, *this, scratch_);
}

void Pipeline::feed_typed(std::string_view sample, uint64_t position) {
  std::string error;
  warnings_.clear();
  if (!typed_->decode(sample, error, &warnings_)) {
    on_error(io::LineError{position, 0, error});
    return;
  }
  pending_ = true;
  pending_where_.emplace(position);
  pending_text_ = sample;
  commit();
}

void Pipeline::finish_report() {
  if (reported_ > options_.max_reported)
    std::fprintf(stderr, "rvc: %llu more errors/warnings were not shown\n",
                 static_cast<unsigned long long>(reported_ - options_.max_reported));
}

}  // namespace rvc::runtime
