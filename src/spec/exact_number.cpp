#include "spec/exact_number.hpp"

#include <charconv>
#include <string>

namespace rvc::spec {

bool integer_literal(std::string_view text, double& d, ExactInt& exact) {
  if (text.empty()) return false;
  const bool negative = text[0] == '-';
  const size_t digits_at = text[0] == '-' || text[0] == '+' ? 1 : 0;
  if (digits_at == text.size()) return false;
  for (size_t i = digits_at; i < text.size(); ++i)
    if (text[i] < '0' || text[i] > '9') return false;
  const char* first = text.data() + digits_at;
  const char* last = text.data() + text.size();
  uint64_t magnitude = 0;
  auto [stop, ec] = std::from_chars(first, last, magnitude);
  if (ec != std::errc() || stop != last) return false;  // beyond 2^64 - 1
  if (negative) {
    if (magnitude > uint64_t{1} << 63) return false;  // below -2^63
    // -magnitude in two's complement, without the overflow of negating INT64_MIN.
    const auto v = static_cast<int64_t>(~magnitude + 1);
    d = magnitude == 0 ? -0.0 : static_cast<double>(v);
    exact = exact_of(v);
  } else {
    d = static_cast<double>(magnitude);  // correctly rounded, as reading the text as a double would
    exact = exact_of(magnitude);
  }
  return true;
}

void append_exact(std::string& out, const ExactInt& x) {
  char buf[24];
  auto [p, ec] = x.kind == ExactInt::Unsigned ? std::to_chars(buf, buf + sizeof buf, x.bits)
                                              : std::to_chars(buf, buf + sizeof buf, static_cast<int64_t>(x.bits));
  out.append(buf, p);
}

}  // namespace rvc::spec
