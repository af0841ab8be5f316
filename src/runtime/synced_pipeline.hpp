// Several named inputs checked as one stream (issue 12): `--input
// gear=dds:/vehicle/status/gear_status --input steer=...` and properties
// over `{gear.report == REVERSE}`, `{steer.steering_tire_angle > 0.3}`.
//
//   input i payload -> its own Pipeline (decode-only: its own atom table,
//   type, stamp field) -> values held by token -> sync::Policy -> a set ->
//   the members' values written into one combined atom array -> Checker
//
// So each message is decoded once, on arrival, into the few bytes its tests
// need; the policy moves tokens, never payloads. `rvc sync` runs the same
// thing without properties and publishes each set as one JSON object.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "engine/checker.hpp"
#include "engine/timed/timed_atoms.hpp"
#include "msg/msg_types.hpp"
#include "runtime/feed.hpp"
#include "runtime/pipeline.hpp"
#include "sync/policy.hpp"

namespace rvc::runtime {

struct SyncInput {
  std::string name;                        // "gear": properties test {gear.…}
  std::string uri;                         // where it comes from (messages, counters)
  const msg::MessageType* type = nullptr;  // typed (CDR) payloads; null: JSON
  // The message's stamp: a field path ("header.stamp", "stamp", "t"; a Time
  // message or a number of seconds), "arrival" (wall clock when it reaches
  // rvc), or empty: typed header.stamp / stamp, else arrival; JSON: the
  // pipeline's time field ("time").
  std::string stamp;
};

struct SyncOptions {
  sync::PolicyKind policy = sync::PolicyKind::Merge;
  sync::PolicyOptions policy_options;  // `inputs` is filled in
  double dead_after = 5;               // seconds: an input silent this long while others deliver is reported
  // The inputs are files, read by the caller in the order next_input() asks
  // for: a k-way merge by stamp, one message ahead per input, so the sets do
  // not depend on which file a thread happened to read faster. A file whose
  // stamps go back is refused at that line (each file must be in order).
  bool ordered = false;
};

// One set as JSON: {"time": stamp, "gear": {...}, "steer": {...}}, every
// input's latest message (merge: those that have had one).
using SetCallback = std::function<void(std::string_view json, double stamp)>;

class SyncedPipeline final : public Feed, private sync::Handler {
 public:
  // Throws spec::SpecError for a test on no input ({speed} with inputs gear,
  // steer; the column of the test), or on a field an input's type lacks;
  // std::invalid_argument for bad input names. `on_set` (may be empty) gets
  // every set as JSON: what `rvc sync` publishes.
  SyncedPipeline(const std::vector<engine::PropertySpec>& properties, const PipelineOptions& options,
                 std::vector<SyncInput> inputs, const SyncOptions& sync, engine::VerdictCallback on_verdict,
                 SetCallback on_set = {});
  ~SyncedPipeline() override;

  // Feed.
  void feed_input(uint32_t input, std::string_view payload, uint64_t position) override;
  void feed_logged(uint32_t input, std::string_view payload, uint64_t position, double log_time) override {
    feed_at(input, payload, position, log_time);
  }
  void warn(const io::LineError& warning) override;
  void idle() override;
  void end_of_input() override;
  bool reads_in_order() const override { return sync_.ordered; }
  int next_input() override;
  void input_ended(uint32_t input) override;
  uint64_t received() const override;
  void add_dropped(io::JsonObject& out) const override;
  uint64_t lost() const override { return late_dropped_; }
  // accepted: messages in a checked set; rejected: messages the inputs
  // refused (out of order ones too) plus sets out of time order; warnings:
  // the inputs'.
  const PipelineStats& stats() const override;
  uint64_t violations() const override { return checker_.violations(); }
  void finish_report() override;
  void add_stats(io::JsonObject& out) const override;
  // Dense time on a clock: the held values are the latest set's members'
  // (combined_), as the next set's step will be given them.
  double next_deadline() override;
  void tick(double stream_now) override;
  void settle() override { checker_.finish(); }
  double last_stamp() const override {
    return has_time_ ? last_time_ : std::numeric_limits<double>::quiet_NaN();
  }

