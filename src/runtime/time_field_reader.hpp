// Reads one time field (seconds, or a builtin_interfaces/Time {sec, nanosec})
// out of a message: a JSON object, or a typed CDR sample. `rvc hz` reads a
// message's stamp with it (latency) and, with --time-source stamps, the time
// the statistics run on. It reuses the decoders the checker reads dense time
// with (JsonDecoder, CdrDecoder with no field tests), so a stamp means the
// same in `rvc hz` as in a property.
#pragma once

#include <memory>
#include <string>
#include <string_view>

#include "engine/atom_table.hpp"
#include "msg/msg_types.hpp"

namespace rvc::io {
class CdrDecoder;
}  // namespace rvc::io

namespace rvc::runtime {

class TimeFieldReader {
 public:
  enum class Result { Ok, Missing, Malformed };

  // `field` is a path ("time", "header.stamp"). With a type, the samples are
  // CDR of that type: throws msg::MsgError if the type has no such field or
  // it is no number or Time.
  TimeFieldReader(const std::string& field, const msg::MessageType* type);
  ~TimeFieldReader();
  TimeFieldReader(const TimeFieldReader&) = delete;
  TimeFieldReader& operator=(const TimeFieldReader&) = delete;

  // Missing: valid message without the field (JSON only). Malformed: not a
  // JSON object / not a sample of the type; `error` says why.
  Result read(std::string_view payload, double& seconds, std::string& error);
  const std::string& field() const { return field_; }

 private:
  std::string field_;
  engine::AtomTable no_tests_;  // the decoders evaluate field tests; here there are none
  struct Json;  // the decoder and simdjson's parser (simdjson.h stays out of this header)
  std::unique_ptr<Json> json_;
  std::unique_ptr<io::CdrDecoder> cdr_;
};

}  // namespace rvc::runtime
