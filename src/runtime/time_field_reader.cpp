#include "runtime/time_field_reader.hpp"

#include <simdjson.h>

#include "io/cdr_decoder.hpp"
#include "io/json_decoder.hpp"

namespace rvc::runtime {

struct TimeFieldReader::Json {
  Json(const engine::AtomTable& atoms, const io::DecoderOptions& options) : decoder(atoms, options) {}
  io::JsonDecoder decoder;
  simdjson::ondemand::parser parser;
  std::string scratch;  // the payload with simdjson's padding
};

TimeFieldReader::TimeFieldReader(const std::string& field, const msg::MessageType* type) : field_(field) {
  io::DecoderOptions options;
  options.need_time = true;
  options.time_field = field;
  options.layouts = false;  // one field per message: nothing to gain from learning layouts
  if (type) {
    cdr_ = std::make_unique<io::CdrDecoder>(no_tests_, *type, options);
  } else {
    json_ = std::make_unique<Json>(no_tests_, options);
  }
}

TimeFieldReader::~TimeFieldReader() = default;

TimeFieldReader::Result TimeFieldReader::read(std::string_view payload, double& seconds, std::string& error) {
  if (cdr_) {
    if (!cdr_->decode(payload, error)) return Result::Malformed;
    cdr_->commit();
    seconds = cdr_->time();
    return Result::Ok;
  }
  json_->scratch.assign(payload.data(), payload.size());
  json_->scratch.append(simdjson::SIMDJSON_PADDING, '\0');
  simdjson::ondemand::document doc;
  simdjson::ondemand::object object;
  if (auto err = json_->parser.iterate(json_->scratch.data(), payload.size(), json_->scratch.size()).get(doc)) {
    error = std::string("invalid JSON: ") + simdjson::error_message(err);
    return Result::Malformed;
  }
  if (auto err = doc.get_object().get(object)) {
    error = std::string("expected a JSON object: ") + simdjson::error_message(err);
    return Result::Malformed;
  }
  if (!json_->decoder.decode(object, error)) {
    // Absent is Missing (the caller may let it pass); a field of the wrong
    // type, or bad JSON, is never a time.
    if (json_->decoder.malformed() || error.rfind("missing time field", 0) != 0) return Result::Malformed;
    error = "no field \"" + field_ + "\"";
    return Result::Missing;
  }
  json_->decoder.commit();
  seconds = json_->decoder.time();
  return Result::Ok;
}

}  // namespace rvc::runtime
