// Reading one XCDR1 sample field by field: the byte order, alignment counted
// from the end of the 4-byte header, bounds, and the checks every reader of a
// sample must make (bool bytes, string NULs and UTF-8, counts the sample can
// hold). Shared by cdr_to_json (CDR -> JSON) and CdrDecoder (CDR -> atom
// values), so both refuse exactly the same samples with the same words.
//
// An error names the path of the field being read ("status.twist.linear.x",
// "points[2].x") and the byte offset counted from the sample's first byte.
// The path is a stack of parts spelled out only for an error: building it as
// a string for every field cost more than decoding the sample.
#pragma once

#include <simdjson.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "io/cdr_codec.hpp"

namespace rvc::io {

// The fewest bytes one element of type t takes on the wire (a string: its
// length; a message: an empty one's uint8).
inline size_t cdr_min_size(const msg::FieldType& t) {
  if (t.prim == msg::Prim::String || t.prim == msg::Prim::WString) return 4;
  if (t.prim == msg::Prim::Message) return 1;
  return msg::prim_size(t.prim);
}

class CdrCursor {
 public:
  static constexpr size_t kHeader = 4;

  CdrCursor(CdrError& error) : error_(error) {}

  // Checks the encapsulation header (plain CDR, either byte order; the
  // options field is ignored) and positions the cursor after it.
  bool open(std::string_view sample);

  template <typename T>
  bool read(T& v) {
    if (!align(sizeof(T))) return false;
    if (size_ - pos_ < sizeof(T)) return fail("truncated sample");
    std::memcpy(&v, data_ + pos_, sizeof(T));
    if (swap_ && sizeof(T) > 1) v = byteswap(v);
    pos_ += sizeof(T);
    return true;
  }
  // Whether n elements of `size` bytes (aligned to `size`) follow.
  bool has(size_t size, size_t n) const {
    const size_t p = (pos_ + size - 1) & ~(size - 1);
    return p <= size_ && n <= (size_ - p) / size;
  }
  // n elements of `size` bytes each, aligned to `size`, not looked at.
  // (Check has() first: a truncated array is reported at its element.)
  bool skip(size_t size, size_t n) {
    if (!align(size)) return false;
    if (n > (size_ - pos_) / size) return fail("truncated sample");
    pos_ += size * n;
    return true;
  }
  bool boolean(bool& b) {
    uint8_t v = 0;
    if (!read(v)) return false;
    if (v > 1) {
      pos_ -= 1;
      return fail("bool holding " + std::to_string(v));
    }
    b = v != 0;
    return true;
  }
  // A sequence's element count; every element takes at least
  // min_element_size bytes, so a count the rest of the sample cannot hold is
  // refused before any element is read.
  bool count(uint32_t& n, size_t min_element_size) {
    if (!read(n)) return false;
    if (min_element_size && n > (size_ - pos_) / min_element_size) {
      pos_ -= 4;
      return fail("sequence length " + std::to_string(n) + " exceeds the sample");
    }
    return true;
  }
  // A bounded sequence: also its bound.
  bool count(uint32_t& n, size_t min_element_size, uint32_t bound) {
    if (!count(n, min_element_size)) return false;
    if (n > bound) {
      pos_ -= 4;
      return fail("sequence of " + std::to_string(n) + " elements over its bound " + std::to_string(bound));
    }
    return true;
  }
  bool string(std::string_view& text, uint32_t bound) {
    uint32_t len = 0;
    if (!read(len)) return false;
    if (len > size_ - pos_) {  // a cut sample: say which string and by how much
      pos_ -= 4;
      return string_too_long(len);
    }
    if (len == 0) {  // some writers send an empty string as length 0, without the NUL
      text = {};
      return true;
    }
    const char* s = reinterpret_cast<const char*>(data_ + pos_);
    if (s[len - 1] != '\0') return fail("string without its terminating NUL");
    text = std::string_view(s, len - 1);
    if (text.find('\0') != std::string_view::npos) return fail("string with a NUL inside");
    if (bound && text.size() > bound)
      return fail("string of " + std::to_string(text.size()) + " bytes over its bound " + std::to_string(bound));
    if (!simdjson::validate_utf8(text.data(), text.size())) return fail("string that is not UTF-8");
    pos_ += len;
    return true;
  }

  // After the last field: only padding (at most 3 bytes, to a 4-byte
  // boundary: writers pad samples) may remain.
  bool finish() {
    const size_t rest = size_ - pos_;
    if (rest > 3) {
      error_ = {std::to_string(rest) + " bytes left over after the last field (a sample of another type?)",
                pos_ + kHeader};
      return false;
    }
    return true;
  }

  void push(const std::string* name) { push_part(name, 0); }
  void push_index(uint32_t index) { push_part(nullptr, index); }
  void pop() { --depth_; }

  bool fail(const std::string& what) {
    const std::string p = path();
    error_ = {what + (p.empty() ? std::string() : " in field " + p), pos_ + kHeader};
    return false;
  }

 private:
  template <typename T>
  static T byteswap(T v) {
    unsigned char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    std::reverse(b, b + sizeof(T));
    std::memcpy(&v, b, sizeof(T));
    return v;
  }
  bool align(size_t n) {
    const size_t p = (pos_ + n - 1) & ~(n - 1);
    if (p > size_) return fail("truncated sample");
    pos_ = p;
    return true;
  }
  struct PathPart {
    const std::string* name;  // null: an array index
    uint32_t index;
  };
  static constexpr size_t kMaxPath = 64;  // deeper parts are not named in errors
  void push_part(const std::string* name, uint32_t index) {
    if (depth_ < kMaxPath) path_[depth_] = {name, index};
    ++depth_;
  }
  std::string path() const;
  bool string_too_long(uint32_t len);

  const unsigned char* data_ = nullptr;
  size_t size_ = 0;
  size_t pos_ = 0;
  bool swap_ = false;
  CdrError& error_;
  PathPart path_[kMaxPath];
  size_t depth_ = 0;
};

}  // namespace rvc::io
