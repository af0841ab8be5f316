// libFuzzer harness: the .msg parser (src/msg/msg_parser.cpp, msg_values.cpp)
// and the type registry, read as an MCAP bag's ros2msg schema: a definition
// of fuzz_msgs/msg/T, then others, each after a line of '=' and "MSG: pkg/Name".
//
// Any input must end as a linked type or a MsgError (another exception
// escapes and is a crash, as are sanitizer findings). A type that resolves
// must have its default sample encode, decode and encode back to the same
// bytes (default_sample.hpp), within the harness's memory limits
// (resource_limits.hpp): `int32[4294967295] a` filled 16 GiB before the size
// limits, and a default the parser accepts but no encoder writes is a finding.
#include <cstdint>
#include <string>

#include "default_sample.hpp"
#include "msg/type_registry.hpp"
#include "resource_limits.hpp"

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  rvc::fuzz::add_resource_limits(argc, argv);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  rvc::msg::TypeRegistry registry;
  try {
    registry.add_concatenated("fuzz_msgs/msg/T", text, "fuzz.msg");
    const rvc::msg::MessageType& type = registry.resolve("fuzz_msgs/msg/T");
    for (const auto& f : type.fields)
      if (f.type.prim == rvc::msg::Prim::Message && !f.type.message) __builtin_trap();  // resolved means linked
    rvc::fuzz::check_default_sample(type);
  } catch (const rvc::msg::MsgError&) {
  }
  return 0;
}
