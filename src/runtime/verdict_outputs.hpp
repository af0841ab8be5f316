// Verdicts -> every output endpoint, as JSON lines ({"time":..,"property":..,
// "value":..}), one payload per verdict. `rvc check` writes to one file sink,
// `rvc monitor` to any number of file/zenoh/dds sinks: the same code, so both
// format and account for verdicts alike.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "engine/checker.hpp"
#include "msg/msg_types.hpp"
#include "transport/endpoint.hpp"
#include "transport/verdict_sink.hpp"

namespace rvc::runtime {

class VerdictOutputs {
 public:
  VerdictOutputs(std::vector<std::unique_ptr<transport::Sink>> sinks, bool discrete);
  // Typed verdicts (`--verdict-type rvc_msgs/msg/Verdict`): sinks whose flag
  // is set get each verdict as a CDR sample of `type` (encoded from the
  // verdict's JSON: its fields are time, property, value); the others JSON.
  void set_typed(const msg::MessageType* type, std::vector<bool> typed_sinks) {
    type_ = type;
    typed_ = std::move(typed_sinks);
  }

  // Timeline sinks (mcap:) place each verdict at the time of the step it is
  // about, in nanoseconds: the one set here (a bag's message log time, set
  // by check_bag before each message), else the wall clock when
  // `wall_clock` (live inputs: the timeline of a `ros2 bag record` made
  // alongside), else the verdict's own time (dense: seconds; discrete: the
  // step index, as nanoseconds).
  void set_step_time(uint64_t ns) {
    step_time_ = ns;
    has_step_time_ = true;
  }
  void use_wall_clock(bool wall_clock) { wall_clock_ = wall_clock; }
  bool has_timeline_sinks() const { return !timeline_.empty(); }
  // Whether a timeline sink copies the input messages (mcap:PATH?inputs=1),
  // and the copy: after the verdicts of the message's step.
  bool wants_inputs() const {
    for (auto* t : timeline_)
      if (t->wants_inputs()) return true;
    return false;
  }
  void put_input(const transport::InputMessage& message) {
    for (auto* t : timeline_)
      if (t->wants_inputs()) t->put_input(message);
  }

  // Also hands every verdict to `observer` (the results store, the
  // enforcer), before the sinks, in the engine thread.
  void observe(std::function<void(const engine::Verdict&)> observer) { observers_.push_back(std::move(observer)); }

  // Publishes one verdict on every sink. Throws (std::runtime_error) if a
  // sink cannot take it: verdicts that cannot be delivered end the run.
  void put(const engine::Verdict& verdict);
  // Publishes one ready JSON payload the same way (`rvc sync`: one set), as
  // a sample of the typed type on typed sinks.
  void put_payload(std::string_view payload);
  // As put_payload, with the typed sample already encoded.
  void put_encoded(std::string_view payload);
  // Nothing pending upstream: make buffered verdicts visible.
  void idle();
  // The end-of-stream marker, then a flush, on every sink. Throws as put().
  void finish();

  // Extra JSON members for the verdicts put until the next call (",\"handover\":true"
  // while a group replica replays a shard it took over); "" for none. JSON sinks only.
  void set_mark(std::string_view members) { mark_ = members; }
  std::string_view mark() const { return mark_; }

  uint64_t count() const { return count_; }
  size_t size() const { return sinks_.size(); }
  transport::Sink& sink(size_t i) { return *sinks_[i]; }

 private:
  std::vector<std::unique_ptr<transport::Sink>> sinks_;
  bool discrete_;
  uint64_t count_ = 0;
  std::string line_, sample_;
  std::string time_text_;  // the verdict's time as JSON text
  std::string_view mark_;
  const msg::MessageType* type_ = nullptr;
  std::vector<bool> typed_;
  std::vector<std::function<void(const engine::Verdict&)>> observers_;
  std::vector<transport::VerdictSink*> timeline_;  // sinks that take typed verdicts on a timeline
  std::vector<bool> is_timeline_;                  // per sink: put() is not called for it
  uint64_t step_time_ = 0;
  bool has_step_time_ = false, wall_clock_ = false;
  std::string cdr_;
  uint64_t log_time_of(const engine::Verdict& v) const;
  void encode_typed(std::string_view payload);  // sample_ = payload as a sample of type_, if set
};

}  // namespace rvc::runtime
