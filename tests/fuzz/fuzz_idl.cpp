// libFuzzer harness: the IDL parser (src/msg/idl_parser.cpp) and the type
// registry that links what it read.
//
// Any input must end as types or a MsgError: another exception escapes and
// counts as a crash, as do ASan/UBSan findings and stack overflows. Every
// type read must then resolve (linked, cycles refused with a MsgError) and
// have a field list whose printed types name only known primitives or types,
// and its default sample must encode and decode (default_sample.hpp), within
// the harness's memory limits (resource_limits.hpp: an @default or array the
// size limits let through that allocates gigabytes is a finding).
#include <cstdint>
#include <string>

#include "default_sample.hpp"
#include "msg/idl_parser.hpp"
#include "msg/type_registry.hpp"
#include "resource_limits.hpp"

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  rvc::fuzz::add_resource_limits(argc, argv);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<rvc::msg::MessageType> types;
  try {
    types = rvc::msg::parse_idl(text, "fuzz.idl");
  } catch (const rvc::msg::MsgError&) {
    return 0;
  }
  rvc::msg::TypeRegistry registry;
  registry.add_idl(text, "fuzz.idl");
  for (const auto& t : types) {
    try {
      const rvc::msg::MessageType& linked = registry.resolve(t.full_name());
      for (const auto& f : linked.fields)
        if (f.type.prim == rvc::msg::Prim::Message && !f.type.message) __builtin_trap();  // resolved means linked
      rvc::fuzz::check_default_sample(linked);
    } catch (const rvc::msg::MsgError&) {
    }
  }
  return 0;
}
