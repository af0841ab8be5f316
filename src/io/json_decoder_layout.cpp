// The JSON decoder's layout fast path (see io/json_layout.hpp): learning a
// line's layout with simdjson, matching later lines against it, and decoding
// a matched line's values with the same rules as JsonDecoder::decode().
#include <algorithm>
#include <cstring>

#include "io/json_decoder.hpp"
#include "io/raw_key.hpp"

namespace rvc::io {

using simdjson::ondemand::json_type;

namespace {

// A stream rarely has more shapes than this (optional fields present or not);
// a line matches one of them or goes to simdjson.
constexpr size_t kMaxLayouts = 4;
// Learning attempts back off to one in this many simdjson-read lines while
// learned layouts go unused (a stream whose every line looks different).
constexpr uint32_t kMaxLearnInterval = 1024;

bool json_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

}  // namespace

struct JsonDecoder::LayoutWalk {
  const char* base = nullptr;  // the learned text's first byte
  std::vector<JsonLayout::Range> values;
  std::vector<KeyNode*> targets;
  std::vector<bool> convert;
  int time_slot = -1;
};

// Walks one accepted message as decode_object() would read it, recording
// where each scalar lies and which field it feeds. Returns false if the
// message has something a layout does not cover: an escaped key, a tested
// field holding an object or array (presence of an object, indexed arrays),
// a Time object, as decode_value() handles them.
bool JsonDecoder::learn_object(simdjson::ondemand::object object, KeyNode* node, LayoutWalk& walk, int depth) {
  for (auto field_result : object) {
    simdjson::ondemand::field field;
    if (std::move(field_result).get(field)) return false;
    const char* k = reinterpret_cast<const char*>(field.key().raw());
    const size_t n = raw_key_length(k);
    if (std::memchr(k, '\\', n)) return false;
    // decode_object() finds a field among the children not named as array
    // elements; a key without escapes matches a name as written.
    KeyNode* child_node = nullptr;
    if (node) {
      const std::string_view key(k, n);
      for (KeyNode& c : node->children)
        if (!c.is_index && c.raw_comparable && c.name == key) {
          child_node = &c;
          break;
        }
    }
    if (!learn_value(field.value(), child_node, walk, depth + 1)) return false;
  }
  return true;
}

bool JsonDecoder::learn_value(simdjson::ondemand::value value, KeyNode* node, LayoutWalk& walk, int depth) {
  if (depth > 64) return false;  // deep documents: not worth a layout
  json_type type;
  if (value.type().get(type)) return false;
  if (node && node->time_part >= 2) return false;  // a Time object's parts
  switch (type) {
    case json_type::object: {
      if (node && (!node->tests.empty() || node->time_part)) return false;
      simdjson::ondemand::object inner;
      if (value.get_object().get(inner)) return false;
      return learn_object(inner, node, walk, depth);
    }
    case json_type::array: {
      if (node && (!node->tests.empty() || !node->by_index.empty() || node->time_part)) return false;
      simdjson::ondemand::array elements;
      if (value.get_array().get(elements)) return false;
      for (auto element : elements) {  // nothing tests them: each only checked
        simdjson::ondemand::value v;
        if (std::move(element).get(v) || !learn_value(v, nullptr, walk, depth + 1)) return false;
      }
      return true;
    }
    default: {
      std::string_view token = value.raw_json_token();  // up to the next structural byte: drop the spaces before it
      while (!token.empty() && json_space(token.back())) token.remove_suffix(1);
      KeyNode* target = node && (!node->tests.empty() || node->time_part == 1) ? node : nullptr;
      if (target && target->time_part == 1) {
        if (type != json_type::number) return false;
        walk.time_slot = static_cast<int>(walk.values.size());
      }
      const size_t begin = static_cast<size_t>(token.data() - walk.base);
      walk.values.push_back({begin, begin + token.size()});
      walk.targets.push_back(target);
      walk.convert.push_back(target != nullptr);
      return true;
    }
  }
}

void JsonDecoder::learn(std::string_view line) {
  slow_since_learn_ = 0;
  learn_interval_ = std::min(learn_interval_ * 2, kMaxLearnInterval);  // reset when a layout is used
  const std::string_view text = layout_text(line);
  learn_scratch_.assign(text.data(), text.size());
  learn_scratch_.append(simdjson::SIMDJSON_PADDING, '\0');
  simdjson::ondemand::document doc;
  simdjson::ondemand::object object;
  if (learn_parser_.iterate(learn_scratch_.data(), text.size(), learn_scratch_.size()).get(doc) ||
      doc.get_object().get(object))
    return;
  LayoutWalk walk;
  walk.base = learn_scratch_.data();
  if (!learn_object(object, &root_, walk, 0)) return;
  if (options_.need_time && walk.time_slot < 0) return;
  LearnedLayout learned{JsonLayout(text, walk.values, walk.convert), std::move(walk.targets), walk.time_slot, ++uses_};
  if (slot_values_.size() < learned.targets.size()) slot_values_.resize(learned.targets.size());
  if (layouts_.size() < kMaxLayouts) {
    layouts_.push_back(std::move(learned));
  } else {
    auto oldest = std::min_element(layouts_.begin(), layouts_.end(), [](const LearnedLayout& a, const LearnedLayout& b) {
      return a.last_used < b.last_used;
    });
    *oldest = std::move(learned);
  }
}

bool JsonDecoder::match(std::string_view line) {
  if (layouts_.empty()) return false;
  const std::string_view text = layout_text(line);
  // The layout that matched last is the likeliest: try it first.
  for (size_t k = 0; k < layouts_.size(); ++k) {
    const size_t i = (matched_ + k) % layouts_.size();
    LearnedLayout& l = layouts_[i];
    if (!l.layout.match(text, slot_values_.data())) continue;
    // A time that is not a number: decode() words that error.
    if (l.time_slot >= 0 && slot_values_[l.time_slot].kind != ValueKind::Number) return false;
    matched_ = i;
    l.last_used = ++uses_;
    learn_interval_ = 1;
    return true;
  }
  return false;
}

// One matched value of a tested field (or the time), as decode_value() reads a scalar.
inline bool JsonDecoder::apply_matched(KeyNode& target, const FieldValue& v, std::string& error,
                                       std::vector<std::string>* warnings) {
  if (target.time_part == 1) {
    saw_time_ = true;
    next_time_ = v.d;
  }
  if (target.tests.empty()) return true;
  if (!options_.robustness) {
    if (target.kind == Kind::Bool && v.kind == ValueKind::Bool) {
      bool_tests(target, v.b);
      return true;
    }
    if (target.kind == Kind::Number && v.kind == ValueKind::Number) {
      number_tests(target, v.d);
      return true;
    }
  }
  return apply_value(target, v, error, warnings);
}

bool JsonDecoder::decode_matched(std::string& error, std::vector<std::string>* warnings) {
  begin_message();
  const LearnedLayout& l = layouts_[matched_];
  const FieldValue* v = slot_values_.data();
  for (KeyNode* target : l.targets) {
    if (target && !apply_matched(*target, *v, error, warnings)) return false;
    ++v;
  }
  time_ = next_time_;  // a layout of a dense stream always has its time slot
  return true;
}

}  // namespace rvc::io
