#include "io/diagnostics.hpp"

#include <cmath>
#include <stdexcept>

#include "io/cdr_codec.hpp"
#include "io/json_writer.hpp"
#include "msg/type_registry.hpp"

namespace rvc::io {
namespace {

// builtin_interfaces/Time: whole seconds and the nanoseconds after them.
JsonObject time_json(double stamp) {
  if (!std::isfinite(stamp) || stamp < 0) stamp = 0;
  double sec = std::floor(stamp);
  auto nanosec = static_cast<int64_t>(std::llround((stamp - sec) * 1e9));
  if (nanosec >= 1000000000) {  // 0.9999999999 rounds up to the next second
    sec += 1;
    nanosec -= 1000000000;
  }
  return JsonObject().add("sec", static_cast<int64_t>(sec)).add("nanosec", nanosec);
}

const msg::MessageType& array_type() {
  // Resolved once: the bundled definitions never change while rvc runs.
  static msg::TypeRegistry registry;
  static const msg::MessageType& type = registry.resolve(kDiagnosticArrayType);
  return type;
}

}  // namespace

const char* to_string(DiagLevel level) {
  switch (level) {
    case DiagLevel::Ok: return "OK";
    case DiagLevel::Warn: return "WARN";
    case DiagLevel::Error: return "ERROR";
    case DiagLevel::Stale: return "STALE";
  }
  return "UNKNOWN";
}

std::string diagnostic_array_json(double stamp, const std::vector<DiagStatus>& statuses, std::string_view frame_id) {
  JsonArray status;
  for (const DiagStatus& s : statuses) {
    JsonArray values;
    for (const auto& [key, value] : s.values) values.add(JsonObject().add("key", key).add("value", value));
    status.add(JsonObject()
                   .add("level", static_cast<unsigned>(s.level))
                   .add("name", s.name)
                   .add("message", s.message)
                   .add("hardware_id", s.hardware_id)
                   .add_raw("values", values.str()));
  }
  return JsonObject()
      .add("header", JsonObject().add("stamp", time_json(stamp)).add("frame_id", frame_id))
      .add_raw("status", status.str())
      .str();
}

const msg::MessageType& diagnostic_array_type() { return array_type(); }

std::string diagnostic_array_cdr(double stamp, const std::vector<DiagStatus>& statuses, std::string_view frame_id) {
  std::string sample, error;
  if (!json_to_cdr(array_type(), diagnostic_array_json(stamp, statuses, frame_id), sample, error))
    throw std::runtime_error("diagnostics: cannot encode a DiagnosticArray: " + error);
  return sample;
}

}  // namespace rvc::io
