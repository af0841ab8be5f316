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
#include "io/bound_values.hpp"

namespace rvc::io {

struct DecoderOptions {
  bool need_time = false;          // dense time: every message must carry a time
  std::string time_field = "time";
  bool strict = false;
  bool robustness = false;  // also each test's margin (--robustness; general path only)
};

class JsonDecoder {
 public:
  JsonDecoder(const engine::AtomTable& atoms, DecoderOptions options);

  // Decodes into a staging copy; returns false (with `error`) if the message
  // must be rejected, leaving the committed values untouched. Warnings about
  // fields that kept their previous value are appended to `warnings`.
  bool decode(simdjson::ondemand::object object, std::string& error, std::vector<std::string>* warnings = nullptr);
  // After decode() returned false: whether the JSON itself was malformed
  // (rather than valid JSON that the properties cannot use).
  bool malformed() const { return malformed_; }
  // Makes the last successful decode current.
  void commit() {
    current_.swap(next_);
    bound_.swap(next_bound_);
    if (options_.robustness) margin_.swap(next_margin_);
  }

  const uint8_t* values() const { return current_.data(); }
  // Data references ({id: *x}): per atom, the id of the value its field held
  // last (BoundValues; 0 before any); null when no test binds.
  const uint32_t* bound() const { return bound_.empty() ? nullptr : bound_.data(); }
  // With DecoderOptions::robustness: each test's robustness (io::test_margin);
  // -inf for a field never seen, as Reelay starts.
  const double* margins() const { return margin_.data(); }
  // The values data references bound so far (--explain names them).
  const BoundValues& bound_values() const { return bound_ids_; }
  double time() const { return time_; }

 private:
  // Fast paths: most fields are tested only as Booleans or only as numbers;
  // those read their value with one typed call and no per-test type checks.
  enum class Kind : uint8_t { Bool, Number, General };
  struct BoolTest {  // result = value ? if_true : if_false
    int id;
    uint8_t if_true, if_false;
  };
  struct KeyNode {
    std::string name;
    std::vector<int> tests;          // atom ids testing this field
    std::vector<KeyNode> children;   // nested fields (a.b.c)
    // The time (--time-field, a path): 1 the field itself, a number of seconds or a
    // builtin_interfaces/Time object; 2 its seconds (sec, ROS 1 secs); 3 its nanoseconds (nanosec, nsecs).
    uint8_t time_part = 0;
    bool raw_comparable = true;      // name has no quote/backslash: compare raw JSON key bytes
    bool any_escaped_child = false;  // some child needs the unescaped-key comparison
    // Messages of one topic list their fields in the same order, so each
    // field position remembers the key it saw last time and what it matched
    // (nullptr: a field no test reads). One comparison confirms the guess.
    struct Seen {
      std::string key;
      KeyNode* target;
      // Keys of up to 7 bytes: the key and its closing quote as one 8-byte
      // word (little-endian) and the mask of its bytes, compared in one load.
      uint64_t word = 0, mask = 0;
    };
    std::vector<Seen> by_position;
    Kind kind = Kind::General;
    std::vector<BoolTest> bool_tests;
    uint32_t seen = 0;               // message generation when last present (strict mode)
    bool is_index = false;           // an array element: name "[N]"
    std::vector<KeyNode*> by_index;  // the element children by index (null: not tested)
  };
  void prepare(KeyNode& node);
  static void remember(KeyNode& node, size_t position, simdjson::ondemand::raw_json_string raw, KeyNode* target);
  bool fast_path(KeyNode& node, simdjson::ondemand::value& value);
  KeyNode* child(KeyNode& parent, const std::string& name);
  bool decode_object(simdjson::ondemand::object object, KeyNode& node, std::string& error,
                     std::vector<std::string>* warnings);
  bool invalid(std::string& error, simdjson::error_code err, const std::string& field = {});
  bool decode_value(KeyNode& target, simdjson::ondemand::value value, std::string& error,
                    std::vector<std::string>* warnings);
  bool decode_array(simdjson::ondemand::array elements, KeyNode& node, std::string& error,
                    std::vector<std::string>* warnings);
  bool apply_tests(KeyNode& node, simdjson::ondemand::value value, simdjson::ondemand::json_type type,
                   std::string& error, std::vector<std::string>* warnings);
  bool check_missing(const KeyNode& node, const std::string& prefix, std::string& error) const;

  const engine::AtomTable& atoms_;
  DecoderOptions options_;
  KeyNode root_;
  std::vector<int> presence_tests_;
  std::vector<uint8_t> current_, next_;
  std::vector<uint32_t> bound_, next_bound_;  // sized only when some test binds
  BoundValues bound_ids_;
  std::vector<double> margin_, next_margin_;
  double time_ = 0, next_time_ = 0;
  bool saw_time_ = false;
  double time_sec_ = 0, time_nsec_ = 0;  // parts of a Time object
  bool saw_sec_ = false;
  bool malformed_ = false;
  uint32_t generation_ = 0;
};

}  // namespace rvc::io
