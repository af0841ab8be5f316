#include "runtime/forwarder.hpp"

namespace rvc::runtime {

std::string monitored_topic(const std::string& input_uri) { return input_uri + "_mon"; }

Forwarder::Forwarder(Feed& inner, std::string property, std::unique_ptr<transport::Sink> sink, VerdictOutputs& outputs)
    : inner_(inner), property_(std::move(property)), sink_(std::move(sink)) {
  outputs.observe([this](const engine::Verdict& v) {
    if (v.property == property_) holds_ = v.value;
  });
}

void Forwarder::feed_input(uint32_t input, std::string_view payload, uint64_t position) {
  const uint64_t before = inner_.stats().accepted;
  inner_.feed_input(input, payload, position);
  if (inner_.stats().accepted == before) return;  // rejected: not a message the property judged
  if (holds_) {
    sink_->put(payload, ++forwarded_);
  } else {
    ++held_back_;
  }
}

void Forwarder::add_stats(io::JsonObject& out) const {
  inner_.add_stats(out);
  out.add("forwarded", forwarded_).add("held_back", held_back_);
}

void Forwarder::finish() {
  sink_->put_eos(forwarded_);
  sink_->flush();
}

}  // namespace rvc::runtime
