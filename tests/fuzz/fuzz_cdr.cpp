// libFuzzer harness: the ROS 2 CDR decoder and encoder (src/io/cdr_codec.cpp).
//
// The first byte picks a message type (every bundled type, plus a type built
// here with each kind of field: bounded strings, nested sequences, fixed
// arrays); the rest is the sample. Any input must decode or be refused with a
// CdrError; ASan/UBSan findings and reads past the sample count as crashes.
// Oracles: what decodes is a fixed point of encode-then-decode (both
// endiannesses), so the decoder and the encoder agree on every wire rule; and
// the typed input's decoder (io::CdrDecoder, straight into test values)
// refuses exactly what cdr_to_json refuses, with the same error.
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "engine/checker.hpp"
#include "io/cdr_codec.hpp"
#include "io/cdr_decoder.hpp"
#include "msg/type_registry.hpp"

namespace {

const char* kMixed =
    "uint8 K = 3\n"
    "string<=6 name\n"
    "int8[] small\n"
    "float64[2] pair\n"
    "geometry_msgs/Point[<=3] points\n"
    "std_msgs/Header header\n"
    "bool[] flags\n"
    "string[] words\n"
    "uint64 big\n"
    "std_msgs/Empty nothing\n"
    "int16[<=2] tail\n";

// A checker testing every top-level field of a type (and, in Mixed, nested
// and string fields), and the typed decoder for it.
struct Typed {
  rvc::engine::Checker checker{rvc::engine::TimeModel::Discrete, false, [](const rvc::engine::Verdict&) {}};
  std::unique_ptr<rvc::io::CdrDecoder> decoder;
  explicit Typed(const rvc::msg::MessageType& type) {
    std::string spec =
        "{header.stamp.sec > 3} || {name == \"ab\"} || {pair} || {points[1].x > 0} || {small[0] < 3} || "
        "{words[1] == \"a\"} || {flags[2]: *}";
    if (type.name != "Mixed") {
      spec.clear();
      for (const auto& f : type.fields) spec += (spec.empty() ? "{" : " || {") + f.name + ": *}";
    }
    if (!spec.empty()) checker.add_property({"p", spec});
    decoder = std::make_unique<rvc::io::CdrDecoder>(checker.atoms(), type, rvc::io::DecoderOptions{});
  }
};

struct Types {
  rvc::msg::TypeRegistry registry;
  std::vector<const rvc::msg::MessageType*> all;
  std::vector<std::unique_ptr<Typed>> typed;
  Types() {
    registry.add_definition("rvcfuzz_msgs/msg/Mixed", kMixed, "fuzz_cdr.cpp");
    all.push_back(&registry.resolve("rvcfuzz_msgs/msg/Mixed"));
    for (const auto& name : rvc::msg::TypeRegistry::bundled_types()) all.push_back(&registry.resolve(name));
    for (const auto* t : all) typed.push_back(std::make_unique<Typed>(*t));
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Types types;
  if (size < 1) return 0;
  const size_t which = data[0] % types.all.size();
  const auto& type = *types.all[which];
  const std::string_view sample(reinterpret_cast<const char*>(data) + 1, size - 1);
  std::string json;
  rvc::io::CdrError error;
  const bool ok = rvc::io::cdr_to_json(type, sample, json, error);
  std::string typed_error;
  if (types.typed[which]->decoder->decode(sample, typed_error) != ok) std::abort();
  if (!ok && typed_error != "bad " + type.full_name() + " sample: " + error.to_string()) std::abort();
  if (!ok) return 0;
  for (bool big : {false, true}) {
    std::string encoded, why, again;
    rvc::io::CdrWriteOptions options;
    options.big_endian = big;
    if (!rvc::io::json_to_cdr(type, json, encoded, why, options)) std::abort();  // decoded JSON must encode
    rvc::io::CdrError error2;
    if (!rvc::io::cdr_to_json(type, encoded, again, error2) || again != json) std::abort();
  }
  return 0;
}
