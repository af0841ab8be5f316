#include "session.hpp"

#include <utility>

namespace rvc::python {

Session::Session(std::vector<engine::PropertySpec> properties, SessionOptions options)
    : options_(std::move(options)) {
  runtime::PipelineOptions po;
  po.model = options_.dense ? engine::TimeModel::Dense : engine::TimeModel::Discrete;
  po.emit_all = options_.emit_all;
  po.time_field = options_.time_field;
  po.position_name = "message";
  po.robustness = options_.robustness;
  po.explain = options_.explain;
  po.max_data_values = options_.max_data_values;
  po.origin = options_.origin_zero ? runtime::Origin::Zero : runtime::Origin::First;
  if (options_.max_message_size) po.max_message_size = po.max_typed_message_size = options_.max_message_size;
  po.on_report = [this](const std::string& text) { on_report(text); };
  if (!options_.type.empty()) {
    for (const auto& dir : options_.msg_paths) registry_.add_search_path(dir);
    po.type = &registry_.resolve(options_.type);
  }
  pipeline_ = std::make_unique<runtime::Pipeline>(properties, po,
                                                  [this](const engine::Verdict& v) { on_verdict(v); });
}

void Session::on_verdict(const engine::Verdict& v) {
  const std::vector<std::string>& names = pipeline_->checker().names();
  Captured c{static_cast<uint32_t>(&v.property - names.data()), v.time, v.value, v.robustness, {}, false};
  if (v.robust) c.value = v.robustness > 0;
  if (v.explanation) {
    c.explanation = *v.explanation;
    c.explained = true;
  }
  captured_.push_back(std::move(c));
}

void Session::on_report(const std::string& text) {
  if (text.rfind("warning: ", 0) == 0) warnings_.push_back(text.substr(9));
  else rejections_.push_back(text);
}

bool Session::feed_lenient(std::string_view payload) {
  const uint64_t rejected = pipeline_->stats().rejected;
  pipeline_->feed(payload, ++position_);
  return pipeline_->stats().rejected == rejected;
}

void Session::feed(std::string_view payload) {
  if (feed_lenient(payload)) return;
  std::string text = rejections_.empty() ? "message " + std::to_string(position_) + " refused" : rejections_.back();
  rejections_.clear();
  throw RejectedMessage(text);
}

void Session::tick(double t) { pipeline_->tick(t); }

}  // namespace rvc::python
