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

namespace rvc::runtime {

class VerdictOutputs {
 public:
  VerdictOutputs(std::vector<std::unique_ptr<transport::Sink>> sinks, bool discrete)
      : sinks_(std::move(sinks)), discrete_(discrete) {}
  // Typed verdicts (`--verdict-type rvc_msgs/msg/Verdict`): sinks whose flag
  // is set get each verdict as a CDR sample of `type` (encoded from the
  // verdict's JSON: its fields are time, property, value); the others JSON.
  void set_typed(const msg::MessageType* type, std::vector<bool> typed_sinks) {
    type_ = type;
    typed_ = std::move(typed_sinks);
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
  // Nothing pending upstream: make buffered verdicts visible.
  void idle();
  // The end-of-stream marker, then a flush, on every sink. Throws as put().
  void finish();

  // Extra JSON members for the verdicts put until the next call (",\"handover\":true"
  // while a group replica replays a shard it took over); "" for none. JSON sinks only.
  void set_mark(std::string_view members) { mark_ = members; }

  uint64_t count() const { return count_; }
  size_t size() const { return sinks_.size(); }
  transport::Sink& sink(size_t i) { return *sinks_[i]; }

 private:
  std::vector<std::unique_ptr<transport::Sink>> sinks_;
  bool discrete_;
  uint64_t count_ = 0;
  std::string line_, sample_;
  std::string_view mark_;
  const msg::MessageType* type_ = nullptr;
  std::vector<bool> typed_;
  std::vector<std::function<void(const engine::Verdict&)>> observers_;
};

}  // namespace rvc::runtime
