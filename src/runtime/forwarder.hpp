// ROSMonitoring's filter action (`rvc monitor --forward PROPERTY`): every
// message the property still holds after is republished on `<topic>_mon`
// (or --forward-to); a message that violates it is held back. Downstream
// nodes subscribe to the _mon topic and only ever see traffic that passed.
//
// A Feed around the monitor's own: the message is checked first, then
// forwarded (or not) on the engine thread, in input order.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "runtime/feed.hpp"
#include "runtime/verdict_outputs.hpp"
#include "transport/endpoint.hpp"

namespace rvc::runtime {

// "zenoh:vehicle/status" -> "zenoh:vehicle/status_mon", "dds:/chatter" ->
// "dds:/chatter_mon" (the ROSMonitoring convention).
std::string monitored_topic(const std::string& input_uri);

class Forwarder final : public Feed {
 public:
  // Observes `outputs` for the property's verdicts; `sink` gets what passes.
  Forwarder(Feed& inner, std::string property, std::unique_ptr<transport::Sink> sink, VerdictOutputs& outputs);

  void feed_input(uint32_t input, std::string_view payload, uint64_t position) override;
  void warn(const io::LineError& warning) override { inner_.warn(warning); }
  void idle() override {
    inner_.idle();
    sink_->idle();
  }
  void end_of_input() override { inner_.end_of_input(); }
  double next_deadline() override { return inner_.next_deadline(); }
  void tick(double stream_now) override { inner_.tick(stream_now); }
  double last_stamp() const override { return inner_.last_stamp(); }
  const PipelineStats& stats() const override { return inner_.stats(); }
  uint64_t violations() const override { return inner_.violations(); }
  void finish_report() override { inner_.finish_report(); }
  void add_stats(io::JsonObject& out) const override;
  void finish();  // end-of-stream marker, flush

 private:
  Feed& inner_;
  std::string property_;
  std::unique_ptr<transport::Sink> sink_;
  bool holds_ = false;  // the property's latest verdict
  uint64_t forwarded_ = 0, held_back_ = 0;
};

}  // namespace rvc::runtime
