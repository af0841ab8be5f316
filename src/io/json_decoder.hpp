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
#include "io/field_tests.hpp"
#include "io/json_layout.hpp"
#include "io/threshold_index.hpp"

namespace rvc::io {

struct DecoderOptions {
  bool need_time = false;          // dense time: every message must carry a time
  std::string time_field = "time";
  bool strict = false;
  bool robustness = false;  // also each test's margin (--robustness; general path only)
  // Read lines laid out like earlier ones by position (JsonLayout) instead of
  // parsing them. Off only to compare the two paths (tests, fuzzing).
  bool layouts = true;
  // Evaluate a field's comparisons with many constants together (io/threshold_index.hpp)
  // and write only the atoms that change. Off only to compare with the plain per-test loop.
  bool threshold_index = true;
};

class JsonDecoder {
 public:
  JsonDecoder(const engine::AtomTable& atoms, DecoderOptions options);

  // Decodes into a staging copy; returns false (with `error`) if the message
  // must be rejected, leaving the committed values untouched. Warnings about
  // fields that kept their previous value are appended to `warnings`.
  bool decode(simdjson::ondemand::object object, std::string& error, std::vector<std::string>* warnings = nullptr);
  // The layout fast path (JsonLayout). match() says whether `text` (one
  // message) has a layout learned from an earlier message, reading its
  // values; decode_matched() then decodes it as decode() would have. A
  // message that does not match goes to decode() (and simdjson) as usual.
  bool match(std::string_view text);
  // The same for the line starting at p: its end (its newline, or `end`), or null.
  const char* match_line(const char* p, const char* end);
  bool decode_matched(std::string& error, std::vector<std::string>* warnings = nullptr);
  // After a message read by decode() was accepted: whether its layout should
  // be learned now (attempts back off while learned layouts go unused), and
  // learning it from the message's text.
  bool learns_layouts() const { return options_.layouts && !options_.strict; }
  bool wants_layout() {
    return learns_layouts() && resting_ < kLearnBeforeProbe && ++slow_since_learn_ >= learn_interval_;
  }
  void learn(std::string_view line);

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
  // Dense time: the message's time, exactly, in nanoseconds (read from the
  // number's decimal text, or a Time's sec and nanosec; spec/exact_time.hpp),
  // and as double seconds.
  int64_t time_ns() const { return time_ns_; }
  double time() const { return static_cast<double>(time_ns_) / 1e9; }

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
    // A Number field's comparisons with many constants, evaluated together;
    // number_rest: its other tests (all of them without an index).
    ThresholdIndex thresholds;
    std::vector<int> number_rest;
    uint32_t seen = 0;               // message generation when last present (strict mode)
    bool is_index = false;           // an array element: name "[N]"
    std::vector<KeyNode*> by_index;  // the element children by index (null: not tested)
    // Array quantifiers (issue 29): the child "[*]" every element is decoded
    // into, and the quantified tests below it, folded over the elements.
    KeyNode* each = nullptr;
    std::vector<int> quant_ids;
  };
  // A layout with the fields its slots feed (the other slots are only checked).
  struct SlotUse {
    // Bool, Number: Kind's fast paths; OneBool: a field with a single Boolean test, `test`.
    enum How : uint8_t { OneBool, Bool, Number, General, Time } how;
    uint32_t slot;
    KeyNode* target;
    BoolTest test;
  };
  struct LearnedLayout {
    JsonLayout layout;
    std::vector<SlotUse> uses;
    int time_slot = -1;  // the slot holding the time (dense), which must be a number
    uint64_t last_used = 0;
  };
  struct LayoutWalk;
  bool learn_object(simdjson::ondemand::object object, KeyNode* node, LayoutWalk& walk, int depth);
  bool learn_value(simdjson::ondemand::value value, KeyNode* node, LayoutWalk& walk, int depth);
  void begin_message();
  void bool_tests(const KeyNode& node, bool b);
  void number_tests(const KeyNode& node, double d);
  [[gnu::noinline]] void number_tests_exact(const KeyNode& node, const FieldValue& v);
  // From 2^53 up (rare: out of the hot path): the exact value read from the number's text.
  [[gnu::cold, gnu::noinline]] void number_tests_from_text(const KeyNode& node, std::string_view token, double d);
  bool apply_value(KeyNode& node, const FieldValue& value, std::string& error, std::vector<std::string>* warnings);
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
  bool finish_quantifiers(const KeyNode& node, uint32_t elements, std::string& error,
                          std::vector<std::string>* warnings);
  bool not_an_array(const KeyNode& node, ValueKind kind, std::string& error, std::vector<std::string>* warnings);

