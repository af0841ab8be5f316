// libFuzzer harness: the ROS 2 CDR decoder and encoder (src/io/cdr_codec.cpp).
//
// The first byte picks a message type (every bundled type, plus a type built
// here with each kind of field: bounded strings, nested sequences, fixed
// arrays); the rest is the sample. Any input must decode or be refused with a
// CdrError; ASan/UBSan findings and reads past the sample count as crashes.
// Oracle: what decodes is a fixed point of encode-then-decode (both
// endiannesses), so the decoder and the encoder agree on every wire rule.
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "io/cdr_codec.hpp"
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

struct Types {
  rvc::msg::TypeRegistry registry;
  std::vector<const rvc::msg::MessageType*> all;
  Types() {
    registry.add_definition("rvcfuzz_msgs/msg/Mixed", kMixed, "fuzz_cdr.cpp");
    all.push_back(&registry.resolve("rvcfuzz_msgs/msg/Mixed"));
    for (const auto& name : rvc::msg::TypeRegistry::bundled_types()) all.push_back(&registry.resolve(name));
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Types types;
  if (size < 1) return 0;
  const auto& type = *types.all[data[0] % types.all.size()];
  const std::string_view sample(reinterpret_cast<const char*>(data) + 1, size - 1);
  std::string json;
  rvc::io::CdrError error;
  if (!rvc::io::cdr_to_json(type, sample, json, error)) return 0;
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
