#include "io/json_layout.hpp"

#include <simdjson.h>

#include <charconv>
#include <cstring>

namespace rvc::io {
namespace {

// a[0, n) == b[0, n), for the short runs between values (a key and its
// punctuation): overlapping word loads instead of a call to memcmp. Every
// load stays inside both ranges, so a payload without padding is safe.
inline bool same_bytes(const char* a, const char* b, size_t n) {
  if (n > 16) return std::memcmp(a, b, n) == 0;
  if (n >= 8) {
    uint64_t x0, y0, x1, y1;
    std::memcpy(&x0, a, 8), std::memcpy(&y0, b, 8);
    std::memcpy(&x1, a + n - 8, 8), std::memcpy(&y1, b + n - 8, 8);
    return ((x0 ^ y0) | (x1 ^ y1)) == 0;
  }
  if (n >= 4) {
    uint32_t x0, y0, x1, y1;
    std::memcpy(&x0, a, 4), std::memcpy(&y0, b, 4);
    std::memcpy(&x1, a + n - 4, 4), std::memcpy(&y1, b + n - 4, 4);
    return ((x0 ^ y0) | (x1 ^ y1)) == 0;
  }
  for (size_t i = 0; i < n; ++i)
    if (a[i] != b[i]) return false;
  return true;
}

inline uint32_t word4(const char* p) {
  uint32_t w;
  std::memcpy(&w, p, 4);
  return w;
}

inline bool digit(char c) { return static_cast<unsigned char>(c - '0') < 10; }

// Powers of ten a double holds exactly.
constexpr double kExact10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
                               1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

// One JSON number at p (RFC 8259: -?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?),
// ending before `end` or at the first byte that cannot continue it. Returns
// its end, or nullptr if it is malformed or one whose reading could differ
// from simdjson's (out of a double's range, an exponent of 4+ digits): those
// lines go to simdjson, which decides and words the error.
const char* scan_number(const char* p, const char* end, bool convert, double& out, spec::ExactInt& exact) {
  const char* q = p;
  const bool negative = *q == '-';
  if (negative && ++q == end) return nullptr;
  uint64_t mantissa = 0;
  // A run of digits from q: its end, its digits folded into the mantissa when converting.
  const auto run = [&](const char* q) {
    if (convert)
      for (; q != end && digit(*q); ++q) mantissa = mantissa * 10 + static_cast<unsigned>(*q - '0');
    else
      while (q != end && digit(*q)) ++q;
    return q;
  };
  int digits = 0, fraction = 0;
  if (*q == '0') {
    ++q;
  } else if (digit(*q)) {
    const char* first = q;
    q = run(q);
    digits = static_cast<int>(q - first);
  } else {
    return nullptr;
  }
  if (q != end && *q == '.') {
    if (++q == end || !digit(*q)) return nullptr;
    const char* first = q;
    q = run(q);
    fraction = static_cast<int>(q - first);
    digits += fraction;
  }
  bool exponent = false;
  if (q != end && (*q == 'e' || *q == 'E')) {
    exponent = true;
    if (++q != end && (*q == '+' || *q == '-')) ++q;
    if (q == end || !digit(*q)) return nullptr;
    const char* first = q;
    while (q != end && digit(*q)) ++q;
    if (q - first > 3) return nullptr;
  }
  // Up to 15 significant digits and no exponent: the mantissa and the power
  // of ten are exact doubles, so one division rounds correctly (the usual
  // fast path of decimal-to-binary conversion).
  if (!exponent && digits <= 15) {
    if (convert) {
      const double d = static_cast<double>(mantissa) / kExact10[fraction];
      out = negative ? -d : d;
    }
    return q;
  }
  if (!convert && !exponent && digits - fraction <= 300) return q;  // well inside a double's range
  // An integer of 16 digits or more: exactly, as set_json_number reads it on simdjson's path.
  if (!exponent && fraction == 0 && spec::integer_literal(std::string_view(p, static_cast<size_t>(q - p)), out, exact))
    return q;
  // Otherwise the standard library's correctly rounded conversion; a value
  // out of range (or rounding to zero) is left to simdjson.
  double d = 0;
  auto [stop, ec] = std::from_chars(p, q, d);
  if (ec != std::errc() || stop != q) return nullptr;
  out = d;
  return q;
}

// One JSON scalar at p: returns its end (or nullptr: no match) and its value.
inline const char* scan_scalar(const char* p, const char* end, bool convert, FieldValue& v) {
  if (p == end) return nullptr;
  switch (*p) {
    case 't':
      if (end - p < 4 || word4(p) != word4("true")) return nullptr;
      v.kind = ValueKind::Bool, v.b = true;
      return p + 4;
    case 'f':
      if (end - p < 5 || word4(p + 1) != word4("alse")) return nullptr;
      v.kind = ValueKind::Bool, v.b = false;
      return p + 5;
    case 'n':
      if (end - p < 4 || word4(p) != word4("null")) return nullptr;
      v.kind = ValueKind::Null;
      return p + 4;
    case '"': {
      const char* q = p + 1;
      bool ascii = true;
      for (;; ++q) {
        if (q == end) return nullptr;
        const auto c = static_cast<unsigned char>(*q);
        if (c == '"') break;
        if (c == '\\' || c < 0x20) return nullptr;  // escapes and control bytes: simdjson's to judge
        ascii = ascii && c < 0x80;
      }
      if (!ascii && !simdjson::validate_utf8(p + 1, static_cast<size_t>(q - p - 1))) return nullptr;
      v.kind = ValueKind::String;
      v.s = std::string_view(p + 1, static_cast<size_t>(q - p - 1));
      return q + 1;
    }
    default:
      v.kind = ValueKind::Number;
      v.exact.kind = spec::ExactInt::None;  // (its bits mean nothing then)
      const char* stop = scan_number(p, end, convert, v.d, v.exact);
      // The number's text: dense time reads a time slot from it exactly.
      if (stop) v.s = std::string_view(p, static_cast<size_t>(stop - p));
      return stop;
  }
}

}  // namespace

JsonLayout::JsonLayout(std::string_view text, const std::vector<Range>& values, const std::vector<bool>& convert) {
  size_t at = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    const Range& r = values[i];
    Slot slot{static_cast<uint32_t>(skeleton_.size()), static_cast<uint32_t>(r.begin - at), 0, 0, convert[i]};
    if (slot.before_len <= 8) {
      std::memcpy(&slot.word, text.data() + at, slot.before_len);
      slot.mask = slot.before_len == 8 ? ~uint64_t{0} : (uint64_t{1} << (8 * slot.before_len)) - 1;
    }
    slots_.push_back(slot);
    skeleton_.append(text.substr(at, r.begin - at));
    at = r.end;
  }
  tail_at_ = static_cast<uint32_t>(skeleton_.size());
  tail_len_ = static_cast<uint32_t>(text.size() - at);
  skeleton_.append(text.substr(at));
}

const char* JsonLayout::match(const char* p, const char* const end, FieldValue* out) const {
  const char* skeleton = skeleton_.data();
  for (const Slot& slot : slots_) {
    if (slot.mask && end - p >= 8) {  // the usual case: a short run, and room for a whole word
      uint64_t w;
      std::memcpy(&w, p, 8);
      if ((w & slot.mask) != slot.word) return nullptr;
    } else if (static_cast<size_t>(end - p) < slot.before_len ||
               !same_bytes(p, skeleton + slot.before_at, slot.before_len)) {
      return nullptr;
    }
    p += slot.before_len;
    if (!(p = scan_scalar(p, end, slot.convert, *out++))) return nullptr;
  }
  if (static_cast<size_t>(end - p) < tail_len_ || !same_bytes(p, skeleton + tail_at_, tail_len_)) return nullptr;
  return p + tail_len_;
}

}  // namespace rvc::io
