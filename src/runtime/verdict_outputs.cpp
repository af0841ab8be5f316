#include "runtime/verdict_outputs.hpp"

#include <stdexcept>

#include "io/cdr_codec.hpp"
#include "io/json_writer.hpp"
#include "io/verdict_writer.hpp"

namespace rvc::runtime {

void VerdictOutputs::put(const engine::Verdict& v) {
  for (auto& observer : observers_) observer(v);
  line_.clear();
  if (v.robust) io::append_robustness(line_, v.time, discrete_, v.property, v.robustness);
  else io::append_verdict(line_, v.time, discrete_, v.property, v.value);
  if (v.explanation && !type_) {  // {"time":..,"value":false,"explain":["...", ...]} (typed verdicts have no field for it)
    line_.resize(line_.size() - 2);  // "}\n"
    line_ += ",\"explain\":[";
    for (size_t i = 0; i < v.explanation->size(); ++i) {
      if (i) line_ += ',';
      io::append_json_string(line_, (*v.explanation)[i]);
    }
    line_ += "]}\n";
  }
  if (v.known_at == v.known_at && !type_) io::append_known_at(line_, v.known_at);  // bounded future: not NaN
  line_.pop_back();  // one message per verdict: no newline (file sinks add their own)
  put_payload(line_);
}

void VerdictOutputs::put_payload(std::string_view payload) {
  ++count_;
  if (type_) {
    std::string error;
    if (!io::json_to_cdr(*type_, payload, sample_, error))
      throw std::runtime_error("as " + type_->full_name() + ": " + error + " in " + std::string(payload));
  }
  for (size_t i = 0; i < sinks_.size(); ++i) sinks_[i]->put(type_ && typed_[i] ? sample_ : payload, count_);
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
