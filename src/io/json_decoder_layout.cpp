// The JSON decoder's layout fast path (see io/json_layout.hpp): learning a
// line's layout with simdjson, matching later lines against it, and decoding
// a matched line's values with the same rules as JsonDecoder::decode().
#include <algorithm>
#include <cmath>
#include <cstring>

#include "io/json_decoder.hpp"
#include "spec/exact_time.hpp"
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
  if (node && node->each) return false;  // an array quantifier's array: its length varies (decode() folds it)
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
      // A time slot no test reads is read from its text (exactly, to the nanosecond): no double.
      walk.convert.push_back(target != nullptr && !(target->time_part == 1 && target->tests.empty()));
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
  LearnedLayout learned{JsonLayout(text, walk.values, walk.convert), {}, walk.time_slot, ++uses_};
  for (size_t i = 0; i < walk.targets.size(); ++i) {
    KeyNode* t = walk.targets[i];
    if (!t) continue;
    const bool fast = !options_.robustness && !t->time_part;
    const auto how = t->time_part ? SlotUse::Time
                     : fast && t->kind == Kind::Bool   ? SlotUse::Bool
                     : fast && t->kind == Kind::Number ? SlotUse::Number
                                                       : SlotUse::General;
    SlotUse use{how, static_cast<uint32_t>(i), t, {}};
    if (how == SlotUse::Bool && t->bool_tests.size() == 1) use.how = SlotUse::OneBool, use.test = t->bool_tests[0];
    learned.uses.push_back(use);
  }
  if (slot_values_.size() < walk.targets.size()) slot_values_.resize(walk.targets.size());
  if (layouts_.size() < kMaxLayouts) {
    layouts_.push_back(std::move(learned));
  } else {
    layouts_[matched_].last_used = ++uses_;  // the layout in use stays
    auto oldest = std::min_element(layouts_.begin(), layouts_.end(), [](const LearnedLayout& a, const LearnedLayout& b) {
      return a.last_used < b.last_used;
    });
    *oldest = std::move(learned);
  }
}

const char* JsonDecoder::match_line(const char* p, const char* end) {
  if (layouts_.empty()) return nullptr;
  if (resting_) {
    --resting_;
    return nullptr;
  }
  if (++tries_ == kProbe) {  // the last kProbe tries decide whether layouts pay here
    if (hits_ * 2 < tries_) {
      resting_ = rest_span_;
      rest_span_ = std::min(rest_span_ * 2, kMaxRest);
      learn_interval_ = 1;  // learn afresh before the next probe
    } else {
      rest_span_ = kFirstRest;
    }
    tries_ = hits_ = 0;
  }
  while (p != end && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
  // The layout that matched last is the likeliest: try it first.
  for (size_t k = 0, n = layouts_.size(), i = matched_; k < n; ++k, i = i + 1 == n ? 0 : i + 1) {
    LearnedLayout& l = layouts_[i];
    const char* stop = l.layout.match(p, end, slot_values_.data());
    if (!stop) continue;
    while (stop != end && (*stop == ' ' || *stop == '\t' || *stop == '\r')) ++stop;
    if (stop != end && *stop != '\n') continue;  // more text on the line
    // A time that is not a number: decode() words that error.
    if (l.time_slot >= 0 && slot_values_[l.time_slot].kind != ValueKind::Number) return nullptr;
    if (i != matched_) {
      matched_ = i;
      l.last_used = ++uses_;
    }
    ++hits_;
    learn_interval_ = 1;
    return stop;
  }
  return nullptr;
}

bool JsonDecoder::match(std::string_view text) {
  const char* end = text.data() + text.size();
  return match_line(text.data(), end) == end;
}

bool JsonDecoder::decode_matched(std::string& error, std::vector<std::string>* warnings) {
  begin_message();
  const LearnedLayout& l = layouts_[matched_];
  const FieldValue* values = slot_values_.data();
  // As decode_value() reads a scalar: the fast paths when the value has the
  // type the field's tests expect, the general path otherwise.
  for (const SlotUse& use : l.uses) {
    const FieldValue& v = values[use.slot];
    KeyNode& target = *use.target;
    switch (use.how) {
      case SlotUse::OneBool:
        if (v.kind != ValueKind::Bool) break;
        next_[use.test.id] = v.b ? use.test.if_true : use.test.if_false;
        continue;
      case SlotUse::Bool:
        if (v.kind != ValueKind::Bool) break;
        bool_tests(target, v.b);
        continue;
      case SlotUse::Number:
        if (v.kind != ValueKind::Number) break;
        if (std::fabs(v.d) >= spec::kTwo53) number_tests_exact(target, v);  // (as fast_path)
        else number_tests(target, v.d);
        continue;
      case SlotUse::Time:  // a number (match() made sure)
        // Exactly from its text (the scanner keeps it in v.s).
        if (!read_time_text(v.s, options_.time_field, next_time_ns_, error)) return false;
        saw_time_ = true;
        if (target.tests.empty()) continue;
        break;
      case SlotUse::General: break;
    }
    if (!apply_value(target, v, error, warnings)) return false;
  }
  time_ns_ = next_time_ns_;  // a layout of a dense stream always has its time slot
  return true;
}

}  // namespace rvc::io
