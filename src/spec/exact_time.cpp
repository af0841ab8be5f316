#include "spec/exact_time.hpp"

#include <charconv>
#include <cmath>
#include <limits>

namespace rvc::spec {
namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }

}  // namespace

// The usual stamp, [-+]digits[.digits] with at most 9 decimals and no exponent
// ("1746721937.599626818"): integer arithmetic, no allocation. False (ns
// untouched) for anything else, which the general reader below decides.
static bool parse_plain_seconds(std::string_view text, int64_t& ns) {
  const char* p = text.data();
  const char* const end = p + text.size();
  const bool negative = p != end && *p == '-';
  if (p != end && (*p == '-' || *p == '+')) ++p;
  // Unsigned arithmetic: a run too long to fit wraps harmlessly, and is refused by its length.
  const char* const int_begin = p;
  uint64_t whole = 0;
  for (; p != end && static_cast<unsigned>(*p - '0') < 10; ++p) whole = whole * 10 + static_cast<unsigned>(*p - '0');
  const auto int_digits = p - int_begin;
  if (int_digits == 0 || int_digits > 10) return false;
  uint64_t frac = 0;
  long decimals = 0;
  if (p != end && *p == '.') {
    const char* const frac_begin = ++p;
    for (; p != end && static_cast<unsigned>(*p - '0') < 10; ++p) frac = frac * 10 + static_cast<unsigned>(*p - '0');
    decimals = p - frac_begin;
    if (decimals == 0 || decimals > 9) return false;  // none: malformed; past the nanosecond: rounding
  }
  if (p != end || whole > 9223372036u) return false;  // an exponent, not a number, or (near) past int64 ns
  static constexpr uint64_t kScale[] = {1000000000, 100000000, 10000000, 1000000, 100000,
                                        10000,      1000,      100,      10,      1};
  const uint64_t v = whole * 1000000000u + frac * kScale[decimals];  // < 2^64: 9223372036999999999 at most
  if (v > static_cast<uint64_t>(std::numeric_limits<int64_t>::max())) return false;
  ns = negative ? -static_cast<int64_t>(v) : static_cast<int64_t>(v);
  return true;
}

SecondsStatus parse_seconds(std::string_view text, int64_t& ns) {
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r' || text.back() == '\n'))
    text.remove_suffix(1);
  if (parse_plain_seconds(text, ns)) return SecondsStatus::Ok;
  size_t i = 0;
  bool negative = false;
  if (i < text.size() && (text[i] == '-' || text[i] == '+')) negative = text[i++] == '-';
  // The significant digits as one decimal string (leading zeros dropped) and
  // the power of ten that scales it: value = digits * 10^scale.
  std::string digits;
  int64_t scale = 0;
  size_t int_digits = 0, frac_digits = 0;
  for (; i < text.size() && is_digit(text[i]); ++i, ++int_digits)
    if (!(digits.empty() && text[i] == '0')) digits += text[i];
  if (i < text.size() && text[i] == '.') {
    ++i;
    for (; i < text.size() && is_digit(text[i]); ++i, ++frac_digits) {
      if (!(digits.empty() && text[i] == '0')) digits += text[i];
      --scale;
    }
    if (frac_digits == 0) return SecondsStatus::Malformed;
  }
  if (int_digits + frac_digits == 0) return SecondsStatus::Malformed;
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    bool eneg = false;
    if (i < text.size() && (text[i] == '-' || text[i] == '+')) eneg = text[i++] == '-';
    if (i == text.size() || !is_digit(text[i])) return SecondsStatus::Malformed;
    int64_t e = 0;
    for (; i < text.size() && is_digit(text[i]); ++i)
      if (e < 100000) e = e * 10 + (text[i] - '0');  // saturates: 1e99999 is out of range anyway
    scale += eneg ? -e : e;
  }
  if (i != text.size()) return SecondsStatus::Malformed;
  if (digits.empty()) {
    ns = 0;
    return SecondsStatus::Ok;
  }
  // In nanoseconds: digits * 10^(scale + 9). The integer part is the digits
  // up to that power; the rest is rounded (to nearest, ties to even).
  const int64_t shift = scale + 9;
  const int64_t n = static_cast<int64_t>(digits.size());
  if (n + shift > 19) return SecondsStatus::OutOfRange;  // >= 10^19 ns > int64
  const int64_t keep = n + shift;  // how many leading digits form the integer
  unsigned __int128 v = 0;
  for (int64_t k = 0; k < keep && k < n; ++k) v = v * 10 + static_cast<unsigned>(digits[static_cast<size_t>(k)] - '0');
  for (int64_t k = n; k < keep; ++k) v *= 10;
  if (keep < n) {
    // The first dropped digit decides, the rest break a tie.
    const int first = keep >= 0 ? digits[static_cast<size_t>(keep)] - '0' : 0;
    bool rest = false;
    for (int64_t k = keep >= 0 ? keep + 1 : 0; k < n; ++k) rest = rest || digits[static_cast<size_t>(k)] != '0';
    if (keep < 0) rest = true;  // every digit lies below the first dropped place: less than half
    const bool up = keep >= 0 && (first > 5 || (first == 5 && (rest || (v & 1))));
    if (up) ++v;
  }
  const unsigned __int128 limit = negative ? static_cast<unsigned __int128>(std::numeric_limits<int64_t>::max()) + 1
                                           : static_cast<unsigned __int128>(std::numeric_limits<int64_t>::max());
  if (v > limit) return SecondsStatus::OutOfRange;
  ns = negative ? static_cast<int64_t>(-static_cast<__int128>(v)) : static_cast<int64_t>(v);
  return SecondsStatus::Ok;
}

bool time_to_ns(int64_t sec, int64_t nanosec, int64_t& ns) {
  int64_t s;
  if (__builtin_mul_overflow(sec, kNsPerSecond, &s)) return false;
  return !__builtin_add_overflow(s, nanosec, &ns);
}

void append_seconds(std::string& out, int64_t ns) {
  unsigned __int128 v = ns < 0 ? static_cast<unsigned __int128>(-static_cast<__int128>(ns))
                               : static_cast<unsigned __int128>(ns);
  if (ns < 0) out += '-';
  const auto whole = static_cast<uint64_t>(v / kNsPerSecond);
  auto frac = static_cast<uint32_t>(v % kNsPerSecond);
  out += std::to_string(whole);
  if (frac == 0) return;
  char buf[10];
  for (int k = 8; k >= 0; --k, frac /= 10) buf[k] = static_cast<char>('0' + frac % 10);
  int len = 9;
  while (len > 0 && buf[len - 1] == '0') --len;
  out += '.';
  out.append(buf, static_cast<size_t>(len));
}

double seconds_to_ns(double seconds) {
  if (!std::isfinite(seconds)) return seconds * 1e9;  // inf stays inf, NaN NaN
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, seconds);
  int64_t ns = 0;
  if (parse_seconds(std::string_view(buf, static_cast<size_t>(r.ptr - buf)), ns) != SecondsStatus::Ok)
    return seconds < 0 ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
  return static_cast<double>(ns);
}

std::string seconds_text(int64_t ns) {
  std::string s;
  append_seconds(s, ns);
  return s;
}

}  // namespace rvc::spec
