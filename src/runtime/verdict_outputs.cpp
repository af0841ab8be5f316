#include "runtime/verdict_outputs.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "io/cdr_codec.hpp"
#include "io/json_writer.hpp"
#include "io/verdict_writer.hpp"
#include "spec/exact_time.hpp"

namespace rvc::runtime {

VerdictOutputs::VerdictOutputs(std::vector<std::unique_ptr<transport::Sink>> sinks, bool discrete)
    : sinks_(std::move(sinks)), discrete_(discrete) {
  for (auto& s : sinks_) {
    auto* t = dynamic_cast<transport::VerdictSink*>(s.get());
    if (t) timeline_.push_back(t);
    is_timeline_.push_back(t != nullptr);
  }
}

uint64_t VerdictOutputs::log_time_of(const engine::Verdict& v) const {
  if (has_step_time_) return step_time_;
  if (wall_clock_)
    return static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                     std::chrono::system_clock::now().time_since_epoch())
                                     .count());
  if (v.exact) return v.time_ns > 0 ? static_cast<uint64_t>(v.time_ns) : 0;  // dense: the instant, exactly
  if (!(v.time > 0)) return 0;
  if (discrete_) return static_cast<uint64_t>(v.time);
  const double ns = std::round(v.time * 1e9);
  return ns >= 1.8e19 ? std::numeric_limits<uint64_t>::max() : static_cast<uint64_t>(ns);
}

void VerdictOutputs::put(const engine::Verdict& v) {
  for (auto& observer : observers_) observer(v);
  // rvc_msgs/msg/Verdict in CDR: for timeline sinks, and for typed sinks of that type.
  const bool verdict_type = type_ && type_->full_name() == "rvc_msgs/msg/Verdict";
  if (!timeline_.empty() || verdict_type) {
    cdr_.clear();
    const uint64_t at = log_time_of(v);
    io::append_verdict_cdr(cdr_, v.time, v.property, v.value, at,
                           v.robust ? v.robustness : std::numeric_limits<double>::quiet_NaN(), v.explanation);
    for (auto* t : timeline_) t->put_verdict(cdr_, at);
  }
  line_.clear();
  time_text_.clear();
  if (v.exact) spec::append_seconds(time_text_, v.time_ns);  // exact decimal seconds (dense)
  else io::append_number(time_text_, v.time);
  if (v.robust) io::append_robustness_at(line_, time_text_, v.property, v.robustness);
  else io::append_verdict_at(line_, time_text_, v.property, v.value);
  if (v.explanation && (!type_ || verdict_type)) {  // {"time":..,"value":false,"explain":["...", ...]} (other typed verdicts have no field for it)
    line_.resize(line_.size() - 2);  // "}\n"
    line_ += ",\"explain\":[";
    for (size_t i = 0; i < v.explanation->size(); ++i) {
      if (i) line_ += ',';
      io::append_json_string(line_, (*v.explanation)[i]);
    }
    line_ += "]}\n";
  }
  if (v.known_at == v.known_at && !type_) {  // bounded future: not NaN
    if (v.exact) io::append_known_at_text(line_, spec::seconds_text(v.known_ns));
    else io::append_known_at(line_, v.known_at);
  }
  if (!mark_.empty() && !type_) line_.insert(line_.size() - 2, mark_);  // before "}\n"
  line_.pop_back();  // one message per verdict: no newline (file sinks add their own)
  if (verdict_type) sample_ = cdr_;
  else encode_typed(line_);
  put_encoded(line_);
}

void VerdictOutputs::put_payload(std::string_view payload) {
  // Sets (rvc sync) are no verdicts: a timeline sink has no channel for them.
  if (!timeline_.empty()) throw std::runtime_error("an mcap: output takes verdicts (rvc check, rvc monitor) only");
  encode_typed(payload);
  put_encoded(payload);
}

void VerdictOutputs::encode_typed(std::string_view payload) {
  if (type_) {
    std::string error;
    if (!io::json_to_cdr(*type_, payload, sample_, error))
      throw std::runtime_error("as " + type_->full_name() + ": " + error + " in " + std::string(payload));
  }
}

void VerdictOutputs::put_encoded(std::string_view payload) {
  ++count_;
  for (size_t i = 0; i < sinks_.size(); ++i)
    if (!is_timeline_[i]) sinks_[i]->put(type_ && typed_[i] ? sample_ : payload, count_);
}

void VerdictOutputs::idle() {
  for (auto& s : sinks_) s->idle();
}

void VerdictOutputs::finish() {
  for (auto& s : sinks_) {
    s->put_eos(count_);
    s->flush();
  }
}

}  // namespace rvc::runtime