  const engine::AtomTable& atoms_;
  DecoderOptions options_;
  KeyNode root_;
  std::vector<int> presence_tests_;
  std::vector<uint8_t> current_, next_;
  std::vector<uint32_t> bound_, next_bound_;  // sized only when some test binds
  BoundValues bound_ids_;
  std::vector<double> margin_, next_margin_;
  std::vector<QuantFold> folds_;  // per atom, sized when some test is an array quantifier
  uint32_t element_index_ = 0;    // the element being decoded into a "[*]" node
  int64_t time_ns_ = 0, next_time_ns_ = 0;
  bool saw_time_ = false;
  int64_t time_sec_ns_ = 0;  // parts of a Time object: sec (as ns), nanosec
  double time_nsec_ = 0;
  // The time number's text as nanoseconds, or false with `error` set.
  bool read_time_text(std::string_view text, const std::string& name, int64_t& ns, std::string& error) const;
  bool combine_time(std::string& error);
  bool saw_sec_ = false;
  bool malformed_ = false;
  uint32_t generation_ = 0;
  std::vector<LearnedLayout> layouts_;  // at most kMaxLayouts, replaced least recently used first
  size_t matched_ = 0;                  // the layout the last match() found
  uint64_t uses_ = 0;
  std::vector<FieldValue> slot_values_;  // of the matched line
  uint32_t slow_since_learn_ = 0, learn_interval_ = 1;
  // When layouts rarely match (a stream whose messages keep changing shape),
  // trying them costs more than it saves: after a probe of kProbe tries with
  // fewer than half matched, match_line() declines the next resting_ calls
  // without trying, a span that doubles while probes keep failing. Layouts
  // are learned again just before the next probe.
  static constexpr uint32_t kProbe = 64, kFirstRest = 256, kMaxRest = 1 << 16, kLearnBeforeProbe = 16;
  uint32_t tries_ = 0, hits_ = 0, resting_ = 0, rest_span_ = kFirstRest;
  simdjson::ondemand::parser learn_parser_;
  std::string learn_scratch_;
};

// A Boolean-only field's tests, given its value. (Inline: both the simdjson
// path and the layout path run these per field.)
inline void JsonDecoder::bool_tests(const KeyNode& node, bool b) {
  uint8_t* out = next_.data();
  for (const BoolTest *t = node.bool_tests.data(), *end = t + node.bool_tests.size(); t != end; ++t)
    out[t->id] = b ? t->if_true : t->if_false;
}

// A number-only field's tests, given its value. Below 2^53 the double
// comparisons are exact, whatever the literal (an integer literal beyond 2^53
// is on the same side of d as its rounded double); from 2^53 up (nanosecond
// stamps, 64-bit ids) number_tests_exact compares the exact value.
inline void JsonDecoder::number_tests(const KeyNode& node, double d) {
  if (!node.thresholds.empty()) node.thresholds.apply(d, next_.data());
  for (int id : node.number_rest) {
    const spec::FieldTest& t = atoms_.tests()[id];
    const double x = t.value.number;
    uint8_t r = 1;
    using Op = spec::FieldTest::Op;
    switch (t.op) {
      case Op::Eq: r = d == x; break;
      case Op::Ne: r = d != x; break;
      case Op::Lt: r = d < x; break;
      case Op::Le: r = d <= x; break;
      case Op::Gt: r = d > x; break;
      case Op::Ge: r = d >= x; break;
      default: break;  // Present
    }
    next_[id] = r;
  }
}

}  // namespace rvc::io
