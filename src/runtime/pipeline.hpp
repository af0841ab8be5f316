// decode -> engine -> verdicts, shared by `rvc check` (files) and
// `rvc monitor` (network): one JSON decode per message for all properties,
// time-order checks for dense time, size limits, and counters for what was
// rejected. A file read line by line and the same lines arriving as network
// payloads go through the same rules, so check and monitor agree.
#pragma once

#include <simdjson.h>

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/checker.hpp"
#include "engine/timed/timed_atoms.hpp"
#include "io/cdr_decoder.hpp"
#include "io/json_decoder.hpp"
#include "io/jsonl_reader.hpp"
#include "msg/msg_types.hpp"
#include "runtime/engine_time.hpp"
#include "runtime/feed.hpp"

namespace rvc::runtime {

struct PipelineOptions {
  engine::TimeModel model = engine::TimeModel::Discrete;
  bool emit_all = false;
  bool strict = false;
  std::string time_field = "time";
  std::string position_name = "line";  // how errors name a message: "line 12", "seq 12"
  size_t max_reported = 100;           // errors and warnings printed before going quiet
  bool parse_only = false;             // decode every message but run no monitor (benchmark floor)
  bool robustness = false;             // robustness values instead of Booleans
  bool explain = false;                // a violation's verdict says why (discrete)
  uint32_t max_data_values = 100000;   // data references: distinct values per variable
  size_t max_message_size = 1 << 20;   // longest message: a line, a payload, a line inside a batched payload
  // Typed input (a CDR sample, one per payload): the decoder reads only the
  // tested fields and steps over the rest without copying (an Image's data),
  // so the cap only bounds memory: well above camera frames and point clouds.
  size_t max_typed_message_size = size_t{256} << 20;
  bool layouts = true;                 // read lines laid out like earlier ones by position (io/json_layout.hpp)
  // Evaluate comparisons of one field with many constants together and step
  // only the operators whose inputs changed (io/threshold_index.hpp,
  // engine/discrete/monitor.hpp). Off (hidden --plain-eval): every test and
  // operator at every message, to compare the two paths.
  bool incremental = true;
  // Typed input (--type): each payload is one CDR sample of this type,
  // decoded straight into the tests' values (properties are checked against
  // the type first). Owned by the caller's msg::TypeRegistry; null: JSON.
  const msg::MessageType* type = nullptr;
  // Sees each message as it is committed, before the monitors step on it
  // (the results store's witness window): the input's name, the message's
  // text (a JSON line, or a CDR sample) and its position.
  std::function<void(std::string_view input, std::string_view text, uint64_t position)> on_message;
  std::string input_name;  // what on_message calls this input
  // Where each error and warning line goes (without the "rvc: " prefix); empty: stderr, at most
  // max_reported of them. The Python package (python/) turns them into exceptions and warnings.
  std::function<void(const std::string& text)> on_report;
  // Dense time: where the timeline starts (runtime/engine_time.hpp): the
  // first message (default) or 0 (--origin zero, Reelay's rule).
  Origin origin = Origin::First;
};

// Decode-only mode (a synchronized input, see SyncedPipeline): each accepted
// message's committed values, in the order of the atom table given to the
// Pipeline, its time (NaN without a time field) and its position.
using MessageHook = std::function<void(const uint8_t* values, double time, uint64_t position)>;

class Pipeline final : public io::JsonlHandler, public Feed {
 public:
  // Throws spec::SpecError (prefixed with the property's name) for a bad spec.
  Pipeline(const std::vector<engine::PropertySpec>& properties, const PipelineOptions& options,
           engine::VerdictCallback on_verdict);
  // Decode-only: evaluates the tests of `atoms` (which must outlive the
  // Pipeline; typed: already bound to the type) and hands every accepted
  // message to `hook` instead of a checker. With a time field (dense model),
  // a message whose time is negative or not a number is rejected; the order
  // of times is left to the hook.
  Pipeline(const engine::AtomTable& atoms, const PipelineOptions& options, MessageHook hook);

  io::ReadResult on_object(const io::Position& position, simdjson::ondemand::object object) override;
  std::string json_error() const override { return json_error_; }
  void commit() override;
  void discard() override {
    pending_ = false;
    pending_rejection_.clear();
  }
  bool reads_layouts() const override { return !typed_ && decoder_.learns_layouts(); }
  const char* match_line(const char* p, const char* end) override { return decoder_.match_line(p, end); }
  void read_matched(const io::Position& where) override;
  void on_error(const io::LineError& error) override;
  void on_warning(const io::LineError& warning) override;
  // One network payload; `position` names it in errors (its sequence number).
  // A payload holding several lines is a batch: one message per line. A
  // payload (or line) over max_message_size is rejected, as in a file.
  void feed(std::string_view payload, uint64_t position);

  const PipelineStats& stats() const override { return stats_; }
  const engine::Checker& checker() const { return checker_; }
  bool violated() const { return checker_.violations() > 0; }
  // Prints "N more errors were not shown" if output was cut short.
  void finish_report() override;

  // Feed, for the monitor loop: one input.
  void feed_input(uint32_t, std::string_view payload, uint64_t position) override;
  // A recorded message: its log time is its arrival ({@latency}).
  void feed_logged(uint32_t, std::string_view payload, uint64_t position, double log_time) override;

