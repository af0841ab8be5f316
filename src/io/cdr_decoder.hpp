// Decodes one typed (CDR) sample straight into the values of the field tests
// of a Checker's atom table: the counterpart of JsonDecoder for `--type`,
// with no JSON in between.
//
// The message type is known before the first sample, so the fields the tests
// read are found once: the decoder walks a plan of the type in wire order,
// evaluates the tests of each tested field as it passes it, and only checks
// the rest (bool bytes, string NULs/UTF-8/bounds, counts; fixed-size numbers
// are stepped over). A bad sample is refused whatever the properties read,
// with the same words as `rvc echo` and cdr_to_json, since both read through
// CdrCursor.
//
// Dense time: the time field may be a path to a number ("t", "data.time") or
// to a builtin_interfaces/Time-like message ("stamp", "header.stamp": int32
// sec + uint32 nanosec, read as sec + nanosec * 1e-9).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "engine/atom_table.hpp"
#include "io/cdr_codec.hpp"
#include "io/field_tests.hpp"
#include "io/json_decoder.hpp"
#include "io/threshold_index.hpp"
#include "msg/msg_types.hpp"

namespace rvc::io {

class CdrCursor;

class CdrDecoder {
 public:
  // Throws msg::MsgError for a dense-time field the type lacks or that is
  // neither a number nor a Time message. (Tests on fields the type lacks
  // were refused before, by runtime::bind_message_type.)
  CdrDecoder(const engine::AtomTable& atoms, const msg::MessageType& type, const DecoderOptions& options);
  ~CdrDecoder();

  // Decodes into a staging copy; false with `error` if the sample must be
  // refused (`malformed()` then tells a bad sample from a strict-mode
  // problem). Warnings about tests that kept their previous value are
  // appended to `warnings`.
  bool decode(std::string_view sample, std::string& error, std::vector<std::string>* warnings = nullptr);
  bool malformed() const { return malformed_; }
  void commit() {
    current_.swap(next_);
    bound_.swap(next_bound_);
    if (options_.robustness) margin_.swap(next_margin_);
  }

  const uint8_t* values() const { return current_.data(); }
  // With DecoderOptions::robustness: each test's robustness (io::test_margin,
  // as JsonDecoder::margins); -inf before the first sample.
  const double* margins() const { return margin_.data(); }
  // Data references: per atom, the id of the value bound last (as JsonDecoder::bound).
  const uint32_t* bound() const { return bound_.empty() ? nullptr : bound_.data(); }
  // The values data references bound so far (--explain names them).
  const BoundValues& bound_values() const { return bound_ids_; }
  // Dense time: the sample's time exactly, in nanoseconds (a Time's sec and
  // nanosec are integers; a number field is seconds, read from its shortest
  // text: spec/exact_time.hpp), and as double seconds.
  int64_t time_ns() const { return time_ns_; }
  double time() const { return static_cast<double>(time_ns_) / 1e9; }

  // "time" -> the field dense time reads in a message of this type when the
  // user kept the default: "time" if the type has it, else "header.stamp",
  // else "stamp" (every Table-3 message), else "time" (refused later).
  static std::string default_time_field(const msg::MessageType& type, const std::string& requested);

 private:
  enum class TimeRole : uint8_t { None, Number, Sec, Nanosec };
  struct Plan;
  struct FieldPlan {
    const std::string* name = nullptr;  // the field's name (null: an array element)
    msg::FieldType type;                // an element's: the array's type without the array
    std::vector<int> tests;             // atom ids testing this field
    std::unique_ptr<Plan> below;        // a nested message with tested (or time) fields inside
    std::vector<std::unique_ptr<FieldPlan>> elements;  // tested elements by index ({ranges[0]}), else null
    // Array quantifiers (issue 29): the plan every element is read with
    // ("[*]"), and the quantified tests below it, folded over the elements.
    std::unique_ptr<FieldPlan> each;
    std::vector<int> quant_ids;
    TimeRole time = TimeRole::None;
    // Comparisons with many constants, evaluated together for a number
    // (DecoderOptions::threshold_index); rest: the other tests.
    ThresholdIndex thresholds;
    std::vector<int> rest;
  };
  struct Plan {
    const msg::MessageType* type = nullptr;
    std::vector<FieldPlan> fields;  // one per field of the type, in wire order
  };

  FieldPlan& plan_path(const std::vector<std::string>& path, int quant_id = -1);
  bool finish_quantifiers(const FieldPlan& f, uint32_t elements);
  void plan_time(const std::string& time_field);
  bool message(CdrCursor& in, const Plan& plan);
  bool tested_field(CdrCursor& in, const FieldPlan& f);
  bool indexed_array(CdrCursor& in, const FieldPlan& f);
  bool planned_value(CdrCursor& in, const FieldPlan& f);
  static std::unique_ptr<Plan> plan_of(const msg::MessageType& type);
  bool apply(const FieldPlan& f, const FieldValue& value);
  void index_thresholds(Plan& plan);
  void index_thresholds(FieldPlan& f);
  static bool skip(CdrCursor& in, const msg::FieldType& t);
  static bool skip_element(CdrCursor& in, const msg::FieldType& t);
  static bool skip_message(CdrCursor& in, const msg::MessageType& type);

  const engine::AtomTable& atoms_;
  DecoderOptions options_;
  Plan root_;
  std::vector<int> presence_tests_;
  std::vector<uint8_t> current_, next_;
  std::vector<uint32_t> bound_, next_bound_;  // sized only when some test binds
  std::vector<double> margin_, next_margin_;  // sized only with DecoderOptions::robustness
  BoundValues bound_ids_;
  int64_t time_ns_ = 0;
  double next_time_ = 0;  // a number field's seconds
  bool time_is_number_ = false;
  double sec_ = 0, nanosec_ = 0;
  bool malformed_ = false;
  bool refused_ = false;  // a strict-mode problem, not a bad sample
  std::vector<QuantFold> folds_;  // per atom, sized when some test is an array quantifier
  uint32_t element_index_ = 0;    // the element being read with a "[*]" plan
  std::string* error_ = nullptr;               // of the decode in progress
  std::vector<std::string>* warnings_ = nullptr;
};

}  // namespace rvc::io