  // One payload with its arrival time given (wall-clock seconds): tests and
  // bags (whose arrival is the log time).
  void feed_at(uint32_t input, std::string_view payload, uint64_t position, double arrival);
  const engine::Checker& checker() const { return checker_; }

  // Timing atoms and aggregates ({steer.@age <= 0.1}, count[0:1](steer.@arrived)),
  // as Pipeline has them: an input "arrives" in a set when one of its
  // messages is used for the first time in that set. Files and bags step
  // through their change instants between sets (on_set); a live clock uses:
  double timed_next_change() const { return timed_ ? timed_->next_change() : std::numeric_limits<double>::infinity(); }
  void advance_timed(double t);
  // The combined values the monitors hold since the last set, timed atoms included.
  const uint8_t* held_values();
  uint64_t sets() const { return sets_; }
  size_t inputs() const;

  struct InputCounters {
    uint64_t received = 0;  // payloads (a batch counts its lines)
    uint64_t decoded = 0;   // messages that went to the policy
    uint64_t used = 0;      // messages that were in a set
    std::array<uint64_t, sync::kReleaseKinds> released{};  // by Release
    uint64_t out_of_order = 0;  // ordered inputs: refused, stamped before the input's previous message
    uint64_t late_checked = 0;  // merge, --late process: late messages checked as the next event
    double last_arrival = 0;
    bool reported_dead = false;
  };
  const InputCounters& counters(size_t input) const;

 private:
  struct Input;
  struct Held;
  void on_set(const sync::Member* members, size_t count, double set_stamp) override;
  void on_release(const sync::Member& message, sync::Release why) override;
  void accept(uint32_t input, const uint8_t* values, double time, uint64_t position);
  void check_health(double now);
  bool ticking() const { return has_time_ && !options_.parse_only && options_.model == engine::TimeModel::Dense; }
  void step_to(double instant);  // the one place a tick reaches the checker (see Pipeline::step_to)
  void report(const std::string& text);
  void report_late(const sync::Member& message, double after, bool checked, bool replaced);

  engine::Checker checker_;
  std::unique_ptr<engine::timed::TimedAtoms> timed_;  // null: no timing atoms
  std::vector<double> combined_margins_;  // field aggregates: the members' margins (their field values)
  PipelineOptions options_;
  SyncOptions sync_;
  std::vector<Input> inputs_;
  std::unique_ptr<sync::Policy> policy_;
  SetCallback on_set_;
  std::vector<Held> held_;         // by token
  std::vector<uint32_t> free_;     // tokens free for reuse
  std::vector<uint8_t> combined_;  // the checker's atoms: every input's values of its latest set member
  mutable PipelineStats stats_;
  double first_arrival_ = 0;
  uint64_t sets_ = 0, sets_rejected_ = 0, reported_ = 0;
  uint64_t late_dropped_ = 0;  // lost: dropped late, or (merge) replaced by a message at the same stamp
  uint64_t late_checked_ = 0, late_reported_ = 0;
  uint64_t late_to_clock_ = 0;  // sets stamped at or before the instant ticks had reached
  bool has_time_ = false, ended_ = false;
  double last_time_ = 0;     // the last set's stamp, seconds (the policies' unit)
  double last_engine_ = 0;   // ... in engine time (runtime/engine_time.hpp), exact
  EngineTime time_;
  double deadline_seconds_ = std::numeric_limits<double>::quiet_NaN(), deadline_engine_ = 0;
  double engine_of(double stream_seconds) const;
  uint32_t feeding_ = 0;           // the input whose payload is being decoded
  double arrival_ = 0;             // of that payload
  std::string_view message_;       // that payload (for on_set's JSON)
  std::string json_;               // scratch
};

}  // namespace rvc::runtime