  // ---- Timing atoms and window aggregates (engine/timed; issue 26) ----
  // They change value without a message: {@age <= 0.1} turns false 0.1 s
  // after the last one, a window's count drops when a sample leaves it.
  // Files and bags step the monitors through each such instant between two
  // messages themselves (commit()); a live clock asks when the next one is
  // and moves them there:
  //   while ((c = timed_next_change()) <= now) { tick(c) with held_values(); advance_timed(c); }
  // The earliest instant after the last message or advance at which a
  // timed atom changes (+inf: none, or discrete time, or no timed atoms).
  double timed_next_change() const { return timed_ ? timed_->next_change() : std::numeric_limits<double>::infinity(); }
  // Updates the timed atoms' committed values at t (>= the last message's time).
  void advance_timed(double t);
  // The values the monitors hold since the last message, timed atoms
  // included (what a tick steps with); margins likewise (--robustness).
  const uint8_t* held_values();
  const double* held_margins();
  // Decode-only pipelines: the committed margins (SyncedPipeline's field aggregates).
  const double* committed_margins() const { return margins(); }
  void warn(const io::LineError& warning) override { on_warning(warning); }
  uint64_t violations() const override { return checker_.violations(); }

  // Feed: dense time on a clock. Held values are the committed ones (the
  // last accepted message's, fields it lacked kept from before).
  double next_deadline() override;
  void tick(double stream_now) override;
  void settle() override { checker_.finish(); }
  double last_stamp() const override {
    return has_time_ ? static_cast<double>(last_ns_) / 1e9 : std::numeric_limits<double>::quiet_NaN();
  }
  // The last accepted message's exact time (dense), and the message being
  // committed (decode-only pipelines: their hook's time, exactly).
  int64_t last_stamp_ns() const { return last_ns_; }
  int64_t message_time_ns() const { return typed_ ? typed_->time_ns() : decoder_.time_ns(); }
  const EngineTime& engine_time() const { return time_; }

 private:
  // --explain (discrete): an expression atom's sentence about the current
  // step also names the numbers it computed with, then the verdict goes on.
  void send_explained(const engine::VerdictCallback& send, const engine::Verdict& v) const;
  // Ticks run only on a checking dense pipeline after its first message:
  // before it there is no held value, and the timeline's start is 0.
  bool ticking() const {
    return has_time_ && !hook_ && !options_.parse_only && checker_.model() == engine::TimeModel::Dense;
  }
  // Steps the monitors to `instant` with every field held. The one place a
  // tick reaches the checker: change instants of other origins (time-driven
  // atoms) are folded in by stepping to each of them in turn.
  void step_to(double instant);
  // A message stamped at or before the instant ticks reached: counted, and
  // the first one warned about (it is still checked, at that instant).
  void note_late(double t);
  void report(const std::string& text);
  bool oversized(std::string_view payload, uint64_t position);  // rejects it if so
  void feed_typed(std::string_view sample, uint64_t position);
  void make_typed_decoder();
  void arrive_timed(double t);  // --type: the CDR decoder, over atoms_, after options_ are set
  template <class F>
  void step_checker(const io::Position& where, F&& step);  // a data-limit error names `where`
  // The decoder of the message being committed.
  void commit_values() { typed_ ? typed_->commit() : decoder_.commit(); }
  const uint8_t* values() const { return typed_ ? typed_->values() : decoder_.values(); }
  const uint32_t* bound() const { return typed_ ? typed_->bound() : decoder_.bound(); }
  const double* margins() const { return typed_ ? typed_->margins() : decoder_.margins(); }
  double message_time() const { return typed_ ? typed_->time() : decoder_.time(); }
  engine::Checker checker_;
  // Timing atoms and aggregates of the properties (null: none). Before the
  // decoders: it adds the hidden tests field aggregates read.
  std::unique_ptr<engine::timed::TimedAtoms> timed_;
  std::vector<uint8_t> timed_values_;  // decoder values with the timed atoms' written over
  std::vector<double> timed_margins_;
  double arrival_ = std::numeric_limits<double>::quiet_NaN();  // of the message being fed ({@latency})
  uint64_t steps_ = 0;  // discrete time: the step the next message makes
  PipelineOptions options_;
  const engine::AtomTable& atoms_;  // the checker's, or a synchronized input's
  MessageHook hook_;
  io::JsonDecoder decoder_;
  PipelineStats stats_;
  bool has_time_ = false;
  bool pending_ = false;        // decoded, waiting for commit()
  bool fast_commit_ = false;     // read_matched() may step the checker at once (a discrete JSON run, see there)
  bool pending_matched_ = false;  // ... read by its layout (else by simdjson, and its layout may be learned)
  // Where the pending message came from. A copy, not a pointer: the reader's
  // Position may be a temporary that is gone by commit().
  std::optional<io::Position> pending_where_;
  double last_time_ = 0;  // engine time of the last message (dense)
  int64_t last_ns_ = 0;   // ... and its exact stamp
  EngineTime time_;
  // The last deadline handed out, in Feed seconds and engine time: a tick at
  // exactly that double is at exactly that engine time (no rounding back).
  double deadline_seconds_ = std::numeric_limits<double>::quiet_NaN();
  double deadline_engine_ = 0;
  bool warned_inexact_ = false;
  double engine_of(double stream_seconds) const;
  std::string instant_text(double engine) const;  // an engine time as the instant's exact seconds
  uint64_t reported_ = 0;
  bool warned_late_ = false;
  std::vector<std::string> warnings_;  // of the pending message, reported at commit()
  std::string pending_rejection_;      // why the pending message is refused, reported at commit()
  std::string_view pending_text_;      // its text, when options_.on_message wants it
  std::string json_error_;
  simdjson::ondemand::parser parser_;
  std::string scratch_;
  std::optional<io::CdrDecoder> typed_;  // --type: CDR samples instead of JSON
  io::ChunkReader batch_reader_;
  uint64_t batch_position_ = 0;  // position of the payload being read as a batch, else 0
};

}  // namespace rvc::runtime
