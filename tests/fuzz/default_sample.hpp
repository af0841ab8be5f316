// What the .msg and .idl harnesses check of every type they resolve: its
// default sample (every field its default, as `rvc msg encode` writes {})
// encodes, decodes, and encodes back to the same bytes. A default the parser
// accepted but the encoder cannot write (`bool b 1` once was) traps, as does a
// type over the registry's size limit (and any allocation over the malloc
// limit, resource_limits.hpp).
#pragma once

#include <string>

#include "io/cdr_codec.hpp"
#include "msg/msg_types.hpp"

namespace rvc::fuzz {

inline bool has_wstring(const msg::MessageType& t, int depth = 0) {
  if (depth > 80) return false;
  for (const auto& f : t.fields) {
    if (f.type.prim == msg::Prim::WString) return true;
    if (f.type.prim == msg::Prim::Message && f.type.message && has_wstring(*f.type.message, depth + 1)) return true;
  }
  return false;
}

inline void check_default_sample(const msg::MessageType& type) {
  if (type.fixed_bytes > msg::kMaxFixedBytes) __builtin_trap();  // the registry's limit held
  // Samples up to 1 MiB make the round trip: a 64 MiB one, allowed, takes seconds under ASan
  // (a timeout, not a finding; the first 60 s run hit one).
  if (type.fixed_bytes > (uint64_t{1} << 20)) return;
  if (has_wstring(type)) return;  // refused by the codec with a message
  std::string sample, error, json, again;
  if (!io::json_to_cdr(type, "{}", sample, error)) __builtin_trap();  // a default the encoder refuses
  io::CdrError bad;
  if (!io::cdr_to_json(type, sample, json, bad)) __builtin_trap();
  if (!io::json_to_cdr(type, json, again, error) || again != sample) __builtin_trap();
}

}  // namespace rvc::fuzz
