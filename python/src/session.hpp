// One stream of messages checked against named properties, in-process: a
// runtime::Pipeline (the decoder, checker and rules `rvc check` and
// `rvc monitor` use) whose verdicts are collected for Python instead of
// written as JSON lines, and whose error lines become exceptions.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "msg/type_registry.hpp"
#include "runtime/pipeline.hpp"

namespace rvc::python {

struct Captured {
  uint32_t property;  // index in Session::names()
  double time;        // step index in discrete time
  bool value;
  double robustness;  // robustness semantics: the verdict's value
  std::vector<std::string> explanation;
  bool explained = false;
};

struct SessionOptions {
  bool dense = false;
  bool robustness = false;
  bool explain = false;
  bool emit_all = false;  // every step (discrete), not only changes
  std::string time_field = "time";
  std::string type;                    // ROS 2 type of CDR samples; empty: dict / JSON messages
  std::vector<std::string> msg_paths;  // folders of .msg / .idl definitions for `type`
  uint32_t max_data_values = 100000;
  // Dense time: where the timeline starts (runtime/engine_time.hpp). Reelay's
  // drop-in API keeps Reelay's 0; rvc.Monitor starts at the first message.
  bool origin_zero = false;
  size_t max_message_size = 0;  // every message's cap; 0: the defaults (1 MiB JSON, 256 MiB CDR)
};

// A message rvc refused (its text names why and where); Python's ValueError.
struct RejectedMessage : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Session {
 public:
  // Throws spec::SpecError for a bad property, msg::MsgError for an unknown type.
  Session(std::vector<engine::PropertySpec> properties, SessionOptions options);

  // One message: a JSON object's text, or a CDR sample with a type. Verdicts
  // are appended to captured(). Throws RejectedMessage when it is refused
  // (the monitors then did not move), data::DataLimitError past the limit.
  void feed(std::string_view payload);
  // The same, but a refused message is only counted and its text kept in
  // take_rejections() (update_many: one bad message costs only itself).
  bool feed_lenient(std::string_view payload);
  // A message refused before it reached the pipeline (a value JSON cannot
  // hold): counted as given and rejected, so the counts still add up.
  void refuse() {
    ++position_;
    ++refused_;
  }
  // Dense time: an empty message at `t` (docs/semantics.md, "Ticks").
  void tick(double t);

  std::vector<Captured>& captured() { return captured_; }
  bool has_warnings() const { return !warnings_.empty(); }
  std::vector<std::string> take_warnings() { return std::exchange(warnings_, {}); }
  std::vector<std::string> take_rejections() { return std::exchange(rejections_, {}); }
  const runtime::PipelineStats& stats() const { return pipeline_->stats(); }
  uint64_t violations() const { return pipeline_->violations(); }
  const std::vector<std::string>& names() const { return pipeline_->checker().names(); }
  const SessionOptions& options() const { return options_; }
  uint64_t messages() const { return position_; }  // given, refused ones included
  uint64_t rejected() const { return pipeline_->stats().rejected + refused_; }
  // Dense time: where the monitors are, in seconds (the checker counts nanoseconds from the origin).
  double clock() const {
    const double c = pipeline_->checker().clock();
    return pipeline_->engine_time().started() ? pipeline_->engine_time().seconds(c) : c;
  }
  bool has_data_references() const { return pipeline_->checker().has_data_references(); }

 private:
  void on_verdict(const engine::Verdict& v);
  void on_report(const std::string& text);

  SessionOptions options_;
  msg::TypeRegistry registry_;  // owns the type the pipeline decodes
  std::vector<Captured> captured_;
  std::vector<std::string> warnings_, rejections_;
  std::unique_ptr<runtime::Pipeline> pipeline_;
  uint64_t position_ = 0;
  uint64_t refused_ = 0;
};

}  // namespace rvc::python
