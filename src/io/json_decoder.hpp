// Decodes one JSON object into the values of every field test of a Checker's
// atom table, reading each field once however many tests and properties use it.
//
// Missing fields follow Reelay: a test on an absent field keeps the value it
// had after the previous message (false before the field was ever seen);
// presence tests ({k: *}) are re-evaluated every message. A field of the
// wrong type (a string where a number is compared) also keeps its value and
// is reported as a warning. In strict mode both are errors that reject the
// message instead.
#pragma once

#include <simdjson.h>

#include <cstdint>
#include <string>
#include <vector>

#include "engine/atom_table.hpp"

namespace rvc::io {

struct DecoderOptions {
  bool need_time = false;          // dense time: every message must carry a time
  std::string time_field = "time";
  bool strict = false;
};

class JsonDecoder {
 public:
  JsonDecoder(const engine::AtomTable& atoms, DecoderOptions options);

  // Decodes into a staging copy; returns false (with `error`) if the message
  // must be rejected, leaving the committed values untouched. Warnings about
  // fields that kept their previous value are appended to `warnings`.
  bool decode(simdjson::ondemand::object object, std::string& error, std::vector<std::string>* warnings = nullptr);
  // Makes the last successful decode current.
  void commit() { current_.swap(next_); }

  const uint8_t* values() const { return current_.data(); }
  double time() const { return time_; }

 private:
  struct KeyNode {
    std::string name;
    std::vector<int> tests;          // atom ids testing this field
    std::vector<KeyNode> children;   // nested fields (a.b.c)
    bool is_time = false;
    uint32_t seen = 0;               // message generation when last present (strict mode)
  };
  KeyNode* child(KeyNode& parent, const std::string& name);
  bool decode_object(simdjson::ondemand::object object, KeyNode& node, std::string& error,
                     std::vector<std::string>* warnings);
  bool apply_tests(KeyNode& node, simdjson::ondemand::value value, simdjson::ondemand::json_type type,
                   std::string& error, std::vector<std::string>* warnings);
  bool check_missing(const KeyNode& node, const std::string& prefix, std::string& error) const;

  const engine::AtomTable& atoms_;
  DecoderOptions options_;
  KeyNode root_;
  std::vector<int> presence_tests_;
  std::vector<uint8_t> current_, next_;
  double time_ = 0, next_time_ = 0;
  bool saw_time_ = false;
  uint32_t generation_ = 0;
};

}  // namespace rvc::io
