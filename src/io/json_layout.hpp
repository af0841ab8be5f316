// A line layout: what stays the same from one JSON message of a stream to the
// next. Messages of one topic are printed by one serializer, so they repeat
// the same keys, in the same order, with the same spacing; only the scalar
// values change. A layout keeps those bytes (the skeleton) and the places of
// the values between them (the slots), learned from a line simdjson has
// already read.
//
// A later line matches when its bytes equal the skeleton around each slot and
// each slot holds one well-formed JSON scalar (number, string without
// escapes, true, false, null). Such a line is valid JSON with the same keys
// as the learned one, so its values can be read by position, without a parse:
// the token boundaries are fixed by the skeleton, and a scalar's own grammar
// says where it ends. Anything else (another key, a nested value where a
// scalar was, an escape, a number simdjson might read differently) does not
// match, and the caller reads the line with simdjson as usual, which stays
// the reference for every error message.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "io/field_tests.hpp"

namespace rvc::io {

class JsonLayout {
 public:
  // Builds the layout of `text`, whose scalar values lie at `values` (byte
  // ranges, in order, not overlapping). `convert[i]`: slot i's numbers are
  // needed as doubles (else only checked to be well-formed).
  struct Range {
    size_t begin, end;
  };
  JsonLayout(std::string_view text, const std::vector<Range>& values, const std::vector<bool>& convert);

  size_t slots() const { return slots_.size(); }
  // Whether the text at [p, end) starts with a message of this layout: its
  // end if so (out[i] then holds slot i's value, strings pointing into the
  // text), else null. `out` has slots() entries. What follows the message is
  // the caller's to check: a reader finds the end of a line this way, with
  // no separate search for the newline.
  const char* match(const char* p, const char* end, FieldValue* out) const;

 private:
  struct Slot {
    uint32_t before_at, before_len;  // the skeleton bytes before this value
    // The same bytes as one little-endian word and the mask of its bytes,
    // when they fit in 8 (a key and its punctuation, mostly): one compare.
    uint64_t word = 0, mask = 0;
    bool convert;
  };
  std::string skeleton_;
  std::vector<Slot> slots_;
  uint32_t tail_at_ = 0, tail_len_ = 0;  // the bytes after the last value
};

inline bool json_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }

// The text of a line as layouts see it: without the JSON whitespace around
// it (a CR before the newline, indentation), so a CRLF file, and the same
// line read as a file or a payload, give one layout.
inline std::string_view layout_text(std::string_view line) {
  while (!line.empty() && json_space(line.front())) line.remove_prefix(1);
  while (!line.empty() && json_space(line.back())) line.remove_suffix(1);
  return line;
}

}  // namespace rvc::io
